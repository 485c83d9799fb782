// Ground-truth ray tracer (see ground_truth.h). Embree stays in this file.
#include "systems/splat_render/ground_truth.h"
#include "systems/splat_render/nearest_point.h"
#include "systems/splat_render/texture_lookup.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/splat_render/camera_math.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"
#include "systems/splat_render/splat_pack.h"

namespace sffd::render {

namespace {

double srgb_decode(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// d(u, v) of sphere_uv for a displacement dp of the unit direction d (the radial part of dp is ignored to
// first order by the formulas below).
glm::dvec2 sphere_uv_differential(const glm::dvec3& d, const glm::dvec3& dp) {
    const double rxz2 = std::max(d.x * d.x + d.z * d.z, 1e-300);
    const double dlon = (d.x * dp.z - d.z * dp.x) / rxz2;
    const double dcolat = -dp.y / std::sqrt(rxz2);
    return {dlon / (2.0 * std::numbers::pi), dcolat / std::numbers::pi};
}

// Where the ray o + t*dir meets the plane through p with normal n (t may be any sign); nullopt if parallel.
std::optional<glm::dvec3> ray_plane(const glm::dvec3& o, const glm::dvec3& dir, const glm::dvec3& p,
                                    const glm::dvec3& n) {
    const double den = glm::dot(dir, n);
    if (std::abs(den) < 1e-12) return std::nullopt;
    return o + dir * (glm::dot(p - o, n) / den);
}

// One surface hit: world position, unit normal (oriented towards the ray origin's side as the surface's
// outward normal), the rest point on the sphere as a unit direction, and the linear map from a world
// displacement on the tangent plane at the hit to the rest displacement (identity at rest).
struct Hit {
    glm::dvec3 position{0.0}, normal{0.0}, rest_dir{0.0};
    glm::dmat3 to_rest{1.0};
    // Mesh hits: uv, and the triangle's uv gradients (a world displacement dq in its plane moves uv by
    // (grad_u . dq, grad_v . dq)).
    bool mesh = false;
    glm::dvec3 rest_point{0.0};  // the hit's rest point in the world (mesh hits; the sphere's: rest_dir)
    glm::dvec2 uv{0.0};
    glm::dvec3 grad_u{0.0}, grad_v{0.0};
};

// One Embree triangle scene (device, scene, one geometry), built once from float vertices relative to a
// centre of the caller's choice (precision far from the origin) and 3 indices per triangle.
class EmbreeTriangles {
public:
    EmbreeTriangles() = default;
    ~EmbreeTriangles() {
        if (scene_) rtcReleaseScene(scene_);
        if (device_) rtcReleaseDevice(device_);
    }
    EmbreeTriangles(const EmbreeTriangles&) = delete;
    EmbreeTriangles& operator=(const EmbreeTriangles&) = delete;

    // Empty on success, else the message.
    std::string build(const std::vector<glm::vec3>& pos, const std::vector<std::uint32_t>& tris) {
        device_ = rtcNewDevice(nullptr);
        if (!device_) return "render_reference(): rtcNewDevice failed";
        scene_ = rtcNewScene(device_);
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), pos.size()));
        for (std::size_t i = 0; i < pos.size(); ++i)
            v[3 * i] = pos[i].x, v[3 * i + 1] = pos[i].y, v[3 * i + 2] = pos[i].z;
        auto* idx = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), tris.size() / 3));
        std::copy(tris.begin(), tris.end(), idx);
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
        rtcCommitScene(scene_);
        return {};
    }

    // The nearest hit of the ray o + t dir (o relative to the vertices' centre), if any.
    std::optional<RTCRayHit> intersect(const glm::dvec3& o, const glm::dvec3& dir) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        rh.ray.org_x = float(o.x), rh.ray.org_y = float(o.y), rh.ray.org_z = float(o.z);
        rh.ray.dir_x = float(dir.x), rh.ray.dir_y = float(dir.y), rh.ray.dir_z = float(dir.z);
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
        return rh;
    }

private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
};

