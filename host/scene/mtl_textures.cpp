// MTL texture maps -> TextureInfo entries over the scene's one texel array.
//
//   map_Kd            multiplies Kd (8-bit files are sRGB-encoded colour; float files linear);
//                     its alpha channel, where some texel is below 1/2 and no map_d is given,
//                     is the material's cut-out
//   map_Ks            multiplies Ks of a glossy or mirror material
//   map_Ke            multiplies Ke (taken as 1 1 1 where the MTL gives the map but no Ke): an
//                     emitter whose radiance varies over its surface
//   map_d             cut-out (alpha test): the file's alpha channel if it has one, else its
//                     first channel
//   bump, map_bump    height field (-bm scales it), perturbs the shading normal
//   norm              tangent-space normal map (rgb = (n + 1) / 2), replaces the shading normal
// Options honoured per use: -s and -o (u and v), -clamp on, -bm. Paths are relative to the MTL's
// folder (or the OBJ's); Windows backslashes and a leading "./" or ".\" are accepted, and a name whose case
// does not match the file's (common in files made on Windows) is found by a case-blind look in
// its folder. An image is read once however many materials use it.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>

#include <tiny_obj_loader.h>

#include "film/image_io.h"
#include "scene/loader_internal.h"
#include "util/error.h"

namespace clbdpt::detail {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

bool is_file(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

// The entry of `dir` whose name equals `name` ignoring case, or an empty path.
fs::path find_case_blind(const fs::path& dir, const std::string& name) {
    std::error_code ec;
    const std::string wanted = lower(name);
    for (fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec), end; !ec && it != end; it.increment(ec)) {
        if (lower(it->path().filename().string()) == wanted) return it->path();
    }
    return {};
}

// Packs 8-bit RGBA as one uint: r | g << 8 | b << 16 | a << 24 (TEXTURE_RGBA8_*).
uint32_t pack_rgba8(const uint8_t* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

bool alpha_has_holes(const TextureImage& image) {
    if (!image.has_alpha) return false;
    const size_t pixels = size_t(image.width) * size_t(image.height);
    for (size_t p = 0; p < pixels; ++p) {
        const float a = image.is_float ? image.rgba32f[p * 4 + 3] : float(image.rgba8[p * 4 + 3]) / 255.0f;
        if (a < 0.5f) return true;
    }
    return false;
}

}  // namespace

std::string resolve_texture_path(const std::string& base_dir, const std::string& name) {
    std::string cleaned = name;
    std::replace(cleaned.begin(), cleaned.end(), '\\', '/');
    while (cleaned.rfind("./", 0) == 0) cleaned.erase(0, 2);
    if (cleaned.empty()) return "";
    const fs::path given(cleaned);
    const fs::path full = given.is_absolute() ? given : fs::path(base_dir) / given;
    if (is_file(full)) return full.string();
    // Case-blind, component by component from the base folder (or the root).
    fs::path resolved = given.is_absolute() ? given.root_path() : fs::path(base_dir);
    for (const fs::path& part : given.relative_path()) {
        const fs::path exact = resolved / part;
        std::error_code ec;
        if (fs::exists(exact, ec)) {
            resolved = exact;
            continue;
        }
        const fs::path match = find_case_blind(resolved, part.string());
        if (match.empty()) return "";
        resolved = match;
    }
    return is_file(resolved) ? resolved.string() : "";
}

TextureLoader::Use TextureLoader::add(Scene& scene, const std::vector<std::string>& base_dirs, const std::string& name,
                                      const tinyobj::texture_option_t& option, bool colour) {
    std::string path;
    for (size_t i = 0; i < base_dirs.size() && path.empty(); ++i) path = resolve_texture_path(base_dirs[i], name);
    if (path.empty()) {
        unreadable.push_back(name);
        return {};
    }
    const std::string key = path + (colour ? "|colour" : "|data");
    auto found = images_.find(key);
    if (found == images_.end()) {
        TextureImage image;
        try {
            image = read_texture_image(path);
        } catch (const Error&) {
            unreadable.push_back(name);
            return {};
        }
        Image slot;
        slot.offset = scene.texels.size();
        slot.width = image.width;
        slot.height = image.height;
        slot.format = image.is_float ? TEXTURE_RGBA32F : (colour ? TEXTURE_RGBA8_SRGB : TEXTURE_RGBA8_LINEAR);
        slot.has_alpha = image.has_alpha;
        slot.has_holes = alpha_has_holes(image);
        const size_t pixels = size_t(image.width) * size_t(image.height);
        if (slot.offset + pixels * (image.is_float ? 4 : 1) > size_t(UINT32_MAX))
            throw Error("'" + path + "': the scene's textures exceed 16 GiB");
        if (image.is_float) {
            const size_t at = scene.texels.size();
            scene.texels.resize(at + pixels * 4);
            std::memcpy(&scene.texels[at], image.rgba32f.data(), pixels * 4 * sizeof(float));
        } else {
            scene.texels.reserve(scene.texels.size() + pixels);
            for (size_t p = 0; p < pixels; ++p) scene.texels.push_back(pack_rgba8(&image.rgba8[p * 4]));
        }
        found = images_.emplace(key, slot).first;
    }
    const Image& slot = found->second;
    TextureInfo info{};
    info.offset = uint32_t(slot.offset);
    info.width = slot.width;
    info.height = slot.height;
    info.format = slot.format;
    info.scale_u = float(option.scale[0]);
    info.scale_v = float(option.scale[1]);
    info.offset_u = float(option.origin_offset[0]);
    info.offset_v = float(option.origin_offset[1]);
    info.clamp = option.clamp ? 1 : 0;
    scene.textures.push_back(info);
    Use use;
    use.texture = int(scene.textures.size());
    use.has_alpha = slot.has_alpha;
    use.alpha_has_holes = slot.has_holes;
    return use;
}

void attach_textures(Scene& scene, TextureLoader& loader, const std::vector<std::string>& base_dir,
                     const tinyobj::material_t& mtl, Material* m) {
    TextureLoader::Use kd;
    if (!mtl.diffuse_texname.empty() && m->kind != MATERIAL_GLASS) {
        kd = loader.add(scene, base_dir, mtl.diffuse_texname, mtl.diffuse_texopt, true);
        m->kd_texture = kd.texture;
    }
    if (!mtl.specular_texname.empty() && (m->kind == MATERIAL_GLOSSY || m->kind == MATERIAL_MIRROR))
        m->ks_texture = loader.add(scene, base_dir, mtl.specular_texname, mtl.specular_texopt, true).texture;
    if (!mtl.emissive_texname.empty()) {
        m->ke_texture = loader.add(scene, base_dir, mtl.emissive_texname, mtl.emissive_texopt, true).texture;
        const bool no_ke = m->ke.s[0] <= 0 && m->ke.s[1] <= 0 && m->ke.s[2] <= 0;
        if (m->ke_texture && no_ke) m->ke.s[0] = m->ke.s[1] = m->ke.s[2] = 1.0f;
    }
    if (!mtl.alpha_texname.empty()) {
        const TextureLoader::Use d = loader.add(scene, base_dir, mtl.alpha_texname, mtl.alpha_texopt, false);
        m->cutout_texture = d.texture;
        m->cutout_channel = d.has_alpha ? 3 : 0;  // an alpha channel if there is one, else the grey value
    } else if (kd.alpha_has_holes) {
        m->cutout_texture = kd.texture;  // alpha is never sRGB-encoded: the kd use reads it raw
        m->cutout_channel = 3;
    }
    if (!mtl.normal_texname.empty()) {
        m->bump_texture = loader.add(scene, base_dir, mtl.normal_texname, mtl.normal_texopt, false).texture;
        m->bump_is_normal_map = 1;
    } else if (!mtl.bump_texname.empty()) {
        m->bump_texture = loader.add(scene, base_dir, mtl.bump_texname, mtl.bump_texopt, false).texture;
        m->bump_scale = float(mtl.bump_texopt.bump_multiplier);
    }
}

}  // namespace clbdpt::detail
