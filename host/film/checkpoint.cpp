#include "film/checkpoint.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "util/atomic_file.h"
#include "util/error.h"
#include "util/fnv1a.h"

namespace clbdpt {

namespace {

constexpr char kMagic[8] = {'C', 'L', 'B', 'D', 'P', 'T', 'C', 'K'};
// 2: the light subpaths' Russian roulette joined the strategy mix (a checkpoint of version 1
// was rendered without roulette, which its resumed passes could not match).
constexpr uint32_t kVersion = 2;

// Film sizes beyond these are not something clbdpt writes (the command line caps the film at
// 32768 on a side); a header claiming more is damage, refused before allocating for it.
constexpr int64_t kMaxSide = 32768;
constexpr int64_t kMaxStrategyStride = 256;
constexpr uint64_t kMaxSettingsBytes = 1 << 16;

struct Header {
    char magic[8];
    uint32_t version;
    int32_t width, height, spp;
    uint64_t scene_fingerprint;
    int32_t integrator;
    float light_subpaths;
    int32_t inner_connections;
    int32_t roulette_light_from;
    int32_t reserved;
    int32_t strategy_stride;  // 0: no strategy sums
    uint64_t strategy_values;
    uint64_t settings_bytes;
};
static_assert(sizeof(Header) == 72, "the checkpoint header is written as it lies in memory");

void append(std::string* out, const void* data, size_t bytes) { out->append(static_cast<const char*>(data), bytes); }

}  // namespace

void write_checkpoint(const std::string& path, const CheckpointInfo& info, const Film& film) {
    Header h{};
    std::memcpy(h.magic, kMagic, sizeof kMagic);
    h.version = kVersion;
    h.width = film.width;
    h.height = film.height;
    h.spp = film.spp;
    h.scene_fingerprint = info.scene_fingerprint;
    h.integrator = info.integrator;
    h.light_subpaths = info.light_subpaths;
    h.inner_connections = info.inner_connections;
    h.roulette_light_from = info.roulette_light_from;
    h.strategy_stride = film.strategy_sum.empty() ? 0 : film.strategy_stride;
    h.strategy_values = film.strategy_sum.size();
    h.settings_bytes = info.settings.size();
    std::string bytes;
    bytes.reserve(sizeof h + sizeof(double) * (film.camera_sum.size() * 2 + film.strategy_sum.size()) + 8);
    append(&bytes, &h, sizeof h);
    bytes += info.settings;
    append(&bytes, film.camera_sum.data(), sizeof(double) * film.camera_sum.size());
    append(&bytes, film.light_sum.data(), sizeof(double) * film.light_sum.size());
    append(&bytes, film.strategy_sum.data(), sizeof(double) * film.strategy_sum.size());
    Fnv1a hash_of_contents;
    hash_of_contents.bytes(bytes.data(), bytes.size());
    const uint64_t hash = hash_of_contents.value();
    append(&bytes, &hash, sizeof hash);
    write_file_atomically(path, bytes, /*durable=*/true);
}

Checkpoint read_checkpoint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot read checkpoint '" + path + "': " + std::strerror(errno));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    const std::string bytes = buffer.str();
    auto damaged = [&](const std::string& why) {
        return Error("checkpoint '" + path + "' is not usable: " + why);
    };
    Header h{};
    if (bytes.size() < sizeof h + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
        throw damaged("not a clbdpt checkpoint");
    std::memcpy(&h, bytes.data(), sizeof h);
    if (h.version != kVersion)
        throw damaged("format version " + std::to_string(h.version) + ", this clbdpt reads " + std::to_string(kVersion));
    if (h.width < 1 || h.width > kMaxSide || h.height < 1 || h.height > kMaxSide || h.spp < 0 ||
        h.strategy_stride < 0 || h.strategy_stride > kMaxStrategyStride)
        throw damaged("its header is damaged");
    const uint64_t pixel_values = uint64_t(h.width) * uint64_t(h.height) * 3;
    const uint64_t expected =
        sizeof h + h.settings_bytes + sizeof(double) * (2 * pixel_values + h.strategy_values) + 8;
    if (h.strategy_values > pixel_values * uint64_t(kMaxStrategyStride) * kMaxStrategyStride ||
        h.settings_bytes > kMaxSettingsBytes || bytes.size() != expected)
        throw damaged("it is truncated or damaged (" + std::to_string(bytes.size()) + " bytes, expected " +
                      std::to_string(expected) + ")");
    uint64_t stored_hash;
    std::memcpy(&stored_hash, bytes.data() + bytes.size() - 8, 8);
    Fnv1a hash_of_contents;
    hash_of_contents.bytes(bytes.data(), bytes.size() - 8);
    if (hash_of_contents.value() != stored_hash) throw damaged("its contents are damaged (hash mismatch)");

    Checkpoint c;
    c.info.scene_fingerprint = h.scene_fingerprint;
    c.info.integrator = h.integrator;
    c.info.light_subpaths = h.light_subpaths;
    c.info.inner_connections = h.inner_connections;
    c.info.roulette_light_from = h.roulette_light_from;
    c.film = Film(h.width, h.height);
    c.film.spp = h.spp;
    const char* p = bytes.data() + sizeof h;
    c.info.settings.assign(p, h.settings_bytes);
    p += h.settings_bytes;
    std::memcpy(c.film.camera_sum.data(), p, sizeof(double) * pixel_values);
    p += sizeof(double) * pixel_values;
    std::memcpy(c.film.light_sum.data(), p, sizeof(double) * pixel_values);
    p += sizeof(double) * pixel_values;
    if (h.strategy_values > 0) {
        c.film.strategy_sum.resize(h.strategy_values);
        c.film.strategy_stride = h.strategy_stride;
        std::memcpy(c.film.strategy_sum.data(), p, sizeof(double) * h.strategy_values);
    }
    return c;
}

std::vector<std::string> settings_differences(const std::string& from, const std::string& to) {
    auto pairs = [](const std::string& line) {
        std::vector<std::pair<std::string, std::string>> out;
        std::istringstream words(line);
        for (std::string word; words >> word;) {
            const size_t eq = word.find('=');
            out.push_back({word.substr(0, eq), eq == std::string::npos ? "" : word.substr(eq + 1)});
        }
        return out;
    };
    const auto a = pairs(from), b = pairs(to);
    std::vector<std::string> differences;
    auto value_in = [](const std::vector<std::pair<std::string, std::string>>& v, const std::string& key) {
        for (const auto& [k, value] : v)
            if (k == key) return value;
        return std::string("(none)");
    };
    for (const auto& [key, value] : a)
        if (value_in(b, key) != value) differences.push_back(key + ": " + value + " -> " + value_in(b, key));
    for (const auto& [key, value] : b)
        if (value_in(a, key) == "(none)") differences.push_back(key + ": (none) -> " + value);
    return differences;
}

}  // namespace clbdpt
