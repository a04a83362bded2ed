// Line-by-line validation of OBJ text before tinyobj sees it. tinyobj is lenient where a renderer
// must not be: "v 1.0 2.0" gets z = 0, "nan" parses as 0, a face index past the end only warns
// and a negative one that resolves below 0 is used unchecked. Catching these here lets every
// message name the file and line.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt::detail {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail_at(const std::string& display, int line, const std::string& what) {
    throw Error(display + ":" + std::to_string(line) + ": " + what);
}

// Reads the next line from `text` at `*pos`, ending at the line breaks tinyobj recognises
// ("\n", "\r\n" and a lone "\r") so that line numbers agree with tinyobj's own messages.
bool next_line(const std::string& text, size_t* pos, std::string* line) {
    if (*pos >= text.size()) return false;
    const size_t end = text.find_first_of("\r\n", *pos);
    if (end == std::string::npos) {
        line->assign(text, *pos, std::string::npos);
        *pos = text.size();
        return true;
    }
    line->assign(text, *pos, end - *pos);
    *pos = end + ((text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n') ? 2 : 1);
    return true;
}

std::vector<std::string> split_tokens(const std::string& line) {
    std::vector<std::string> tokens;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
    return tokens;
}

// A plain decimal number: [+-] digits [. digits] [(e|E) [+-] digits], at least one digit in the
// mantissa. strtod alone would also take "nan", "inf" and hex floats, which tinyobj reads as 0.
bool is_decimal_number(const std::string& s) {
    size_t i = 0;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    size_t digits = 0;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++digits;
    if (i < s.size() && s[i] == '.') {
        ++i;
        while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++digits;
    }
    if (digits == 0) return false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        size_t exponent_digits = 0;
        while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++exponent_digits;
        if (exponent_digits == 0) return false;
    }
    return i == s.size();
}

bool names_non_finite(const std::string& s) {
    std::string lower;
    for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!lower.empty() && (lower[0] == '+' || lower[0] == '-')) lower.erase(0, 1);
    return lower.rfind("nan", 0) == 0 || lower.rfind("inf", 0) == 0;
}

// Parses the numbers of a `v`/`vn`/`vt` line (tokens after the keyword, up to a comment) and
// checks they are finite as floats, the precision tinyobj stores.
std::vector<float> parse_numbers(const std::vector<std::string>& tokens, const std::string& display,
                                 int line) {
    std::vector<float> values;
    for (size_t i = 1; i < tokens.size(); ++i) {
        const std::string& t = tokens[i];
        if (t[0] == '#') break;
        if (names_non_finite(t)) fail_at(display, line, "coordinate '" + t + "' is not finite");
        if (!is_decimal_number(t)) fail_at(display, line, "bad number '" + t + "'");
        float value = static_cast<float>(std::strtod(t.c_str(), nullptr));
        if (!std::isfinite(value)) {
            fail_at(display, line, "coordinate '" + t + "' is not finite (out of float range)");
        }
        values.push_back(value);
    }
    return values;
}

bool parse_int(const std::string& s, long* value) {
    if (s.empty()) return false;
    size_t i = (s[0] == '+' || s[0] == '-') ? 1 : 0;
    if (i == s.size()) return false;
    for (size_t k = i; k < s.size(); ++k) {
        if (!std::isdigit(static_cast<unsigned char>(s[k]))) return false;
    }
    errno = 0;
    *value = std::strtol(s.c_str(), nullptr, 10);
    return errno == 0 && *value >= INT_MIN && *value <= INT_MAX;
}

// tinyobj's mtllib splitting: on spaces, with "\ " escaping a space inside a file name; any
// other backslash is a Windows path separator and stays.
std::vector<std::string> split_mtllib(const std::string& rest) {
    std::vector<std::string> names;
    std::string current;
    for (size_t i = 0; i < rest.size(); ++i) {
        char c = rest[i];
        if (c == '\\' && i + 1 < rest.size() && rest[i + 1] == ' ') {
            current += rest[++i];
        } else if (c == ' ' || c == '\t') {
            if (!current.empty()) names.push_back(current);
            current.clear();
        } else {
            current += c;
        }
    }
    if (!current.empty()) names.push_back(current);
    return names;
}

// An index that refers past the vertices read so far; OBJ readers (tinyobj included) resolve
// positive indices against the whole file, so these are checked once the file is read.
struct ForwardReference {
    int line;
    const char* what;  // "vertex", "normal", "texture coordinate"
    long index;        // 1-based
};

std::string count_of(long n, const std::string& what) {
    if (n == 1) return "1 " + what;
    return std::to_string(n) + " " + (what == "vertex" ? std::string("vertices") : what + "s");
}

}  // namespace