// An ExactMesh in world space through Embree. Deformed by lattices (F the lattices in order), each
// triangle is traced as a k x k subdivision whose vertices are F of the rest points (positions and
// normals through ffd::deform), as the deformed sphere is; a hit's rest point is the barycentric mix of the
// sub-triangle's rest points, its uv the parent triangle's affine map there, and the uv gradient the
// parent's pulled through the sub-triangle's world -> rest map.
class MeshTracer {
public:
    MeshTracer(const ExactMesh& mesh, const glm::dmat4& model, const std::vector<Lattice>& lattices,
               const ReferenceSettings& settings)
        : mesh_(mesh) {
        const std::size_t nv = mesh.positions.size(), nt = mesh.triangles.size() / 3;
        if (nt == 0 || nv == 0) {
            error_ = "render_reference(): the exact mesh has no triangles";
            return;
        }
        for (std::uint32_t i : mesh.triangles)
            if (i >= nv) {
                error_ = "render_reference(): the exact mesh has a triangle index out of range";
                return;
            }
        world_.resize(nv);
        centre_ = glm::dvec3(0.0);
        for (std::size_t i = 0; i < nv; ++i)
            world_[i] = glm::dvec3(model * glm::dvec4(mesh.positions[i], 1.0)), centre_ += world_[i];
        centre_ /= double(nv);  // float vertices relative to the mesh's centre keep precision far from 0
        const glm::dmat3 nm = glm::transpose(glm::inverse(glm::dmat3(model)));
        std::vector<glm::dvec3> normals;
        if (mesh.normals.size() == nv) {
            normals.resize(nv);
            for (std::size_t i = 0; i < nv; ++i) normals[i] = nm * glm::dvec3(mesh.normals[i]);
        }
        grad_u_.resize(nt), grad_v_.resize(nt);
        const bool uv = mesh.uvs.size() == nv;
        for (std::size_t t = 0; t < nt; ++t) {
            // The triangle's affine uv map: grad = a e1 + b e2 with grad . e1 = du1, grad . e2 = du2.
            const std::uint32_t* tri = &mesh.triangles[3 * t];
            const glm::dvec3 e1 = world_[tri[1]] - world_[tri[0]], e2 = world_[tri[2]] - world_[tri[0]];
            const double g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2),
                         det = g11 * g22 - g12 * g12;
            if (!uv || !(det > 1e-24 * g11 * g22)) continue;
            const glm::dvec2 d1 = glm::dvec2(mesh.uvs[tri[1]]) - glm::dvec2(mesh.uvs[tri[0]]);
            const glm::dvec2 d2 = glm::dvec2(mesh.uvs[tri[2]]) - glm::dvec2(mesh.uvs[tri[0]]);
            auto solve = [&](double r1, double r2) {
                return ((g22 * r1 - g12 * r2) / det) * e1 + ((g11 * r2 - g12 * r1) / det) * e2;
            };
            grad_u_[t] = solve(d1.x, d2.x);
            grad_v_[t] = solve(d1.y, d2.y);
        }
        // Traced triangles: the mesh's own at rest; k x k sub-triangles per triangle when deformed (k so
        // that all of them stay within about mesh_subdivision_budget).
        deformed_ = !lattices.empty();
        const int k =
            deformed_
                ? std::clamp(int(std::sqrt(double(std::max(settings.mesh_triangle_budget, 1)) / double(nt))),
                             1, 256)
                : 1;
        const std::size_t per = std::size_t(k + 1) * std::size_t(k + 2) / 2;
        rest_.reserve(nt * per);
        std::vector<glm::vec3> pos, nrm;
        pos.reserve(nt * per), nrm.reserve(nt * per);
        for (std::size_t t = 0; t < nt; ++t) {
            const std::uint32_t* tri = &mesh.triangles[3 * t];
            const glm::dvec3 a = world_[tri[0]], b = world_[tri[1]], c = world_[tri[2]];
            const glm::dvec3 face = glm::cross(b - a, c - a);
            const glm::dvec3 fn = glm::length(face) > 0.0 ? glm::normalize(face) : glm::dvec3(0, 0, 1);
            const std::uint32_t base = std::uint32_t(rest_.size());
            auto local = [&](int i, int j) {
                return base + std::uint32_t(i * (k + 1) - i * (i - 1) / 2 + j);
            };  // row i holds k + 1 - i points
            for (int i = 0; i <= k; ++i)
                for (int j = 0; j <= k - i; ++j) {
                    const double bu = double(i) / k, bv = double(j) / k, bw = 1.0 - bu - bv;
                    const glm::dvec3 p = bw * a + bu * b + bv * c;
                    glm::dvec3 n = fn;
                    if (!normals.empty()) {
                        const glm::dvec3 m =
                            bw * normals[tri[0]] + bu * normals[tri[1]] + bv * normals[tri[2]];
                        if (glm::length(m) > 1e-12) n = glm::normalize(m);
                    }
                    rest_.push_back(p);
                    pos.emplace_back(p - centre_);
                    nrm.emplace_back(n);
                }
            for (int i = 0; i < k; ++i)
                for (int j = 0; j < k - i; ++j) {
                    tris_.insert(tris_.end(), {local(i, j), local(i + 1, j), local(i, j + 1)});
                    parent_.push_back(std::uint32_t(t));
                    if (j + 1 <= k - i - 1) {
                        tris_.insert(tris_.end(), {local(i + 1, j), local(i + 1, j + 1), local(i, j + 1)});
                        parent_.push_back(std::uint32_t(t));
                    }
                }
        }
        for (const Lattice& l : lattices) {
            const ffd::PointsIn in{pos.data(), nrm.data(), nullptr, nullptr, pos.size(), centre_};
            const ffd::PointsOut out{pos.data(), nrm.data(), nullptr, nullptr};
            if (auto st = ffd::deform(l, in, out); !st) {
                error_ = st.message();
                return;
            }
        }
        positions_.resize(pos.size());
        for (std::size_t i = 0; i < pos.size(); ++i) positions_[i] = centre_ + glm::dvec3(pos[i]);
        normals_.assign(nrm.begin(), nrm.end());
        smooth_ = !normals.empty() || deformed_;  // else each triangle's own (flat) normal
        error_ = rtc_.build(pos, tris_);
    }

    const std::string& error() const { return error_; }

    std::optional<Hit> trace(const glm::dvec3& origin, const glm::dvec3& dir) const {
        const std::optional<RTCRayHit> found = rtc_.intersect(origin - centre_, dir);
        if (!found) return std::nullopt;
        const RTCRayHit& rh = *found;
        const std::size_t s = rh.hit.primID, t = parent_[s];
        const std::uint32_t* tri = &tris_[3 * s];
        const double bu = rh.hit.u, bv = rh.hit.v, bw = 1.0 - bu - bv;
        const glm::dvec3 a = positions_[tri[0]], b = positions_[tri[1]], c = positions_[tri[2]];
        Hit h;
        h.mesh = true;
        // The hit from the barycentrics in double precision (the float t is enough to find the triangle).
        h.position = bw * a + bu * b + bv * c;
        const glm::dvec3 face = glm::cross(b - a, c - a);
        h.normal = glm::length(face) > 0.0 ? glm::normalize(face) : -glm::normalize(dir);
        if (smooth_) {
            const glm::dvec3 n = bw * normals_[tri[0]] + bu * normals_[tri[1]] + bv * normals_[tri[2]];
            if (glm::length(n) > 1e-12) h.normal = glm::normalize(n);
        }
        // uv: the parent triangle's affine map at the rest point.
        const glm::dvec3 ra = rest_[tri[0]], rb = rest_[tri[1]], rc = rest_[tri[2]];
        const glm::dvec3 rest = bw * ra + bu * rb + bv * rc;
        h.rest_point = rest;
        const std::uint32_t corner = mesh_.triangles[3 * t];
        if (mesh_.uvs.size() == mesh_.positions.size())
            h.uv = glm::dvec2(mesh_.uvs[corner]) + glm::dvec2(glm::dot(grad_u_[t], rest - world_[corner]),
                                                              glm::dot(grad_v_[t], rest - world_[corner]));
        h.grad_u = grad_u_[t], h.grad_v = grad_v_[t];
        if (deformed_) {
            // World -> rest on the sub-triangle (the FFD is affine at its scale): dq = x e1 + y e2 (+ gn,
            // dropped) -> dp = x f1 + y f2; the uv change grad . dp = (M^T grad) . dq.
            const glm::dvec3 e1 = b - a, e2 = c - a, gn = glm::cross(e1, e2);
            glm::dmat3 m(0.0);
            if (glm::dot(gn, gn) > 0.0)
                m = glm::dmat3(rb - ra, rc - ra, glm::dvec3(0.0)) * glm::inverse(glm::dmat3(e1, e2, gn));
            h.grad_u = glm::transpose(m) * grad_u_[t];
            h.grad_v = glm::transpose(m) * grad_v_[t];
        }
        return h;
    }

