#include "runtime/assets/builtin_scenes.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "runtime/assets/splat_estimation.h"
#include "runtime/core/paths.h"

namespace sffd::assets {
namespace fs = std::filesystem;

namespace {

glm::vec3 hsv(float h, float s, float v) {
    const float c = v * s;
    const float hp = std::fmod(h * 6.0f, 6.0f);
    const float x = c * (1.0f - std::abs(std::fmod(hp, 2.0f) - 1.0f));
    glm::vec3 rgb(0.0f);
    if (hp < 1) rgb = {c, x, 0};
    else if (hp < 2) rgb = {x, c, 0};
    else if (hp < 3) rgb = {0, c, x};
    else if (hp < 4) rgb = {0, x, c};
    else if (hp < 5) rgb = {x, 0, c};
    else rgb = {c, 0, x};
    return rgb + glm::vec3(v - c);
}

std::uint32_t pack(glm::vec3 c) {
    auto q = [](float v) {
        return static_cast<std::uint32_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
    };
    return q(c.x) | (q(c.y) << 8) | (q(c.z) << 16) | (255u << 24);
}

}  // namespace

Image make_sphere_texture(int width, int height) {
    Image img;
    img.width = width;
    img.height = height;
    img.rgba8.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
    constexpr int cells_u = 16, cells_v = 8;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(width);
            const float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(height);
            const int cu = std::min(static_cast<int>(u * cells_u), cells_u - 1);
            const int cv = std::min(static_cast<int>(v * cells_v), cells_v - 1);
            // Latitude band colour on light cells, near-black on dark ones.
            const glm::vec3 band = hsv(static_cast<float>(cv) / cells_v, 0.75f, 0.95f);
            glm::vec3 c = ((cu + cv) % 2 == 0) ? band : glm::vec3(0.12f) + 0.15f * band;
            // Thin grid lines on every cell border; a thicker white prime meridian and equator.
            const float fu = u * cells_u - std::floor(u * cells_u),
                        fv = v * cells_v - std::floor(v * cells_v);
            const float line_u = 0.04f, line_v = 0.04f * cells_v / cells_u * 2.0f;
            if (fu < line_u || fu > 1.0f - line_u || fv < line_v || fv > 1.0f - line_v) c = glm::vec3(0.05f);
            if (std::abs(v - 0.5f) < 0.004f || u < 0.004f || u > 0.996f) c = glm::vec3(1.0f);
            const std::uint32_t p = pack(c);
            std::memcpy(&img.rgba8[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(x)) *
                                   4],
                        &p, 4);
        }
    }
    return img;
}

