#include "render/device_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>

#include "render/media_nesting.h"
#include "util/error.h"

namespace clbdpt {

Vec3 vec3_of(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }

void store_triangle_normals(std::vector<Triangle>& triangles) {
    for (Triangle& t : triangles) {
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = double(t.p1.s[k]) - double(t.p0.s[k]);
            e2[k] = double(t.p2.s[k]) - double(t.p0.s[k]);
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        // The loader drops triangles of zero area; one whose float corners still coincide gets
        // no normal (0), which no cosine or offset can turn into a NaN.
        const double inv = len > 0 ? 1.0 / len : 0.0;
        t.p0.s[3] = float(n[0] * inv);
        t.p1.s[3] = float(n[1] * inv);
        t.p2.s[3] = float(n[2] * inv);
    }
}

std::vector<TriangleRows> triangle_rows(const std::vector<Triangle>& triangles) {
    std::vector<TriangleRows> rows(triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i) {
        const cl_float4* corner[3] = {&triangles[i].p0, &triangles[i].p1, &triangles[i].p2};
        for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 3; ++c) rows[i].row[k].s[c] = corner[c]->s[k];
            rows[i].row[k].s[3] = corner[k]->s[3]; // the normal's coordinate k (store_triangle_normals)
        }
    }
    return rows;
}

namespace {

constexpr float kPi = 3.14159265358979323846f;

cl_float4 float4_of(Vec3 v, float w = 0.0f) {
    cl_float4 r;
    r.s[0] = v.x;
    r.s[1] = v.y;
    r.s[2] = v.z;
    r.s[3] = w;
    return r;
}


bool is_emissive(const Material& m) { return m.ke.s[0] > 0 || m.ke.s[1] > 0 || m.ke.s[2] > 0; }

// Builds a normalised CDF over weights (n + 1 entries) and returns the sum. All-zero weights
// give a uniform CDF.
float build_cdf(const std::vector<float>& weights, float* cdf) {
    const size_t n = weights.size();
    double total = 0;
    for (float w : weights) total += w;
    cdf[0] = 0;
    double running = 0;
    for (size_t i = 0; i < n; ++i) {
        running += weights[i];
        cdf[i + 1] = total > 0 ? float(running / total) : float(double(i + 1) / double(n));
    }
    cdf[n] = 1.0f;
    return float(total);
}

float srgb_to_linear(uint32_t code) {
    const float c = float(code) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// Mean luminance of a texture's texels (linear), layout as in cl/shared/types.h.
float texture_mean_luminance(const Scene& scene, int texture) {
    const TextureInfo& t = scene.textures[size_t(texture - 1)];
    const size_t count = size_t(t.width) * size_t(t.height);
    double sum = 0;
    for (size_t i = 0; i < count; ++i) {
        Vec3 c;
        if (t.format == TEXTURE_RGBA32F) {
            const uint32_t* p = &scene.texels[t.offset + 4 * i];
            float v[3];
            std::memcpy(v, p, sizeof v);
            c = Vec3(v[0], v[1], v[2]);
        } else {
            const uint32_t v = scene.texels[t.offset + i];
            const uint32_t r = v & 255u, g = (v >> 8) & 255u, b = (v >> 16) & 255u;
            c = t.format == TEXTURE_RGBA8_SRGB ? Vec3(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b))
                                               : Vec3(float(r), float(g), float(b)) * (1.0f / 255.0f);
        }
        sum += std::max(0.0f, luminance(c));
    }
    return count ? float(sum / double(count)) : 0.0f;
}

}  // namespace

void append_cdf_guide(std::vector<float>& buffer, size_t cdf_offset, int n, int g) {
    std::vector<float> guide(size_t(g) + 1);
    const float* cdf = buffer.data() + cdf_offset;
    for (int k = 0; k <= g; ++k) {
        const float u = g > 0 ? float(double(k) / double(g)) : 0.0f;
        const int32_t i = n > 0 ? int32_t(std::upper_bound(cdf, cdf + n, u) - cdf) - 1 : 0;
        std::memcpy(&guide[size_t(k)], &i, sizeof i);
    }
    buffer.insert(buffer.end(), guide.begin(), guide.end());
}