private:
    const ExactMesh& mesh_;
    std::vector<glm::dvec3> world_, grad_u_, grad_v_;     // rest vertices (world), per-triangle uv gradients
    std::vector<glm::dvec3> rest_, positions_, normals_;  // traced vertices: rest, deformed, normals
    std::vector<std::uint32_t> tris_, parent_;            // traced triangles and the mesh triangle of each
    glm::dvec3 centre_{0.0};
    bool deformed_ = false, smooth_ = false;
    EmbreeTriangles rtc_;
    std::string error_;
};

// The deformed sphere: Embree scene over the tessellation, with the rest points and FFD normals.
class DeformedSphere {
public:
    DeformedSphere(const ReferenceScene& scene, const ReferenceSettings& settings) : scene_(scene) {
        const int nu = std::max(settings.longitude_steps, 8), nv = std::max(settings.colatitude_steps, 4);
        cols_ = nu + 1;
        const std::size_t count = std::size_t(nu + 1) * std::size_t(nv + 1);
        rest_.resize(count);
        std::vector<glm::vec3> pos(count), nrm(count);
        for (int j = 0; j <= nv; ++j)
            for (int i = 0; i <= nu; ++i) {
                const double lon = 2.0 * std::numbers::pi * i / nu, colat = std::numbers::pi * j / nv;
                const glm::dvec3 d(std::sin(colat) * std::cos(lon), std::cos(colat),
                                   std::sin(colat) * std::sin(lon));
                const std::size_t k = std::size_t(j) * std::size_t(cols_) + std::size_t(i);
                rest_[k] = d;
                pos[k] = glm::vec3(d * scene.radius);  // relative to the sphere centre (the deform origin)
                nrm[k] = glm::vec3(d);
            }
        for (const Lattice& l : scene.lattices) {
            const ffd::PointsIn in{pos.data(), nrm.data(), nullptr, nullptr, count, scene.center};
            const ffd::PointsOut out{pos.data(), nrm.data(), nullptr, nullptr};
            auto st = ffd::deform(l, in, out);
            if (!st) {
                error_ = st.message();
                return;
            }
        }
        normals_ = std::move(nrm);
        const std::size_t tris = std::size_t(nu) * std::size_t(nv) * 2;
        indices_.resize(3 * tris);
        std::uint32_t* idx = indices_.data();
        std::size_t t = 0;
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const auto a = std::uint32_t(j * cols_ + i), b = a + 1, c = a + std::uint32_t(cols_),
                           d = c + 1;
                idx[3 * t] = a, idx[3 * t + 1] = c, idx[3 * t + 2] = b, ++t;
                idx[3 * t] = b, idx[3 * t + 1] = c, idx[3 * t + 2] = d, ++t;
            }
        error_ = rtc_.build(pos, indices_);
        if (!error_.empty()) return;
        positions_ = std::move(pos);
    }

    const std::string& error() const { return error_; }

    std::optional<Hit> trace(const glm::dvec3& origin, const glm::dvec3& dir) const {
        const std::optional<RTCRayHit> found = rtc_.intersect(origin - scene_.center, dir);
        if (!found) return std::nullopt;
        const RTCRayHit& rh = *found;
        const std::uint32_t* tri = &indices_[3 * std::size_t(rh.hit.primID)];
        const double bu = rh.hit.u, bv = rh.hit.v, bw = 1.0 - bu - bv;
        Hit h;
        h.position = origin + dir * double(rh.ray.tfar);
        const glm::dvec3 ra = rest_[tri[0]], rb = rest_[tri[1]], rc = rest_[tri[2]];
        h.rest_dir = glm::normalize(bw * ra + bu * rb + bv * rc);
        h.normal = glm::normalize(bw * glm::dvec3(normals_[tri[0]]) + bu * glm::dvec3(normals_[tri[1]]) +
                                  bv * glm::dvec3(normals_[tri[2]]));
        // Tangent-plane map world -> rest from the triangle's edges (the FFD is affine at this scale).
        const glm::dvec3 pa = positions_[tri[0]], pb = positions_[tri[1]], pc = positions_[tri[2]];
        const glm::dvec3 e1 = pb - pa, e2 = pc - pa, f1 = rb - ra, f2 = rc - ra;  // unit directions
        const glm::dvec3 gn = glm::cross(e1, e2);
        if (glm::dot(gn, gn) > 0.0) {
            // dq = a e1 + b e2 (+ gn, dropped) -> dp = a f1 + b f2: [f1 f2 0] * inverse([e1 e2 gn]).
            h.to_rest = glm::dmat3(f1, f2, glm::dvec3(0.0)) * glm::inverse(glm::dmat3(e1, e2, gn));
        } else {
            h.to_rest = glm::dmat3(0.0);  // pole triangle (degenerate): no uv derivative
        }
        return h;
    }

