// Embree side of picking, one function per step: the device and its error callback, the scenes, each
// geometry's buffers (discs, control-point spheres, Gaussian ellipsoids) and the callbacks Embree calls
// back (the ellipse filter, the ellipsoid bounds / intersect / occluded). Each GeomRecord owns its
// RTCGeometry (released on destruction) and the CPU copies the callbacks read through its user pointer.
#include "systems/picking/picking_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"

namespace sffd::picking::detail {
namespace {

void embree_error(void*, RTCError code, const char* message) {
    log::error("embree: error ", int(code), ": ", message ? message : "(no message)");
}

// Largest singular value of [a b]: the radius of the circle around the ellipse {a x + b y : x²+y² <= 1}
// (larger than max(|a|, |b|) once deformation shears the axes).
float ellipse_bounding_radius(const glm::vec3& a, const glm::vec3& b) {
    const float A = glm::dot(a, a), B = glm::dot(a, b), C = glm::dot(b, b);
    const float half_diff = 0.5f * (A - C);
    return std::sqrt(std::max(0.0f, 0.5f * (A + C) + std::sqrt(half_diff * half_diff + B * B)));
}

// Intersection/occlusion filter: a hidden or deleted point is never hit. Discs: Embree tested the
// bounding disc; keep the hit only when the hit point lies in the splat's ellipse, i.e. when its
// least-squares coordinates (x, y) in the basis (a, b) satisfy x² + y² <= 1.
void ellipse_filter(const RTCFilterFunctionNArguments* args) {
    const auto* rec = static_cast<const GeomRecord*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        if (rec->is_gone(prim)) {
            args->valid[i] = 0;
            continue;
        }
        if (!rec->discs) continue;
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        const glm::vec3 org{RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                            RTCRayN_org_z(args->ray, args->N, i)};
        const glm::vec3 dir{RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
                            RTCRayN_dir_z(args->ray, args->N, i)};
        const glm::vec3 d = org + t * dir - rec->centres[prim];
        const glm::vec3& a = rec->axis_u[prim];
        const glm::vec3& b = rec->axis_v[prim];
        const float A = glm::dot(a, a), B = glm::dot(a, b), C = glm::dot(b, b);
        const float det = A * C - B * B;
        if (!(det > 1e-12f * A * C)) continue;  // degenerate axes: keep Embree's disc answer
        const float ad = glm::dot(a, d), bd = glm::dot(b, d);
        const float x = (C * ad - B * bd) / det;
        const float y = (A * bd - B * ad) / det;
        if (x * x + y * y > 1.0f + 1e-5f) args->valid[i] = 0;
    }
}

PickEllipsoid to_pick_ellipsoid(const GeomRecord::Ellipsoid& e) {
    PickEllipsoid p;
    p.centre = glm::dvec3(e.centre);
    p.to_unit = glm::dmat3(e.to_unit);
    p.k = double(e.k);
    p.opacity = double(e.opacity);
    return p;
}

// User geometry bounds: the box around {c + B x : |x| <= k}, B = to_unit⁻¹; half extent along world axis
// j is k |row j of B|.
void ellipsoid_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* rec = static_cast<const GeomRecord*>(args->geometryUserPtr);
    const GeomRecord::Ellipsoid& e = rec->ellipsoids[args->primID];
    const glm::mat3 B = glm::inverse(e.to_unit);
    glm::vec3 half;
    for (int j = 0; j < 3; ++j)
        half[j] = e.k * glm::length(glm::vec3(B[0][j], B[1][j], B[2][j])) * (1.0f + 1e-5f);
    RTCBounds* b = args->bounds_o;
    b->lower_x = e.centre.x - half.x, b->lower_y = e.centre.y - half.y, b->lower_z = e.centre.z - half.z;
    b->upper_x = e.centre.x + half.x, b->upper_y = e.centre.y + half.y, b->upper_z = e.centre.z + half.z;
}