SplatCloud make_sphere_cloud(std::size_t n) {
    SplatCloud c;
    c.positions.resize(n);
    c.normals.resize(n);
    c.uvs.resize(n);
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (std::size_t i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(n);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * static_cast<double>(i);
        // Y up: the texture's v runs from the north pole (v = 0) to the south pole (v = 1).
        const glm::dvec3 p(r * std::cos(phi), z, r * std::sin(phi));
        c.positions[i] = glm::vec3(p);
        c.normals[i] = glm::vec3(glm::normalize(p));
        double lon = std::atan2(p.z, p.x);  // (-pi, pi]
        if (lon < 0) lon += 2.0 * std::numbers::pi;
        c.uvs[i] = glm::vec2(static_cast<float>(lon / (2.0 * std::numbers::pi)),
                             static_cast<float>(std::acos(std::clamp(z, -1.0, 1.0)) / std::numbers::pi));
    }
    // Every Fibonacci point stands for the same area 4 pi / n, so every splat gets one radius:
    // 0.8 * sqrt(4 pi / n), discs that overlap about twice. That closes the sphere (test
    // Radii.BuiltinSphereIsClosedAndAxesFollowTheTexture) and keeps it closed when a lattice stretches it 2x
    // (the Coverage render tests use the same spheres). The neighbour-distance estimate meant for scans
    // (estimate_radii) gave 1.3 * sqrt(4 pi / n) here: 2.6x the splat area to rasterise for no visible gain.
    const float radius = static_cast<float>(0.8 * std::sqrt(4.0 * std::numbers::pi / static_cast<double>(n)));
    const std::vector<float> radii(n, radius);
    c.axis_u.resize(n);
    c.axis_v.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 nrm = c.normals[i];
        glm::vec3 east = glm::cross(nrm, glm::vec3(0, 1, 0));  // direction of increasing longitude u
        east = glm::length(east) > 1e-4f ? glm::normalize(east) : glm::normalize(any_tangent(nrm));
        const glm::vec3 south = glm::normalize(glm::cross(nrm, east));
        c.axis_u[i] = east * radii[i];
        c.axis_v[i] = south * radii[i];
    }
    // uv frame: the gradients of u = longitude / 2 pi and v = colatitude / pi on the unit sphere (east / (2
    // pi sin(colatitude)) and south / pi) applied to the axes.
    c.uv_axes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 p(c.positions[i]);
        const double sin_colat = std::max(std::sqrt(p.x * p.x + p.z * p.z), 1e-6);
        const glm::dvec3 east = glm::dvec3(-p.z, 0.0, p.x) / sin_colat;
        const glm::dvec3 south = glm::cross(glm::dvec3(c.normals[i]), east);
        const glm::dvec3 grad_u = east / (2.0 * std::numbers::pi * sin_colat),
                         grad_v = south / std::numbers::pi;
        const glm::dvec3 au(c.axis_u[i]), av(c.axis_v[i]);
        c.uv_axes[i] = glm::vec4(float(glm::dot(grad_u, au)), float(glm::dot(grad_v, au)),
                                 float(glm::dot(grad_u, av)), float(glm::dot(grad_v, av)));
    }
    Image tex = make_sphere_texture();
    c.texture.width = tex.width;
    c.texture.height = tex.height;
    c.texture.rgba8 = std::move(tex.rgba8);
    c.texture.path = "";  // procedural
    // Per-splat colours too (the texel under each splat), for renderers or tools that ignore textures.
    c.colors.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const int x = std::clamp(static_cast<int>(c.uvs[i].x * static_cast<float>(c.texture.width)), 0,
                                 c.texture.width - 1);
        const int y = std::clamp(static_cast<int>(c.uvs[i].y * static_cast<float>(c.texture.height)), 0,
                                 c.texture.height - 1);
        std::memcpy(
            &c.colors[i],
            &c.texture.rgba8[(static_cast<std::size_t>(y) * static_cast<std::size_t>(c.texture.width) +
                              static_cast<std::size_t>(x)) *
                             4],
            4);
    }
    return c;
}

fs::path face_cache_path() { return paths::cache_dir() / "face.glb"; }

std::string fetch_script() {
    // The source tree's tools/ or an installed copy's <prefix>/share/splatffd/tools/ (tools/CMakeLists.txt
    // installs it): data_root() is the folder that holds both shaders/ and tools/.
    std::error_code ec;
    const fs::path script = paths::data_root() / "tools" / "fetch_content.sh";
    return fs::is_regular_file(script, ec) ? script.string()
                                           : std::string("tools/fetch_content.sh (in the source tree)");
}

Lattice make_box_lattice(const glm::dvec3& lo, const glm::dvec3& hi, glm::ivec3 div, LatticeBasis basis) {
    return make_lattice(
        lo, {glm::dvec3(hi.x - lo.x, 0, 0), glm::dvec3(0, hi.y - lo.y, 0), glm::dvec3(0, 0, hi.z - lo.z)},
        div, basis);
}