private:
    const ReferenceScene& scene_;
    int cols_ = 0;
    std::vector<glm::dvec3> rest_;
    std::vector<glm::vec3> positions_, normals_;
    std::vector<std::uint32_t> indices_;
    EmbreeTriangles rtc_;
    std::string error_;
};

std::optional<Hit> trace_sphere(const ReferenceScene& scene, const glm::dvec3& origin,
                                const glm::dvec3& dir) {
    const glm::dvec3 oc = origin - scene.center;
    const double a = glm::dot(dir, dir), b = glm::dot(oc, dir),
                 c = glm::dot(oc, oc) - scene.radius * scene.radius;
    const double disc = b * b - a * c;
    if (disc < 0.0) return std::nullopt;
    const double sq = std::sqrt(disc);
    double t = (-b - sq) / a;
    if (t <= 0.0) t = (-b + sq) / a;
    if (t <= 0.0) return std::nullopt;
    Hit h;
    h.position = origin + dir * t;
    h.normal = glm::normalize(h.position - scene.center);
    h.rest_dir = h.normal;
    h.to_rest = glm::dmat3(1.0 / scene.radius);  // a world displacement is a displacement of d times 1/r
    return h;
}

}  // namespace

glm::dvec2 sphere_uv(const glm::dvec3& d) {
    double lon = std::atan2(d.z, d.x);
    if (lon < 0.0) lon += 2.0 * std::numbers::pi;
    return {lon / (2.0 * std::numbers::pi), std::acos(std::clamp(d.y, -1.0, 1.0)) / std::numbers::pi};
}