ObjPrescan prescan_obj(const std::string& obj_path, const std::string& display) {
    std::ifstream in(obj_path, std::ios::binary);
    if (!in) throw Error("cannot open '" + display + "'");
    std::stringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) throw Error("cannot read '" + display + "'");

    ObjPrescan scan;
    long normal_count = 0;
    long texcoord_count = 0;
    std::vector<ForwardReference> forward;

    scan.text = buffer.str();
    const std::string& text = scan.text;
    size_t pos = 0;
    std::string line_text;
    for (int line = 1; next_line(text, &pos, &line_text); ++line) {
        const std::vector<std::string> tokens = split_tokens(line_text);
        if (tokens.empty() || tokens[0][0] == '#') continue;
        const std::string& keyword = tokens[0];

        if (keyword == "v" || keyword == "vn") {
            std::vector<float> values = parse_numbers(tokens, display, line);
            if (values.size() < 3) {
                fail_at(display, line,
                        std::string(keyword == "v" ? "vertex" : "normal") + " needs 3 coordinates, found " +
                            std::to_string(values.size()) + " (truncated file?)");
            }
            if (keyword == "v") {
                scan.vertex_lines.push_back(line);
            } else {
                ++normal_count;
            }
        } else if (keyword == "vt") {
            if (parse_numbers(tokens, display, line).empty()) {
                fail_at(display, line, "texture coordinate needs at least 1 number, found 0");
            }
            ++texcoord_count;
        } else if (keyword == "f") {
            if (tokens.size() < 4) {
                fail_at(display, line,
                        "face needs at least 3 vertices, found " + std::to_string(tokens.size() - 1) +
                            " (truncated file?)");
            }
            const long vertex_count = static_cast<long>(scan.vertex_lines.size());
            for (size_t k = 1; k < tokens.size(); ++k) {
                const std::string& ref = tokens[k];
                // v, v/vt, v//vn or v/vt/vn
                std::vector<std::string> parts;
                std::string part;
                for (char c : ref) {
                    if (c == '/') {
                        parts.push_back(part);
                        part.clear();
                    } else {
                        part += c;
                    }
                }
                parts.push_back(part);
                const bool shape_ok = parts.size() <= 3 && !parts[0].empty() &&
                                      (parts.size() < 2 || !parts[1].empty() || parts.size() == 3) &&
                                      (parts.size() < 3 || !parts[2].empty());
                if (!shape_ok) fail_at(display, line, "bad vertex reference '" + ref + "'");

                const char* what[3] = {"vertex", "texture coordinate", "normal"};
                const long counts[3] = {vertex_count, texcoord_count, normal_count};
                long resolved_vertex = 0;
                for (size_t p = 0; p < parts.size(); ++p) {
                    if (parts[p].empty()) continue;  // the vt of v//vn
                    long index = 0;
                    if (!parse_int(parts[p], &index)) {
                        fail_at(display, line, "bad vertex reference '" + ref + "'");
                    }
                    if (index == 0) {
                        fail_at(display, line, "bad vertex reference '" + ref + "' (OBJ indices start at 1)");
                    }
                    long zero_based = index > 0 ? index - 1 : counts[p] + index;
                    if (zero_based < 0) {
                        fail_at(display, line,
                                std::string(what[p]) + " index " + std::to_string(index) +
                                    " out of range (" + count_of(counts[p], what[p]) + " defined so far)");
                    }
                    if (zero_based >= counts[p]) forward.push_back({line, what[p], index});
                    if (p == 0) resolved_vertex = zero_based;
                }
                scan.face_vertices.push_back(static_cast<int>(resolved_vertex));
            }
            scan.face_lines.push_back(line);
            scan.face_offsets.push_back(scan.face_vertices.size() - (tokens.size() - 1));
        } else if (keyword == "mtllib") {
            const size_t at = line_text.find("mtllib") + 6;
            for (const std::string& name : split_mtllib(line_text.substr(at))) {
                // Windows exporters write "materials\\x.mtl" or ".\\x.mtl", and names whose
                // case differs from the file's: resolved like texture paths.
                const std::string file = resolve_texture_path(fs::path(obj_path).parent_path().string(), name);
                if (!file.empty() && std::ifstream(file)) {
                    if (std::find(scan.mtl_paths.begin(), scan.mtl_paths.end(), file) == scan.mtl_paths.end())
                        scan.mtl_paths.push_back(file);
                } else {
                    // A download often lacks its MTL: the loader warns and renders grey.
                    fs::path shown = fs::path(display).parent_path() / name;
                    scan.missing_mtllibs.push_back({line, shown.string()});
                }
            }
        }
    }
    scan.face_offsets.push_back(scan.face_vertices.size());

    const long totals[3] = {static_cast<long>(scan.vertex_lines.size()), texcoord_count, normal_count};
    for (const ForwardReference& ref : forward) {
        const std::string what = ref.what;
        const long total = what == "vertex" ? totals[0] : (what == "normal" ? totals[2] : totals[1]);
        if (ref.index > total) {
            fail_at(display, ref.line,
                    what + " index " + std::to_string(ref.index) + " out of range (the file has " +
                        count_of(total, what) + ")");
        }
    }
    return scan;
}

}  // namespace clbdpt::detail