void ellipsoid_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* rec = static_cast<const GeomRecord*>(args->geometryUserPtr);
    const GeomRecord::Ellipsoid& e = rec->ellipsoids[args->primID];
    if (rec->is_gone(e.index)) return;  // hidden or deleted: never hit
    const PickEllipsoid pe = to_pick_ellipsoid(e);
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const glm::dvec3 org{RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                             RTCRayN_org_z(ray, args->N, i)};
        const glm::dvec3 dir{RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                             RTCRayN_dir_z(ray, args->N, i)};
        const double t =
            intersect_ellipsoid(pe, org, dir, RTCRayN_tnear(ray, args->N, i), RTCRayN_tfar(ray, args->N, i));
        if (t < 0.0) continue;
        // Every surfaces-scene ray is cast with a PickContext (Impl::intersect, surface_between).
        if (auto* hits = reinterpret_cast<const PickContext*>(args->context)->collect) {
            hits->push_back({t, glm::dot(pe.centre - org, dir) / glm::dot(dir, dir), ray_alpha(pe, org, dir),
                             args->geomID, args->primID});
            continue;
        }
        RTCRayN_tfar(ray, args->N, i) = float(t);
        // Normal: the density's gradient direction, to_unitᵀ to_unit (p − c).
        const glm::dvec3 n = glm::transpose(pe.to_unit) * (pe.to_unit * (org + t * dir - pe.centre));
        RTCHitN_Ng_x(hit, args->N, i) = float(n.x);
        RTCHitN_Ng_y(hit, args->N, i) = float(n.y);
        RTCHitN_Ng_z(hit, args->N, i) = float(n.z);
        RTCHitN_u(hit, args->N, i) = 0.0f;
        RTCHitN_v(hit, args->N, i) = 0.0f;
        RTCHitN_primID(hit, args->N, i) = args->primID;
        RTCHitN_geomID(hit, args->N, i) = args->geomID;
        RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    }
}

void ellipsoid_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* rec = static_cast<const GeomRecord*>(args->geometryUserPtr);
    if (rec->is_gone(rec->ellipsoids[args->primID].index)) return;
    const PickEllipsoid pe = to_pick_ellipsoid(rec->ellipsoids[args->primID]);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        RTCRayN* ray = args->ray;
        const glm::dvec3 org{RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                             RTCRayN_org_z(ray, args->N, i)};
        const glm::dvec3 dir{RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                             RTCRayN_dir_z(ray, args->N, i)};
        // A Gaussian hides what is behind it when it alone covers at least half the pixel (faint floaters
        // in front of a control point do not hide it).
        if (intersect_ellipsoid(pe, org, dir, RTCRayN_tnear(ray, args->N, i),
                                RTCRayN_tfar(ray, args->N, i)) >= 0.0 &&
            ray_alpha(pe, org, dir) >= 0.5)
            RTCRayN_tfar(ray, args->N, i) = -std::numeric_limits<float>::infinity();
    }
}

}  // namespace

RTCDevice create_device() {
    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) {
        log::error("PickingState(): rtcNewDevice failed (error ", int(rtcGetDeviceError(nullptr)), ")");
        return nullptr;
    }
    rtcSetDeviceErrorFunction(device, embree_error, nullptr);
    if (!rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_POINT_GEOMETRY_SUPPORTED))
        log::error("PickingState(): this Embree build has no point geometry; picking will find nothing");
    if (!rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED))
        log::warn("PickingState(): Embree without filter functions: splats are picked as circles");
    return device;
}

RTCScene create_scene(RTCDevice device) {
    RTCScene scene = rtcNewScene(device);
    // Deformed splats move every edit: a fast (low quality) rebuild beats a slow build plus fast traversal
    // for one ray per click.
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    return scene;
}