ReferenceTexture::ReferenceTexture(const SplatTexture& m) {
    if (m.width <= 0 || m.height <= 0 || m.rgba8.size() < std::size_t(m.width) * std::size_t(m.height) * 4)
        return;
    Level base;
    base.width = m.width, base.height = m.height;
    base.texels.resize(std::size_t(base.width) * std::size_t(base.height));
    std::array<float, 256> lut{};
    for (int i = 0; i < 256; ++i) lut[std::size_t(i)] = float(srgb_decode(i / 255.0));
    for (std::size_t k = 0; k < base.texels.size(); ++k) {
        const std::uint8_t* p = &m.rgba8[4 * k];
        base.texels[k] = glm::vec4(lut[p[0]], lut[p[1]], lut[p[2]], float(p[3]) / 255.0f);
    }
    levels_.push_back(std::move(base));
    while (levels_.back().width > 1 || levels_.back().height > 1) {
        const Level& prev = levels_.back();
        Level next;
        const glm::ivec2 size = next_level_size({prev.width, prev.height});
        next.width = size.x, next.height = size.y;
        next.texels.resize(std::size_t(next.width) * std::size_t(next.height));
        const auto texel = [&](int tx, int ty) {
            return prev.texels[std::size_t(ty) * std::size_t(prev.width) + std::size_t(tx)];
        };
        for (int y = 0; y < next.height; ++y)
            for (int x = 0; x < next.width; ++x)
                next.texels[std::size_t(y) * std::size_t(next.width) + std::size_t(x)] =
                    mean_2x2(x, y, prev.width, prev.height, texel);
        levels_.push_back(std::move(next));
    }
}

glm::dvec4 ReferenceTexture::bilinear(const glm::dvec2& uv, int level) const {
    const Level& l = levels_[std::size_t(std::clamp(level, 0, int(levels_.size()) - 1))];
    const BilinearTaps<double> b = bilinear_taps(uv.x, uv.y, l.width, l.height);
    auto t = [&](int tx, int ty) {
        return glm::dvec4(l.texels[std::size_t(ty) * std::size_t(l.width) + std::size_t(tx)]);
    };
    return glm::mix(glm::mix(t(b.x0, b.y0), t(b.x1, b.y0), b.ax),
                    glm::mix(t(b.x0, b.y1), t(b.x1, b.y1), b.ax), b.ay);
}