Camera make_camera(const CameraDesc& desc, int width, int height) {
    Camera c{};
    Vec3 forward = normalize(desc.target - desc.eye);
    Vec3 right = cross(forward, desc.up);
    if (!(length(right) > 0)) throw Error("camera: 'up' is parallel to the viewing direction");
    right = normalize(right);
    Vec3 up = cross(right, forward);
    c.eye = float4_of(desc.eye, 1.0f);
    c.right = float4_of(right);
    c.up = float4_of(up);
    c.forward = float4_of(forward);
    // fov is the full angle across the shorter image axis (pbrt's convention).
    float tan_half = std::tan(desc.fov_degrees * kPi / 360.0f);
    if (width >= height) {
        c.tan_half_height = tan_half;
        c.tan_half_width = tan_half * float(width) / float(height);
    } else {
        c.tan_half_width = tan_half;
        c.tan_half_height = tan_half * float(height) / float(width);
    }
    c.lens_radius = desc.lens_radius;
    c.focus_distance = desc.focus_distance;
    c.width = width;
    c.height = height;
    c.film_area = 4.0f * c.tan_half_width * c.tan_half_height;
    c.lens_area = desc.lens_radius > 0 ? kPi * desc.lens_radius * desc.lens_radius : 1.0f;
    return c;
}

std::vector<float> environment_distribution(const EnvironmentMap& map, EnvironmentSampling how) {
    const int w = map.width, h = map.height;
    std::vector<float> d(size_t(w) * h + size_t(h) * (w + 1) + (h + 1) + 1);
    float* func = d.data();
    float* cond = func + size_t(w) * h;
    float* marg = cond + size_t(h) * (w + 1);
    // sin(theta) at the row centre: the map's texels shrink toward the poles.
    std::vector<float> sin_theta(h);
    for (int y = 0; y < h; ++y) sin_theta[size_t(y)] = std::sin(kPi * (float(y) + 0.5f) / float(h));
    auto texel_luminance = [&](int x, int y) {
        const float* px = &map.rgb[(size_t(y) * w + x) * 3];
        return luminance({px[0], px[1], px[2]});
    };
    // The map's mean radiance over the sphere (texels weighted by their solid angle), which
    // compensation subtracts.
    float mean = 0;
    if (how == EnvironmentSampling::Compensated) {
        double sum = 0, weight = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                sum += double(texel_luminance(x, y)) * sin_theta[size_t(y)];
                weight += sin_theta[size_t(y)];
            }
        mean = weight > 0 ? float(sum / weight) : 0.0f;
    }
    double total = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            total += func[size_t(y) * w + x] = std::max(texel_luminance(x, y) - mean, 0.0f) * sin_theta[size_t(y)];
    // Every texel at the mean (a constant map, up to float rounding): nothing is brighter than
    // the rest, so it is sampled by luminance after all.
    if (total == 0 && mean > 0) return environment_distribution(map, EnvironmentSampling::Luminance);
    std::vector<float> row_integrals(h);
    for (int y = 0; y < h; ++y) {
        std::vector<float> row(func + size_t(y) * w, func + size_t(y + 1) * w);
        row_integrals[size_t(y)] = build_cdf(row, cond + size_t(y) * (w + 1)) / float(w);
    }
    float integral = build_cdf(row_integrals, marg) / float(h);
    marg[h + 1] = integral;
    // The CDFs' guides (cl/sampling.h), one entry per interval and one more.
    const size_t cond_offset = size_t(w) * h, marg_offset = cond_offset + size_t(h) * (w + 1);
    d.reserve(d.size() + size_t(h + 1) + size_t(h) * (w + 1));
    append_cdf_guide(d, marg_offset, h, h);
    for (int y = 0; y < h; ++y) append_cdf_guide(d, cond_offset + size_t(y) * (w + 1), w, w);
    return d;
}

namespace {

// The medium at point p (1 + index, 0 = vacuum), seen along a direction that no axis-aligned
// wall contains.
int medium_at(const DeviceScene& ds, int scene_medium, Vec3 p) {
    return medium_seen_along(ds, scene_medium, p, normalize(Vec3(0.3137f, 0.8712f, 0.3776f)));
}

}  // namespace

std::vector<Material> materials_in_use(const DeviceScene& scene) {
    std::vector<char> used(scene.materials.size(), 0);
    for (const TriangleInfo& info : scene.infos) used[size_t(info.material)] = 1;
    std::vector<Material> in_use;
    for (size_t m = 0; m < used.size(); ++m)
        if (used[m]) in_use.push_back(scene.materials[m]);
    return in_use;
}

bool material_is_specular(const Material& m) { return m.kind == MATERIAL_MIRROR || m.kind == MATERIAL_GLASS; }

bool has_specular_surfaces(const DeviceScene& scene) {
    const std::vector<Material> used = materials_in_use(scene);
    return std::any_of(used.begin(), used.end(), material_is_specular);
}