void add_default_view(ecs::Registry& r, const glm::dvec3& lo, const glm::dvec3& hi,
                      const glm::dvec3& view_dir) {
    const glm::dvec3 centre = 0.5 * (lo + hi);
    const double radius = std::max(0.5 * glm::length(hi - lo), 1e-6);
    const double fov = 40.0;
    // The bounding sphere fills ~90% of the view height (its corners may leave the frame; the object does
    // not).
    const double distance = radius / std::tan(glm::radians(fov) * 0.5) * 0.9;
    const ecs::Entity cam = r.create();
    r.emplace<Name>(cam, Name{"camera"});
    Camera c;
    c.target = centre;
    c.eye = centre + glm::normalize(view_dir) * distance;
    c.up = std::abs(glm::normalize(view_dir).y) > 0.95 ? glm::dvec3(0, 0, -1) : glm::dvec3(0, 1, 0);
    c.fov_y_degrees = static_cast<float>(fov);
    c.near_plane = static_cast<float>(std::max(distance - 4.0 * radius, distance * 0.01));
    c.far_plane = static_cast<float>(distance + 4.0 * radius);
    r.emplace<Camera>(cam, c);
    const ecs::Entity sun = r.create();
    r.emplace<Name>(sun, Name{"key light"});
    DirectionalLight d;
    const glm::dvec3 to_light = glm::normalize(glm::normalize(view_dir) + glm::dvec3(0.4, 0.8, 0.3));
    d.direction = glm::vec3(-to_light);
    r.emplace<DirectionalLight>(sun, d);
    const ecs::Entity amb = r.create();
    r.emplace<Name>(amb, Name{"ambient"});
    r.emplace<AmbientLight>(amb, AmbientLight{});
}

bool is_builtin_scene(const std::string& name) { return name == "sphere" || name == "face"; }

namespace {

ecs::Entity add_cloud_with_lattice(ecs::Registry& r, const std::string& name, SplatCloud cloud,
                                   const SplatMaterial& material, const glm::dvec3& view_dir) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : cloud.positions) {
        lo = glm::min(lo, cloud.origin + glm::dvec3(p));
        hi = glm::max(hi, cloud.origin + glm::dvec3(p));
    }
    // The lattice encloses the object with a 5% margin so outer splats stay inside [0,1]^3.
    const glm::dvec3 pad = 0.05 * (hi - lo);
    const ecs::Entity lat = r.create();
    r.emplace<Name>(lat, Name{name + ".lattice"});
    r.emplace<Transform>(lat, Transform{});
    r.emplace<Lattice>(lat, make_box_lattice(lo - pad, hi + pad, glm::ivec3(kBuiltinLatticeDivisions),
                                             LatticeBasis::bernstein));
    const ecs::Entity e = r.create();
    r.emplace<Name>(e, Name{name});
    r.emplace<Transform>(e, Transform{});
    r.emplace<SplatCloud>(e, std::move(cloud));
    r.emplace<SplatMaterial>(e, material);
    r.emplace<Deformers>(e, Deformers{{lat}});
    add_default_view(r, lo - pad, hi + pad, view_dir);
    return e;
}

}  // namespace

Status load_builtin_scene(ecs::Registry& r, const std::string& name) {
    if (name == "sphere") {
        const ecs::Entity sphere = add_cloud_with_lattice(r, "sphere", make_sphere_cloud(), SplatMaterial{},
                                                          glm::dvec3(0.35, 0.3, 1.0));
        // make_sphere_cloud samples the unit sphere at the origin: the ground-truth renderer traces it.
        r.emplace<ExactSphere>(sphere, ExactSphere{});
        return {};
    }
    if (name == "face") {
        const fs::path cache = face_cache_path();
        std::error_code ec;
        if (!fs::exists(cache, ec))
            return make_error("face: the face scan is not in the content cache (" + cache.string() +
                              "); run " + fetch_script() + " once to download and convert it");
        SplatMaterial material;
        auto cloud = import_splat_cloud(cache, {}, &material);
        if (!cloud)
            return make_error("face: " + cloud.message() + " (run " + fetch_script() +
                              " again to rebuild the cache)");
        if (cloud->size() != kFaceSplats)
            return make_error("face: " + cache.string() + " has " + std::to_string(cloud->size()) +
                              " splats, expected " + std::to_string(kFaceSplats) + "; run " + fetch_script() +
                              " again");
        add_cloud_with_lattice(r, "face", std::move(*cloud), material, glm::dvec3(0.25, 0.1, 1.0));
        return {};
    }
    return make_error(name + ": not a built-in scene (built-ins: sphere, face)");
}

}  // namespace sffd::assets