glm::dvec4 ReferenceTexture::anisotropic(const glm::dvec2& uv, const glm::dvec2& dx, const glm::dvec2& dy,
                                         int max_probes) const {
    const glm::dvec2 size(levels_[0].width, levels_[0].height);
    const double lx = glm::length(dx * size), ly = glm::length(dy * size);
    const double major = std::max(lx, ly), minor = std::min(lx, ly);
    if (!(minor > 0.0) || major <= 1.0) return trilinear(uv, dx, dy);
    const int n = std::clamp(int(std::ceil(major / minor)), 1, std::max(max_probes, 1));
    if (n == 1) return trilinear(uv, dx, dy);
    // n trilinear probes spread over the footprint's major axis, each filtering major / n (EXT_texture_
    // filter_anisotropic's model; GL leaves the exact probe placement to the implementation).
    const glm::dvec2 axis = lx >= ly ? dx : dy;
    const glm::dvec2 step = axis / double(n), other = (lx >= ly ? dy : dx);
    glm::dvec4 sum(0.0);
    for (int i = 0; i < n; ++i) sum += trilinear(uv + axis * ((i + 0.5) / n - 0.5), step, other);
    return sum / double(n);
}

glm::dvec4 ReferenceTexture::trilinear(const glm::dvec2& uv, const glm::dvec2& dx,
                                       const glm::dvec2& dy) const {
    const glm::dvec2 size(levels_[0].width, levels_[0].height);
    const double rho = std::max(glm::length(dx * size), glm::length(dy * size));
    const double lambda = rho > 0.0 ? std::log2(rho) : -1.0;  // NaN derivatives: level 0
    const LevelBlend<double> b = trilinear_levels(lambda, int(levels_.size()) - 1);
    const glm::dvec4 lo = bilinear(uv, b.lo);
    return b.hi == b.lo ? lo : glm::mix(lo, bilinear(uv, b.hi), b.f);
}

glm::dvec3 shade_reference(const ReferenceLights& lights, const glm::dvec3& albedo, const glm::dvec3& n,
                           const glm::dvec3& to_eye, double specular, double shininess) {
    glm::dvec3 color = lights.ambient * albedo;
    for (std::size_t i = 0; i < lights.to_light.size(); ++i) {
        const glm::dvec3 l = lights.to_light[i];
        const double ndl = std::max(glm::dot(n, l), 0.0);
        const glm::dvec3 h = glm::normalize(l + to_eye);
        const double spec = ndl > 0.0 ? std::pow(std::max(glm::dot(n, h), 1e-8), shininess) * specular : 0.0;
        color += lights.color[i] * (albedo * ndl + glm::dvec3(spec));
    }
    return color;
}

ReferenceLights scene_lights(const ecs::Registry& reg) {
    ReferenceLights out;
    bool has_ambient = false;
    reg.view<const DirectionalLight>().each([&](const DirectionalLight& l) {
        if (out.to_light.size() >= 4) return;  // SFFD_MAX_LIGHTS
        out.to_light.push_back(-glm::normalize(glm::dvec3(glm::vec3(glm::normalize(l.direction)))));
        out.color.push_back(glm::dvec3(l.color * l.intensity));
    });
    reg.view<const AmbientLight>().each([&](const AmbientLight& a) {
        out.ambient += glm::dvec3(a.color * a.intensity);
        has_ambient = true;
    });
    if (out.to_light.empty() && !has_ambient) {
        const DirectionalLight l;
        const AmbientLight a;
        out.to_light.push_back(-glm::normalize(glm::dvec3(l.direction)));
        out.color.push_back(glm::dvec3(l.color * l.intensity));
        out.ambient = glm::dvec3(a.color * a.intensity);
    }
    return out;
}