std::vector<GeomRecord::Ellipsoid> gaussian_ellipsoids(const GaussianSource& src, const glm::dmat4& model,
                                                       const glm::dvec3& anchor) {
    const std::size_t n = src.positions.size();
    std::vector<GeomRecord::Ellipsoid> all(n);
    std::vector<std::uint8_t> keep(n, 0);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const PickEllipsoid e = gaussian_ellipsoid(
                    model, src.origin + glm::dvec3(src.positions[i]), src.scales[i], src.rotations[i],
                    src.opacities[i], src.jacobians.empty() ? glm::mat3(1.0f) : src.jacobians[i]);
                if (e.k <= 0.0) continue;
                const glm::mat3 to_unit(e.to_unit);
                const glm::vec3 c(e.centre - anchor);
                if (!std::isfinite(glm::determinant(to_unit)) || glm::determinant(to_unit) == 0.0f) continue;
                all[i] = {c, float(e.k), to_unit, std::uint32_t(i), float(e.opacity)};
                keep[i] = 1;
            }
        });
    // Compact in place (no second n-sized array at the peak).
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (keep[i]) all[kept++] = all[i];
    all.resize(kept);
    return all;
}

void fill_surface(GeomRecord& rec, const SplatSource& src, const glm::dmat4& model,
                  const glm::dvec3& anchor) {
    const std::size_t n = src.positions.size();
    const glm::dmat3 linear(model);
    const glm::mat3 linear_f(linear);
    const glm::mat3 normal_f(glm::transpose(glm::inverse(linear)));
    const bool has_axes = src.axis_u.size() == n && src.axis_v.size() == n;
    auto* vertex = static_cast<float*>(rtcGetGeometryBufferData(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0));
    float* normal =
        rec.discs ? static_cast<float*>(rtcGetGeometryBufferData(rec.geometry, RTC_BUFFER_TYPE_NORMAL, 0))
                  : nullptr;
    rec.centres.resize(rec.discs ? n : 0);
    rec.axis_u.resize(rec.discs ? n : 0);
    rec.axis_v.resize(rec.discs ? n : 0);

    // Without tangent axes a splat has no size: fall back to the mean spacing of the bounding box.
    float fallback_radius = 0.0f;
    if (!has_axes && n > 0) {
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : src.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
        fallback_radius = glm::length(linear_f * (hi - lo)) / std::sqrt(float(n));
    }
    const glm::dvec3 shift = src.origin;
    // Independent per splat: split across cores (the BVH build that follows is parallel too).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i < range.end(); ++i) {
                              const glm::dvec3 world =
                                  glm::dvec3(model * glm::dvec4(shift + glm::dvec3(src.positions[i]), 1.0));
                              const glm::vec3 c(world - anchor);
                              float radius = fallback_radius;
                              if (has_axes) {
                                  const glm::vec3 a = linear_f * src.axis_u[i];
                                  const glm::vec3 b = linear_f * src.axis_v[i];
                                  radius = ellipse_bounding_radius(a, b);
                                  if (rec.discs) rec.axis_u[i] = a, rec.axis_v[i] = b;
                              }
                              vertex[4 * i + 0] = c.x;
                              vertex[4 * i + 1] = c.y;
                              vertex[4 * i + 2] = c.z;
                              vertex[4 * i + 3] = radius;
                              if (rec.discs) {
                                  rec.centres[i] = c;
                                  glm::vec3 nn = normal_f * src.normals[i];
                                  const float len = glm::length(nn);
                                  nn = len > 0.0f ? nn / len : glm::vec3(0, 0, 1);
                                  normal[3 * i + 0] = nn.x;
                                  normal[3 * i + 1] = nn.y;
                                  normal[3 * i + 2] = nn.z;
                              }
                          }
                      });
    rtcUpdateGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    if (rec.discs) rtcUpdateGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_NORMAL, 0);
    rtcCommitGeometry(rec.geometry);
}

