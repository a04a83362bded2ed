#include "render/scene_fingerprint.h"

#include "util/fnv1a.h"

namespace clbdpt {

uint64_t scene_fingerprint(const DeviceScene& s) {
    Fnv1a h;
    h.array(s.triangles);
    h.array(s.infos);
    h.array(s.normals);
    h.array(s.materials);
    h.array(s.lights);
    h.array(s.light_cdf);
    h.array(s.env_texels);
    h.array(s.env_distribution);
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