Result<ReferenceScene> reference_scene(const ecs::Registry& reg, int width, int height) {
    if (width < 1 || height < 1) return make_error("reference_scene(): empty image size");
    ReferenceScene s;
    s.width = width, s.height = height;
    const SplatCloud* cloud = nullptr;
    std::string problem;
    reg.view<const SplatCloud, const ExactSphere>().each(
        [&](ecs::Entity e, const SplatCloud& c, const ExactSphere& sphere) {
            if (cloud) return;
            cloud = &c;
            const Transform* t = reg.try_get<Transform>(e);
            const glm::dmat4 m = model_matrix(t, c.origin);
            if (glm::dmat3(m) != glm::dmat3(1.0))
                problem = "the sphere's Transform rotates or scales it (not supported)";
            s.center = glm::dvec3(m * glm::dvec4(sphere.center, 1.0));
            s.radius = sphere.radius;
            s.texture = &c.texture;
            if (const SplatMaterial* mat = reg.try_get<SplatMaterial>(e)) s.material = *mat;
            // The sphere is traced in the world: each lattice placed there by its own Transform.
            if (const Deformers* d = reg.try_get<Deformers>(e))
                for (ecs::Entity l : d->lattices)
                    if (reg.valid(l) && reg.has<Lattice>(l)) {
                        const Lattice& lat = reg.get<Lattice>(l);
                        const glm::dmat4 world = model_matrix(reg.try_get<Transform>(l));
                        if (ffd::moved_count(lat) > 0) s.lattices.push_back(ffd::map_lattice(lat, world));
                    }
        });
    if (!cloud) {
        reg.view<const SplatCloud, const ExactMesh>().each(
            [&](ecs::Entity e, const SplatCloud& c, const ExactMesh& mesh) {
                if (cloud) return;
                cloud = &c;
                s.mesh = &mesh;
                s.mesh_model = model_matrix(reg.try_get<Transform>(e), c.origin);
                s.texture = &c.texture;
                if (const SplatMaterial* mat = reg.try_get<SplatMaterial>(e)) s.material = *mat;
                if (c.texture.rgba8.empty() && c.colors.size() == c.size() && c.size() > 0)
                    problem =
                        "the mesh's colours are baked per splat (vertex colours, or a tinted or "
                        "multi-texture material): "
                        "no texture to trace";
                // The mesh is deformed in its own space (mesh_model maps it to the world): each lattice
                // mapped there from its own frame, as the splats' deformation does (lattice_frame.h).
                const glm::dmat4 to_mesh = glm::inverse(s.mesh_model);
                if (const Deformers* d = reg.try_get<Deformers>(e))
                    for (ecs::Entity l : d->lattices)
                        if (reg.valid(l) && reg.has<Lattice>(l)) {
                            const Lattice& lat = reg.get<Lattice>(l);
                            if (ffd::moved_count(lat) > 0)
                                s.lattices.push_back(
                                    ffd::map_lattice(lat, to_mesh * model_matrix(reg.try_get<Transform>(l))));
                        }
            });
    }
    if (!cloud)
        return make_error(
            "reference_scene(): no point cloud with an exact surface (ExactSphere or ExactMesh) in the "
            "scene");
    if (!problem.empty()) return make_error("reference_scene(): " + problem);
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) {
        if (&c != cloud) return;
        // Hidden and deleted points: their part of the surface is not traced (ReferenceScene::point_gone).
        const PointFlags* flags = reg.try_get<PointFlags>(e);
        if (!any_point_flagged(flags, c.size(), kPointGone)) return;
        const glm::dmat4 m = model_matrix(reg.try_get<Transform>(e), c.origin);
        s.point_rest.resize(c.size());
        s.point_gone.resize(c.size());
        for (std::size_t i = 0; i < c.size(); ++i) {
            s.point_rest[i] = glm::dvec3(m * glm::dvec4(glm::dvec3(c.positions[i]), 1.0));
            s.point_gone[i] = (flags->bits[i] & kPointGone) != 0 ? 1 : 0;
        }
    });
    const double aspect = double(width) / double(height);
    const Camera cam = scene_camera(reg, aspect);
    s.view = view_matrix(cam);
    s.projection = projection_matrix(cam, aspect);
    s.lights = scene_lights(reg);
    return s;
}