void fill_controls(GeomRecord& rec, const Lattice& lattice, const glm::dmat4& model, const glm::dvec3& anchor,
                   double fraction) {
    const glm::dmat3 linear(model);
    double edge = std::numeric_limits<double>::max();
    for (int a = 0; a < 3; ++a)
        edge = std::min(edge, glm::length(linear * lattice.axes[a]) / std::max(1, lattice.divisions[a]));
    if (!(edge > 0.0) || !std::isfinite(edge)) edge = 1.0;
    const float radius = float(fraction * edge);
    auto* vertex = static_cast<float*>(rtcGetGeometryBufferData(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0));
    for (std::size_t i = 0; i < lattice.current.size(); ++i) {
        const glm::vec3 c(glm::dvec3(model * glm::dvec4(lattice.current[i], 1.0)) - anchor);
        vertex[4 * i + 0] = c.x;
        vertex[4 * i + 1] = c.y;
        vertex[4 * i + 2] = c.z;
        vertex[4 * i + 3] = radius;
    }
    rtcUpdateGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(rec.geometry);
}

void create_geometry(RTCDevice device, RTCScene scene, GeomRecord& rec, RTCGeometryType type,
                     std::size_t count) {
    rec.geometry = rtcNewGeometry(device, type);
    rec.discs = type == RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT;
    rtcSetGeometryBuildQuality(rec.geometry, RTC_BUILD_QUALITY_LOW);
    rtcSetNewGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                            count);
    if (rec.discs)
        rtcSetNewGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                count);
    // Discs test their ellipse; every point geometry drops its gone points.
    rtcSetGeometryUserData(rec.geometry, &rec);
    rtcSetGeometryIntersectFilterFunction(rec.geometry, ellipse_filter);
    rtcSetGeometryOccludedFilterFunction(rec.geometry, ellipse_filter);
    rec.id = rtcAttachGeometry(scene, rec.geometry);
}

void create_gaussian_geometry(RTCDevice device, RTCScene scene, GeomRecord& rec) {
    rec.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rec.discs = false;
    rtcSetGeometryBuildQuality(rec.geometry, RTC_BUILD_QUALITY_LOW);
    rtcSetGeometryUserPrimitiveCount(rec.geometry, unsigned(rec.ellipsoids.size()));
    rtcSetGeometryUserData(rec.geometry, &rec);
    rtcSetGeometryBoundsFunction(rec.geometry, ellipsoid_bounds, nullptr);
    rtcSetGeometryIntersectFunction(rec.geometry, ellipsoid_intersect);
    rtcSetGeometryOccludedFunction(rec.geometry, ellipsoid_occluded);
    rtcCommitGeometry(rec.geometry);
    rec.id = rtcAttachGeometry(scene, rec.geometry);
}

void release_geometry(RTCScene scene, RecordMap& map, RecordMap::iterator it) {
    rtcDetachGeometry(scene, it->second->id);
    map.erase(it);
}

void sync_gone(GeomRecord& rec, const ecs::Registry& registry, ecs::Entity e) {
    const std::uint64_t version = registry.version<PointFlags>(e);
    if (version == rec.flags_version && (version != 0 || rec.gone.empty())) return;
    rec.flags_version = version;
    rec.gone.clear();
    const PointFlags* flags = registry.try_get<PointFlags>(e);
    if (!flags) return;
    bool any = false;
    for (std::uint8_t b : flags->bits) any |= (b & kPointGone) != 0;
    if (!any) return;
    rec.gone.resize(flags->bits.size());
    for (std::size_t i = 0; i < flags->bits.size(); ++i) rec.gone[i] = (flags->bits[i] & kPointGone) != 0;
}

RTCRayHit make_rayhit(const glm::dvec3& origin, const glm::dvec3& direction, double tfar) {
    RTCRayHit rh{};
    rh.ray.org_x = float(origin.x), rh.ray.org_y = float(origin.y), rh.ray.org_z = float(origin.z);
    rh.ray.dir_x = float(direction.x), rh.ray.dir_y = float(direction.y), rh.ray.dir_z = float(direction.z);
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = std::isfinite(tfar) ? float(tfar) : std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xffffffffu;
    rh.ray.flags = 0;
    rh.ray.time = 0.0f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

}  // namespace sffd::picking::detail