DeviceScene build_device_scene(const Scene& scene, int width, int height, EnvironmentSampling env_sampling) {
    DeviceScene ds;
    ds.env_sampling = env_sampling;
    Bvh bvh = build_bvh(scene.triangles);
    ds.bvh_build_seconds = bvh.build_seconds;
    ds.source_triangles = scene.triangles.size();
    ds.bvh_spatial_splits = bvh.spatial_splits;
    ds.nodes = std::move(bvh.nodes);
    ds.triangles = reorder(scene.triangles, bvh.order);
    store_triangle_normals(ds.triangles);
    ds.infos = reorder(scene.infos, bvh.order);
    ds.normals = scene.normals;
    if (!scene.uvs.empty()) ds.uvs = reorder(scene.uvs, bvh.order);
    ds.textures = scene.textures;
    ds.texels = scene.texels;
    ds.materials = scene.materials;
    ds.camera = make_camera(scene.camera, width, height);
    for (const MediumDesc& desc : scene.media) {
        Medium m{};
        m.sigma_a = float4_of(desc.sigma_a);
        m.sigma_s = float4_of(desc.sigma_s);
        m.sigma_t = float4_of(desc.sigma_a + desc.sigma_s);
        m.g = desc.g;
        m.grid_offset = -1;
        if (desc.density) {
            const DensityGrid& grid = *desc.density;
            m.grid_offset = int(ds.densities.size());
            ds.densities.insert(ds.densities.end(), grid.values.begin(), grid.values.end());
            for (int axis = 0; axis < 3; ++axis) {
                m.grid_size[axis] = grid.size[axis];
                m.world_to_grid[axis] = {{grid.world_to_grid[axis][0], grid.world_to_grid[axis][1],
                                          grid.world_to_grid[axis][2], grid.world_to_grid[axis][3]}};
            }
            const Vec3 sigma_t = desc.sigma_a + desc.sigma_s;
            m.majorant = grid.max_value() * std::max(sigma_t.x, std::max(sigma_t.y, sigma_t.z));
        }
        ds.media.push_back(m);
    }
    ds.info.camera_medium = medium_at(ds, scene.scene_medium, scene.camera.eye);

    Vec3 center = scene.bounds.center();
    float radius = 0.5f * length(scene.bounds.extent());
    if (!(radius > 0)) radius = 1.0f;
    ds.info.world_center = float4_of(center, radius);
    ds.info.environment_light = -1;

    std::vector<float> powers;
    // Light selection is proportional to power; for a textured emitter the texture's mean
    // luminance stands in for its mean over the triangle (any positive weight is unbiased:
    // the same probabilities serve sampling and MIS).
    std::map<int, float> texture_luminance;
    auto emission_scale = [&](const Material& m) {
        if (!m.ke_texture) return 1.0f;
        auto it = texture_luminance.find(m.ke_texture);
        if (it == texture_luminance.end()) it = texture_luminance.emplace(m.ke_texture, texture_mean_luminance(scene, m.ke_texture)).first;
        return it->second;
    };
    // Area lights: one per emissive triangle (one-sided, front = counter-clockwise). A triangle
    // that the BVH references more than once (spatial splits) is still one light: its other
    // copies name the same one.
    std::vector<int> light_of_triangle(scene.triangles.size(), -1);
    for (size_t i = 0; i < ds.triangles.size(); ++i) {
        TriangleInfo& info = ds.infos[i];
        info.light = -1;
        const Material& m = ds.materials[info.material];
        if (!is_emissive(m)) continue;
        int& light = light_of_triangle[bvh.order[i]];
        const bool first_copy = light < 0;
        if (first_copy) light = int(ds.lights.size());
        info.light = light;
        if (!first_copy) continue;
        const Triangle& t = ds.triangles[i];
        Vec3 e1 = vec3_of(t.p1) - vec3_of(t.p0), e2 = vec3_of(t.p2) - vec3_of(t.p0);
        Light l{};
        l.kind = LIGHT_AREA;
        l.triangle = int(i);
        l.emission = m.ke;
        l.area = 0.5f * length(cross(e1, e2));
        ds.lights.push_back(l);
        powers.push_back(luminance(vec3_of(m.ke)) * emission_scale(m) * l.area * kPi);
    }
    // The area lights come first (NEE_EVERY_LIGHT samples them as one group, cl/lights.h).
    ds.info.area_light_count = int(ds.lights.size());
    for (const LightDesc& desc : scene.lights) {
        Light l{};
        float power = 0;
        switch (desc.kind) {
        case LightDesc::Kind::Point:
            l.kind = LIGHT_POINT;
            l.medium = medium_at(ds, scene.scene_medium, desc.position);
            l.position = float4_of(desc.position, 1.0f);
            l.emission = float4_of(desc.color);
            power = 4.0f * kPi * luminance(desc.color);
            break;
        case LightDesc::Kind::Spot: {
            l.kind = LIGHT_SPOT;
            l.medium = medium_at(ds, scene.scene_medium, desc.position);
            l.position = float4_of(desc.position, 1.0f);
            Vec3 axis = desc.target - desc.position;
            if (!(length(axis) > 0)) throw Error(scene.path + ": spot light 'target' equals its 'position'");
            l.direction = float4_of(normalize(axis));
            l.emission = float4_of(desc.color);
            // 1 - cos = 2 sin^2(angle / 2), in double: exact for a cone of any width.
            auto one_minus_cos = [](double degrees) {
                const double s = std::sin(0.5 * degrees * 3.14159265358979323846 / 180.0);
                return 2.0 * s * s;
            };
            l.one_minus_cos_total = float(one_minus_cos(desc.cone_angle));
            l.one_minus_cos_falloff = float(one_minus_cos(desc.cone_angle - desc.cone_delta));
            if (!(l.one_minus_cos_total > 0.0f))
                throw Error(scene.path + ": spot light cone of " + std::to_string(desc.cone_angle) +
                            " degrees is too narrow to represent");
            // pbrt-v3: 2 pi (1 - (cos_falloff + cos_total) / 2).
            power = float(3.14159265358979323846 * (double(l.one_minus_cos_falloff) + l.one_minus_cos_total)) *
                    luminance(desc.color);
            break;
        }
        case LightDesc::Kind::Directional:
            if (scene.scene_medium != 0) throw Error(scene.path + ": a directional light cannot shine through the scene-wide medium");
            l.kind = LIGHT_DIRECTIONAL;
            if (!(length(desc.direction) > 0)) throw Error(scene.path + ": directional light has a zero 'direction'");
            l.direction = float4_of(normalize(desc.direction));
            l.emission = float4_of(desc.color);
            power = kPi * radius * radius * luminance(desc.color);
            break;
        case LightDesc::Kind::Environment: {
            if (scene.scene_medium != 0) throw Error(scene.path + ": an environment light cannot shine through the scene-wide medium");
            l.kind = LIGHT_ENVIRONMENT;
            l.emission = float4_of(desc.color);
            float mean = 1.0f;  // mean luminance of the map
            if (scene.environment_map.width > 0) {
                const EnvironmentMap& map = scene.environment_map;
                double sum = 0;
                for (size_t i = 0; i + 2 < map.rgb.size(); i += 3)
                    sum += luminance({map.rgb[i], map.rgb[i + 1], map.rgb[i + 2]});
                mean = float(sum / double(map.rgb.size() / 3));
            }
            power = kPi * radius * radius * luminance(desc.color) * mean;
            ds.info.environment_light = int(ds.lights.size());
            break;
        }
        }
        ds.lights.push_back(l);
        powers.push_back(power);
    }
    ds.light_cdf.assign(ds.lights.size() + 1, 0.0f);
    if (!ds.lights.empty()) {
        ds.light_power = powers;
        float total = build_cdf(powers, ds.light_cdf.data());
        for (size_t i = 0; i < ds.lights.size(); ++i) {
            ds.lights[i].select_pdf = total > 0 ? powers[i] / total : 1.0f / float(ds.lights.size());
            // A spot light, for a light sample from a point inside its cone: as bright there
            // as a point light of its intensity (cl/lights.h, sample_light_for_point).
            if (ds.lights[i].kind == LIGHT_SPOT)
                ds.lights[i].nee_weight = total > 0 ? 4.0f * kPi * luminance(vec3_of(ds.lights[i].emission)) / total
                                                    : ds.lights[i].select_pdf;
        }
    }
    append_cdf_guide(ds.light_cdf, 0, int(ds.lights.size()), int(ds.lights.size()));
    if (scene.environment_map.width > 0) {
        const EnvironmentMap& map = scene.environment_map;
        ds.env_texels.resize(size_t(map.width) * map.height);
        for (size_t i = 0; i < ds.env_texels.size(); ++i)
            ds.env_texels[i] = float4_of({map.rgb[i * 3], map.rgb[i * 3 + 1], map.rgb[i * 3 + 2]});
        ds.env_distribution = environment_distribution(map, env_sampling);
        ds.info.env_width = map.width;
        ds.info.env_height = map.height;
    }
    ds.info.light_count = int(ds.lights.size());
    ds.info.triangle_count = int(ds.triangles.size());
    ds.info.node_count = int(ds.nodes.size());
    ds.warnings = check_media_nesting(scene, ds);
    return ds;
}

}  // namespace clbdpt