Result<FrameImage> render_reference(const ReferenceScene& scene, const ReferenceSettings& settings) {
    if (scene.width < 1 || scene.height < 1 || !scene.texture)
        return make_error("render_reference(): incomplete scene");
    std::optional<DeformedSphere> deformed;
    std::optional<MeshTracer> mesh;
    if (scene.mesh) {
        mesh.emplace(*scene.mesh, scene.mesh_model, scene.lattices, settings);
        if (!mesh->error().empty()) return make_error(mesh->error());
    } else if (!scene.lattices.empty()) {
        deformed.emplace(scene, settings);
        if (!deformed->error().empty()) return make_error(deformed->error());
    }
    const ReferenceTexture texture(*scene.texture);
    const glm::dvec3 base = glm::dvec3(glm::vec3(scene.material.base_color));
    const double specular = scene.material.specular, shininess = scene.material.shininess;
    const glm::dmat4 inv_view = glm::inverse(scene.view);
    const glm::dvec3 eye = glm::dvec3(inv_view[3]);
    const glm::dmat3 to_world(inv_view);
    const double p00 = scene.projection[0][0], p11 = scene.projection[1][1];
    const int w = scene.width, h = scene.height;
    // World direction of the ray through window position (wx, wy) (GL: origin bottom-left, pixel centres
    // at +0.5), scaled so its view-space z is -1.
    auto ray_dir = [&](double wx, double wy) {
        const double nx = 2.0 * wx / w - 1.0, ny = 2.0 * wy / h - 1.0;
        return to_world * glm::dvec3(nx / p00, ny / p11, -1.0);
    };
    // A surface point whose nearest rest splat is hidden or deleted is not there (the splats draw a hole).
    const NearestPoint splats =
        scene.point_gone.size() == scene.point_rest.size() ? NearestPoint(scene.point_rest) : NearestPoint();
    auto trace = [&](const glm::dvec3& dir) {
        std::optional<Hit> hit = mesh       ? mesh->trace(eye, dir)
                                 : deformed ? deformed->trace(eye, dir)
                                            : trace_sphere(scene, eye, dir);
        if (hit && !splats.empty()) {
            const std::size_t k =
                splats.nearest(hit->mesh ? hit->rest_point : scene.center + scene.radius * hit->rest_dir);
            if (k < scene.point_gone.size() && scene.point_gone[k]) hit.reset();
        }
        return hit;
    };
    auto hit_uv = [](const Hit& hit) { return hit.mesh ? hit.uv : sphere_uv(hit.rest_dir); };
    auto shade = [&](const Hit& hit, const glm::dvec3& dir, const glm::dvec4& tex) {
        const glm::dvec3 albedo = texture.empty() ? base : glm::dvec3(tex);
        return shade_reference(scene.lights, albedo, hit.normal, -glm::normalize(dir), specular, shininess);
    };

    FrameImage img;
    img.width = w, img.height = h;
    const std::size_t n = std::size_t(w) * std::size_t(h);
    img.color.assign(n, glm::vec4(0.0f));
    img.depth.assign(n, std::numeric_limits<float>::infinity());
    img.normal.assign(n, glm::vec3(0.0f));
    const glm::dvec3 view_axis = -glm::dvec3(inv_view[2]);
    const int ss = std::max(settings.supersample, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y) {
            const double wy = double(h - 1 - y) + 0.5;
            for (int x = 0; x < w; ++x) {
                const double wx = double(x) + 0.5;
                const glm::dvec3 dir = ray_dir(wx, wy);
                const std::optional<Hit> hit = trace(dir);
                if (!hit) continue;
                glm::dvec3 color(0.0);
                if (ss == 0) {
                    glm::dvec4 tex(0.0);
                    if (!texture.empty()) {
                        // Exact uv derivatives: the neighbouring pixels' rays cut with the tangent plane.
                        auto duv = [&](double ox, double oy) {
                            const auto q =
                                ray_plane(eye, ray_dir(wx + ox, wy + oy), hit->position, hit->normal);
                            if (!q) return glm::dvec2(0.0);
                            const glm::dvec3 dq = *q - hit->position;
                            if (hit->mesh)
                                return glm::dvec2(glm::dot(hit->grad_u, dq), glm::dot(hit->grad_v, dq));
                            return sphere_uv_differential(hit->rest_dir, hit->to_rest * dq);
                        };
                        tex = settings.anisotropic > 0
                                  ? texture.anisotropic(hit_uv(*hit), duv(1.0, 0.0), duv(0.0, 1.0),
                                                        settings.anisotropic)
                                  : texture.trilinear(hit_uv(*hit), duv(1.0, 0.0), duv(0.0, 1.0));
                    }
                    color = shade(*hit, dir, tex);
                } else {
                    int hits = 0;
                    for (int sy = 0; sy < ss; ++sy)
                        for (int sx = 0; sx < ss; ++sx) {
                            const glm::dvec3 d =
                                ray_dir(double(x) + (sx + 0.5) / ss, double(h - 1 - y) + (sy + 0.5) / ss);
                            const std::optional<Hit> sub = trace(d);
                            if (!sub) continue;
                            const glm::dvec4 tex =
                                texture.empty() ? glm::dvec4(0.0) : texture.bilinear(hit_uv(*sub));
                            color += shade(*sub, d, tex);
                            ++hits;
                        }
                    color = hits ? color / double(hits)
                                 : shade(*hit, dir,
                                         texture.empty() ? glm::dvec4(0.0) : texture.bilinear(hit_uv(*hit)));
                }
                const std::size_t k = img.index(x, y);
                img.color[k] = glm::vec4(glm::vec3(color), 1.0f);
                img.depth[k] = float(glm::dot(hit->position - eye, view_axis));
                img.normal[k] = glm::vec3(hit->normal);
            }
        }
    });
    return img;
}

}  // namespace sffd::render
