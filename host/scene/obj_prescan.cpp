// Line-by-line validation of OBJ text before tinyobj sees it. tinyobj is lenient where a renderer
// must not be: "v 1.0 2.0" gets z = 0, "nan" parses as 0, a face index past the end only warns
// and a negative one that resolves below 0 is used unchecked. Catching these here lets every
// message name the file and line.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <string_view>
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
bool next_line(std::string_view text, size_t* pos, std::string_view* line) {
    if (*pos >= text.size()) return false;
    const size_t end = text.find_first_of("\r\n", *pos);
    if (end == std::string_view::npos) {
        *line = text.substr(*pos);
        *pos = text.size();
        return true;
    }
    *line = text.substr(*pos, end - *pos);
    *pos = end + ((text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n') ? 2 : 1);
    return true;
}

// Splits `line` on blanks into `tokens` (views into the line; the vector is reused from line
// to line, so a large file allocates nothing per line).
void split_tokens(std::string_view line, std::vector<std::string_view>* tokens) {
    tokens->clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) tokens->push_back(line.substr(start, i - start));
    }
}

// A plain decimal number: [+-] digits [. digits] [(e|E) [+-] digits], at least one digit in the
// mantissa. strtod alone would also take "nan", "inf" and hex floats, which tinyobj reads as 0.
bool is_decimal_number(std::string_view s) {
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

bool names_non_finite(std::string_view s) {
    if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
    if (s.size() < 3) return false;
    auto is = [&](const char* word) {
        for (int i = 0; i < 3; ++i)
            if (std::tolower(static_cast<unsigned char>(s[size_t(i)])) != word[i]) return false;
        return true;
    };
    return is("nan") || is("inf");
}

// Checks the numbers of a `v`/`vn`/`vt` line (tokens after the keyword, up to a comment) and
// that they are finite as floats, the precision tinyobj stores. Returns how many there are.
size_t check_numbers(const std::vector<std::string_view>& tokens, const std::string& display, int line) {
    size_t count = 0;
    for (size_t i = 1; i < tokens.size(); ++i) {
        const std::string_view t = tokens[i];
        if (t[0] == '#') break;
        if (names_non_finite(t)) fail_at(display, line, "coordinate '" + std::string(t) + "' is not finite");
        if (!is_decimal_number(t)) fail_at(display, line, "bad number '" + std::string(t) + "'");
        // is_decimal_number admits only what from_chars reads whole; a leading '+' it does not.
        const std::string_view digits = t[0] == '+' ? t.substr(1) : t;
        double value = 0.0;
        const std::from_chars_result r = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        // Out of range is also what from_chars says of an underflow ("1e-400"), which strtod
        // rounds to 0 as tinyobj will: ask strtod about those rare cases.
        if (r.ec == std::errc::result_out_of_range) value = std::strtod(std::string(t).c_str(), nullptr);
        if (!std::isfinite(static_cast<float>(value))) {
            fail_at(display, line, "coordinate '" + std::string(t) + "' is not finite (out of float range)");
        }
        ++count;
    }
    return count;
}

bool parse_int(std::string_view s, long* value) {
    if (s.empty()) return false;
    if (s[0] == '+') s.remove_prefix(1);
    if (s.empty() || s[0] == '+') return false;
    const std::from_chars_result r = std::from_chars(s.data(), s.data() + s.size(), *value);
    return r.ec == std::errc() && r.ptr == s.data() + s.size() && *value >= INT_MIN && *value <= INT_MAX;
}

// tinyobj's mtllib splitting: on spaces, with "\ " escaping a space inside a file name; any
// other backslash is a Windows path separator and stays.
std::vector<std::string> split_mtllib(std::string_view rest) {
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

std::string read_obj_text(const std::string& obj_path, const std::string& display) {
    std::ifstream in(obj_path, std::ios::binary | std::ios::ate);
    if (!in) throw Error("cannot open '" + display + "'");
    // Straight into one string of the file's size: a stringstream would copy a large file
    // twice more (and the kernel's page zeroing of every copy dominates loading then).
    const std::streamoff size = in.tellg();
    if (size < 0) throw Error("cannot read '" + display + "'");
    std::string text(static_cast<size_t>(size), '\0');
    in.seekg(0);
    if (!in.read(text.data(), size)) throw Error("cannot read '" + display + "'");
    return text;
}

void blank_inline_comments(std::string* text) {
    for (size_t hash = text->find('#'); hash != std::string::npos; hash = text->find('#', hash + 1)) {
        const size_t line_start = text->find_last_of("\r\n", hash) == std::string::npos
                                      ? 0
                                      : text->find_last_of("\r\n", hash) + 1;
        const std::string_view line(text->data() + line_start, hash - line_start);
        const size_t first = line.find_first_not_of(" \t");
        if (first == std::string_view::npos) continue;  // a whole-line comment
        const std::string_view keyword = line.substr(first, line.find_first_of(" \t", first) - first);
        if (keyword != "v" && keyword != "vt" && keyword != "vn" && keyword != "f") continue;
        const size_t end = text->find_first_of("\r\n", hash);
        std::fill(text->begin() + long(hash), end == std::string::npos ? text->end() : text->begin() + long(end), ' ');
        hash = end == std::string::npos ? text->size() - 1 : end;
    }
}

MaterialLibraries find_material_libraries(std::string_view text, const std::string& obj_path,
                                          const std::string& display) {
    MaterialLibraries libraries;
    size_t pos = 0;
    std::string_view line_text;
    for (int line = 1; next_line(text, &pos, &line_text); ++line) {
        const size_t first = line_text.find_first_not_of(" \t");
        if (first == std::string_view::npos || line_text.compare(first, 6, "mtllib") != 0) continue;
        std::string_view rest = line_text.substr(first + 6);
        if (!rest.empty() && rest[0] != ' ' && rest[0] != '\t') continue;  // "mtllibx" is another keyword
        const size_t comment = rest.find('#');  // an inline comment, after a blank
        if (comment != std::string_view::npos && comment > 0 && (rest[comment - 1] == ' ' || rest[comment - 1] == '\t'))
            rest = rest.substr(0, comment);
        // Names with unescaped spaces ("mtllib box mtllib red.mtl") are common: tokens are
        // joined until they name an existing file (or the last one alone does); what never
        // does is reported token by token. Windows exporters write "materials\\x.mtl" or
        // ".\\x.mtl", and names whose case differs from the file's: resolved like texture paths.
        const std::string obj_dir = fs::path(obj_path).parent_path().string();
        auto existing = [&](const std::string& name) {
            const std::string file = resolve_texture_path(obj_dir, name);
            return !file.empty() && std::ifstream(file) ? file : std::string();
        };
        auto take = [&](const std::string& file) {
            if (std::find(libraries.paths.begin(), libraries.paths.end(), file) == libraries.paths.end())
                libraries.paths.push_back(file);
        };
        auto missing = [&](const std::string& name) {  // a download often lacks its MTL: warned
            libraries.missing.push_back({line, (fs::path(display).parent_path() / name).string()});
        };
        std::vector<std::string> pending;
        std::string pending_name;
        for (const std::string& token : split_mtllib(rest)) {
            pending.push_back(token);
            pending_name += (pending_name.empty() ? "" : " ") + token;
            std::string file = existing(pending_name);
            if (file.empty() && pending.size() > 1 && !(file = existing(token)).empty()) {
                for (size_t i = 0; i + 1 < pending.size(); ++i) missing(pending[i]);
            }
            if (file.empty()) continue;
            take(file);
            pending.clear();
            pending_name.clear();
        }
        for (const std::string& name : pending) missing(name);
    }
    return libraries;
}

ObjPrescan prescan_obj(std::string_view text, const std::string& display) {
    ObjPrescan scan;
    long normal_count = 0;
    long texcoord_count = 0;
    std::vector<ForwardReference> forward;

    size_t pos = 0;
    std::string_view line_text;
    std::vector<std::string_view> tokens;
    for (int line = 1; next_line(text, &pos, &line_text); ++line) {
        split_tokens(line_text, &tokens);
        if (tokens.empty() || tokens[0][0] == '#') continue;
        const std::string_view keyword = tokens[0];

        if (keyword == "v" || keyword == "vn") {
            const size_t values = check_numbers(tokens, display, line);
            if (values < 3) {
                fail_at(display, line,
                        std::string(keyword == "v" ? "vertex" : "normal") + " needs 3 coordinates, found " +
                            std::to_string(values) + " (truncated file?)");
            }
            if (keyword == "v") {
                scan.vertex_lines.push_back(line);
            } else {
                ++normal_count;
            }
        } else if (keyword == "vt") {
            if (check_numbers(tokens, display, line) == 0) {
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
                const std::string_view ref = tokens[k];
                // v, v/vt, v//vn or v/vt/vn
                std::string_view parts[4];
                size_t part_count = 0;
                for (size_t start = 0;;) {
                    const size_t slash = ref.find('/', start);
                    if (part_count < 4) parts[part_count] = ref.substr(start, slash == std::string_view::npos ? slash : slash - start);
                    ++part_count;
                    if (slash == std::string_view::npos) break;
                    start = slash + 1;
                }
                const bool shape_ok = part_count <= 3 && !parts[0].empty() &&
                                      (part_count < 2 || !parts[1].empty() || part_count == 3) &&
                                      (part_count < 3 || !parts[2].empty());
                if (!shape_ok) fail_at(display, line, "bad vertex reference '" + std::string(ref) + "'");

                const char* what[3] = {"vertex", "texture coordinate", "normal"};
                const long counts[3] = {vertex_count, texcoord_count, normal_count};
                for (size_t p = 0; p < part_count; ++p) {
                    if (parts[p].empty()) continue;  // the vt of v//vn
                    long index = 0;
                    if (!parse_int(parts[p], &index)) {
                        fail_at(display, line, "bad vertex reference '" + std::string(ref) + "'");
                    }
                    if (index == 0) {
                        fail_at(display, line, "bad vertex reference '" + std::string(ref) + "' (OBJ indices start at 1)");
                    }
                    long zero_based = index > 0 ? index - 1 : counts[p] + index;
                    if (zero_based < 0) {
                        fail_at(display, line,
                                std::string(what[p]) + " index " + std::to_string(index) +
                                    " out of range (" + count_of(counts[p], what[p]) + " defined so far)");
                    }
                    if (zero_based >= counts[p]) forward.push_back({line, what[p], index});
                }
            }
            ++scan.face_count;
            scan.face_triangles += tokens.size() - 3;
        }
    }

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
