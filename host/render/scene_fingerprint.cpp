#include "render/scene_fingerprint.h"

#include <vector>

namespace clbdpt {

namespace {

// 64-bit FNV-1a. Not cryptographic: it tells an accidental mismatch (another scene, another
// setting) from a resume of the same render.
class Fnv1a {
public:
    void bytes(const void* data, size_t size) {
        const unsigned char* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < size; ++i) {
            hash_ ^= p[i];
            hash_ *= 1099511628211ull;
        }
    }
    // The size first, so that neighbouring arrays cannot trade elements unnoticed.
    template <typename T>
    void array(const std::vector<T>& v) {
        const uint64_t n = v.size();
        bytes(&n, sizeof n);
        bytes(v.data(), sizeof(T) * v.size());
    }
    uint64_t value() const { return hash_; }

private:
    uint64_t hash_ = 14695981039346656037ull;
};

}  // namespace

uint64_t scene_fingerprint(const DeviceScene& s) {
    Fnv1a h;
    h.array(s.triangles);
    h.array(s.infos);
    h.array(s.normals);
    h.array(s.materials);
    h.array(s.lights);
    h.array(s.light_cdf);
    h.array(s.env_texels);
    h.array(s.uvs);
    h.array(s.textures);
    h.array(s.texels);
    h.array(s.media);
    h.array(s.densities);
    h.bytes(&s.camera, sizeof s.camera);
    h.bytes(&s.info, sizeof s.info);
    return h.value();
}

}  // namespace clbdpt
