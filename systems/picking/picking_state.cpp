// Embree side of picking: one function per step (device, scenes, geometry fill, refresh, ray casts), one
// error callback for the device. Who owns what: PickingState::Impl owns the device and both scenes; each
// GeomRecord owns its RTCGeometry (released on destruction) and the CPU copies of splat axes that the
// ellipse filter reads through the geometry's user pointer.
#include "systems/picking/picking_state.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/components.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/splat_source.h"
#include "systems/picking/world_space.h"

namespace sffd::picking {
namespace {

// What a geometry was built from; a refresh rebuilds it when any of these moved.
struct Stamp {
    int source = 0;               // SplatSource::Kind, or -1 for lattices
    std::uint64_t data = 0;       // change stamp of the data component
    std::uint64_t transform = 0;  // change stamp of the entity's Transform
    double param = 0.0;           // control-point radius fraction (lattices)
    std::size_t count = 0;
    bool operator==(const Stamp&) const = default;
};

struct GeomRecord {
    ecs::Entity entity;
    RTCGeometry geometry = nullptr;
    unsigned id = RTC_INVALID_GEOMETRY_ID;
    Stamp stamp;
    bool discs = false;
    // Ellipse filter inputs (discs only), anchor-relative float, indexed by primitive id.
    std::vector<glm::vec3> centres, axis_u, axis_v;
    // Gaussian clouds (user geometry): the pickable Gaussians, indexed by primitive id.
    struct Ellipsoid {
        glm::vec3 centre;     // anchor-relative
        float k;              // Mahalanobis radius (gaussian_pick_sigmas)
        glm::mat3 to_unit;    // S⁻¹ Rᵀ L⁻¹
        std::uint32_t index;  // the Gaussian's index in its cloud
        float opacity;        // linear, for the blending weights of the most-visible pick
    };
    std::vector<Ellipsoid> ellipsoids;

    GeomRecord() = default;
    GeomRecord(const GeomRecord&) = delete;
    GeomRecord& operator=(const GeomRecord&) = delete;
    ~GeomRecord() {
        if (geometry) rtcReleaseGeometry(geometry);
    }
};

using RecordMap = std::unordered_map<std::uint64_t, std::unique_ptr<GeomRecord>>;

void embree_error(void*, RTCError code, const char* message) {
    log::error("embree: error ", int(code), ": ", message ? message : "(no message)");
}

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

// Largest singular value of [a b]: the radius of the circle around the ellipse {a x + b y : x²+y² <= 1}
// (larger than max(|a|, |b|) once deformation shears the axes).
float ellipse_bounding_radius(const glm::vec3& a, const glm::vec3& b) {
    const float A = glm::dot(a, a), B = glm::dot(a, b), C = glm::dot(b, b);
    const float half_diff = 0.5f * (A - C);
    return std::sqrt(std::max(0.0f, 0.5f * (A + C) + std::sqrt(half_diff * half_diff + B * B)));
}

// Intersection/occlusion filter: Embree tested the bounding disc; keep the hit only when the hit point
// lies in the splat's ellipse, i.e. when its least-squares coordinates (x, y) in the basis (a, b)
// satisfy x² + y² <= 1.
void ellipse_filter(const RTCFilterFunctionNArguments* args) {
    const auto* rec = static_cast<const GeomRecord*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
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

// Every Gaussian a collecting ray enters (the most-visible pick): Embree is not told about these hits,
// so traversal goes on behind them, up to the nearest splat disc.
struct GaussianRayHit {
    double t_entry = 0.0;   // where the ray enters the ellipsoid
    double t_centre = 0.0;  // the centre's depth along the ray (the blending order, as 3DGS's depth sort)
    double alpha = 0.0;     // ray_alpha
    unsigned geom = 0, prim = 0;
};

// Our intersect context: Embree's first (it hands the pointer back to the callbacks), then whether the
// Gaussian callbacks collect instead of reporting the nearest hit.
struct PickContext {
    RTCIntersectContext base;
    std::vector<GaussianRayHit>* collect = nullptr;
};
static_assert(std::is_standard_layout_v<PickContext>);

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

// The pickable Gaussians of a cloud (opacity above the 3DGS alpha cut, finite, invertible), in world
// space minus the anchor.
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

// Fills (or refills) a point cloud's geometry buffers from its splats, in world space minus the anchor.
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

// Control points as spheres; radius a fraction of the smallest (world) cell edge of the lattice.
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

// New Embree geometry sized for `count` primitives, attached to `scene`.
void create_geometry(RTCDevice device, RTCScene scene, GeomRecord& rec, RTCGeometryType type,
                     std::size_t count) {
    rec.geometry = rtcNewGeometry(device, type);
    rec.discs = type == RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT;
    rtcSetGeometryBuildQuality(rec.geometry, RTC_BUILD_QUALITY_LOW);
    rtcSetNewGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                            count);
    if (rec.discs) {
        rtcSetNewGeometryBuffer(rec.geometry, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                count);
        rtcSetGeometryUserData(rec.geometry, &rec);
        rtcSetGeometryIntersectFilterFunction(rec.geometry, ellipse_filter);
        rtcSetGeometryOccludedFilterFunction(rec.geometry, ellipse_filter);
    }
    rec.id = rtcAttachGeometry(scene, rec.geometry);
}

void release_geometry(RTCScene scene, RecordMap& map, RecordMap::iterator it) {
    rtcDetachGeometry(scene, it->second->id);
    map.erase(it);
}

// Detaches the geometry of every record whose entity died or lost its `C` (its id becomes free for reuse),
// drops its id, and lets `forget(entity)` drop what else the caller keeps for it. Adds to `released`;
// true when any went.
template <class C, class Forget>
bool release_stale(const ecs::Registry& registry, RTCScene scene, RecordMap& records,
                   std::unordered_map<unsigned, ecs::Entity>& ids, std::uint64_t& released, Forget&& forget) {
    bool changed = false;
    for (auto it = records.begin(); it != records.end();) {
        const ecs::Entity e = it->second->entity;
        if (!registry.valid(e) || !registry.has<C>(e)) {
            ids.erase(it->second->id);
            forget(e);
            auto doomed = it++;
            release_geometry(scene, records, doomed);
            ++released;
            changed = true;
        } else {
            ++it;
        }
    }
    return changed;
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

}  // namespace

struct PickingState::Impl {
    RTCDevice device = nullptr;
    RTCScene surfaces = nullptr;
    RTCScene controls = nullptr;
    RecordMap surface_records, control_records;  // by entity bits
    RecordMap gaussian_records;                  // Gaussian clouds (in the surfaces scene), by entity bits
    std::unordered_map<unsigned, ecs::Entity> surface_ids, control_ids;  // geometry id -> entity
    std::unordered_map<unsigned, ecs::Entity> gaussian_ids;  // surfaces-scene geometry id -> Gaussian entity
    glm::dvec3 anchor{0.0};
    bool anchored = false;
    // Registry stamps of the last refresh: when none moved, refresh() returns at once.
    std::array<std::uint64_t, 5> seen{~0ull, ~0ull, ~0ull, ~0ull, ~0ull};
    double seen_fraction = -1.0;
    DeformCache deform_cache;  // CPU deformations of clouds whose deformed output is GPU-only
    GaussianDeformCache
        gaussian_cache;  // centres + Jacobians of Gaussian clouds without a current CPU output
    Stats stats;

    Impl() : device(create_device()), surfaces(create_scene(device)), controls(create_scene(device)) {
        rtcCommitScene(surfaces);  // empty scenes are valid to trace
        rtcCommitScene(controls);
    }
    ~Impl() {
        surface_records.clear();
        gaussian_records.clear();
        control_records.clear();
        if (surfaces) rtcReleaseScene(surfaces);
        if (controls) rtcReleaseScene(controls);
        if (device) rtcReleaseDevice(device);
    }

    bool refresh_surfaces(ecs::Registry& registry);
    bool refresh_gaussians(ecs::Registry& registry);
    bool refresh_controls(ecs::Registry& registry, double fraction);
    std::optional<RayHit> intersect(RTCScene scene, const std::unordered_map<unsigned, ecs::Entity>& ids,
                                    const Ray& ray, double tfar) const;
    void create_gaussian_geometry(GeomRecord& rec);
};

PickingState::PickingState() : m_impl(std::make_unique<Impl>()) {}
PickingState::~PickingState() = default;
PickingState::PickingState(PickingState&&) noexcept = default;
PickingState& PickingState::operator=(PickingState&&) noexcept = default;

const PickingState::Stats& PickingState::stats() const { return m_impl->stats; }
std::size_t PickingState::surface_geometry_count() const { return m_impl->surface_records.size(); }
std::size_t PickingState::control_geometry_count() const { return m_impl->control_records.size(); }
std::size_t PickingState::gaussian_geometry_count() const { return m_impl->gaussian_records.size(); }

// One RTC_GEOMETRY_TYPE_USER geometry per Gaussian cloud: Embree calls ellipsoid_bounds per primitive at
// the scene commit and ellipsoid_intersect / ellipsoid_occluded for the rays that reach its box.
void PickingState::Impl::create_gaussian_geometry(GeomRecord& rec) {
    rec.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rec.discs = false;
    rtcSetGeometryBuildQuality(rec.geometry, RTC_BUILD_QUALITY_LOW);
    rtcSetGeometryUserPrimitiveCount(rec.geometry, unsigned(rec.ellipsoids.size()));
    rtcSetGeometryUserData(rec.geometry, &rec);
    rtcSetGeometryBoundsFunction(rec.geometry, ellipsoid_bounds, nullptr);
    rtcSetGeometryIntersectFunction(rec.geometry, ellipsoid_intersect);
    rtcSetGeometryOccludedFunction(rec.geometry, ellipsoid_occluded);
    rtcCommitGeometry(rec.geometry);
    rec.id = rtcAttachGeometry(surfaces, rec.geometry);
}

bool PickingState::Impl::refresh_gaussians(ecs::Registry& registry) {
    bool changed = release_stale<GaussianCloud>(
        registry, surfaces, gaussian_records, gaussian_ids, stats.geometries_released,
        [&](ecs::Entity e) { gaussian_cache.clouds.erase(e.bits()); });
    for (auto [e, cloud] : registry.view<const GaussianCloud>()) {
        const GaussianSource src = gaussian_source(registry, e, gaussian_cache);
        const glm::dmat4 model = model_matrix(registry.try_get<Transform>(e));
        if (!anchored && !src.positions.empty()) {
            anchor = glm::dvec3(model * glm::dvec4(src.origin, 1.0));
            anchored = true;
        }
        Stamp stamp{int(src.kind), src.version, registry.version<Transform>(e), 0.0, src.positions.size()};
        auto it = gaussian_records.find(e.bits());
        if (it != gaussian_records.end() && it->second->stamp == stamp) continue;
        std::vector<GeomRecord::Ellipsoid> ellipsoids = gaussian_ellipsoids(src, model, anchor);
        // The primitive count is that of the pickable Gaussians: a different count gets a new geometry.
        if (it != gaussian_records.end() &&
            (it->second->ellipsoids.size() != ellipsoids.size() || ellipsoids.empty())) {
            gaussian_ids.erase(it->second->id);
            release_geometry(surfaces, gaussian_records, it);
            ++stats.geometries_released;
            it = gaussian_records.end();
            changed = true;
        }
        if (ellipsoids.empty()) continue;
        if (it == gaussian_records.end()) {
            auto rec = std::make_unique<GeomRecord>();
            rec->entity = e;
            rec->ellipsoids = std::move(ellipsoids);
            create_gaussian_geometry(*rec);
            gaussian_ids[rec->id] = e;
            it = gaussian_records.emplace(e.bits(), std::move(rec)).first;
            ++stats.geometries_created;
        } else {
            it->second->ellipsoids = std::move(ellipsoids);
            rtcCommitGeometry(it->second->geometry);  // bounds are re-read at the scene commit
            ++stats.geometries_updated;
        }
        it->second->stamp = stamp;
        changed = true;
    }
    stats.gaussian_cpu_deformations = gaussian_cache.deformations;
    stats.gaussian_gpu_read_backs = gaussian_cache.read_backs;
    return changed;
}

bool PickingState::Impl::refresh_surfaces(ecs::Registry& registry) {
    // Entities that died or lost their cloud: detach their geometry (its id becomes free for reuse).
    bool changed =
        release_stale<SplatCloud>(registry, surfaces, surface_records, surface_ids, stats.geometries_released,
                                  [&](ecs::Entity e) { deform_cache.clouds.erase(e.bits()); });
    for (auto [e, cloud] : registry.view<const SplatCloud>()) {
        const SplatSource src = splat_source(registry, e, deform_cache);
        if (!anchored && !src.positions.empty()) {
            anchor = glm::dvec3(model_matrix(registry.try_get<Transform>(e)) * glm::dvec4(src.origin, 1.0));
            anchored = true;
        }
        const Stamp stamp{int(src.kind), src.version, registry.version<Transform>(e), 0.0,
                          src.positions.size()};
        auto it = surface_records.find(e.bits());
        if (it != surface_records.end() && it->second->stamp == stamp) continue;
        const bool discs = src.normals.size() == src.positions.size();
        if (it != surface_records.end() &&
            (it->second->stamp.count != stamp.count || it->second->discs != discs || stamp.count == 0)) {
            surface_ids.erase(it->second->id);
            release_geometry(surfaces, surface_records, it);
            ++stats.geometries_released;
            it = surface_records.end();
            changed = true;
        }
        if (stamp.count == 0) continue;
        if (it == surface_records.end()) {
            auto rec = std::make_unique<GeomRecord>();
            rec->entity = e;
            create_geometry(device, surfaces, *rec,
                            discs ? RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT : RTC_GEOMETRY_TYPE_SPHERE_POINT,
                            stamp.count);
            surface_ids[rec->id] = e;
            it = surface_records.emplace(e.bits(), std::move(rec)).first;
            ++stats.geometries_created;
        } else {
            ++stats.geometries_updated;
        }
        it->second->stamp = stamp;
        fill_surface(*it->second, src, model_matrix(registry.try_get<Transform>(e)), anchor);
        changed = true;
    }
    stats.cpu_deformations = deform_cache.deformations;
    stats.gpu_read_backs = deform_cache.read_backs;
    if (refresh_gaussians(registry)) changed = true;
    if (changed) {
        rtcCommitScene(surfaces);
        ++stats.surface_commits;
    }
    return changed;
}

bool PickingState::Impl::refresh_controls(ecs::Registry& registry, double fraction) {
    bool changed = release_stale<Lattice>(registry, controls, control_records, control_ids,
                                          stats.geometries_released, [](ecs::Entity) {});
    for (auto [e, lattice] : registry.view<const Lattice>()) {
        if (!anchored && !lattice.current.empty()) {
            anchor =
                glm::dvec3(model_matrix(registry.try_get<Transform>(e)) * glm::dvec4(lattice.origin, 1.0));
            anchored = true;
        }
        const Stamp stamp{-1, registry.version<Lattice>(e), registry.version<Transform>(e), fraction,
                          lattice.current.size()};
        auto it = control_records.find(e.bits());
        if (it != control_records.end() && it->second->stamp == stamp) continue;
        if (it != control_records.end() && (it->second->stamp.count != stamp.count || stamp.count == 0)) {
            control_ids.erase(it->second->id);
            release_geometry(controls, control_records, it);
            ++stats.geometries_released;
            it = control_records.end();
            changed = true;
        }
        if (stamp.count == 0) continue;
        if (it == control_records.end()) {
            auto rec = std::make_unique<GeomRecord>();
            rec->entity = e;
            create_geometry(device, controls, *rec, RTC_GEOMETRY_TYPE_SPHERE_POINT, stamp.count);
            control_ids[rec->id] = e;
            it = control_records.emplace(e.bits(), std::move(rec)).first;
            ++stats.geometries_created;
        } else {
            ++stats.geometries_updated;
        }
        it->second->stamp = stamp;
        fill_controls(*it->second, lattice, model_matrix(registry.try_get<Transform>(e)), anchor, fraction);
        changed = true;
    }
    if (changed) {
        rtcCommitScene(controls);
        ++stats.control_commits;
    }
    return changed;
}

bool PickingState::refresh(ecs::Registry& registry, const PickSettings& settings) {
    Impl& s = *m_impl;
    ++s.stats.refresh_calls;
    const std::array<std::uint64_t, 5> now{
        registry.storage_version<SplatCloud>(), splat_source_storage_version(registry),
        registry.storage_version<Transform>(), registry.storage_version<Lattice>(),
        gaussian_source_storage_version(registry)};
    if (now == s.seen && settings.control_point_radius_fraction == s.seen_fraction) return false;
    const bool a = s.refresh_surfaces(registry);
    const bool b = s.refresh_controls(registry, settings.control_point_radius_fraction);
    s.seen = now;
    s.seen_fraction = settings.control_point_radius_fraction;
    return a || b;
}

std::optional<PickingState::RayHit> PickingState::Impl::intersect(
    RTCScene scene, const std::unordered_map<unsigned, ecs::Entity>& ids, const Ray& ray, double tfar) const {
    PickContext context;
    rtcInitIntersectContext(&context.base);
    RTCRayHit rh = make_rayhit(ray.origin - anchor, ray.direction, tfar);
    rtcIntersect1(scene, &context.base, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    if (scene == surfaces) {
        if (const auto g = gaussian_ids.find(rh.hit.geomID); g != gaussian_ids.end()) {
            const auto rec = gaussian_records.find(g->second.bits());
            if (rec == gaussian_records.end() || rh.hit.primID >= rec->second->ellipsoids.size())
                return std::nullopt;
            return RayHit{g->second, rec->second->ellipsoids[rh.hit.primID].index, double(rh.ray.tfar), true};
        }
    }
    const auto it = ids.find(rh.hit.geomID);
    if (it == ids.end()) return std::nullopt;
    return RayHit{it->second, rh.hit.primID, double(rh.ray.tfar), false};
}

std::optional<PickingState::RayHit> PickingState::intersect_surfaces(const Ray& ray, double tfar) const {
    return m_impl->intersect(m_impl->surfaces, m_impl->surface_ids, ray, tfar);
}

std::optional<PickingState::RayHit> PickingState::most_visible_surface(const Ray& ray, double tfar) const {
    const Impl& s = *m_impl;
    std::vector<GaussianRayHit> hits;
    PickContext context;
    rtcInitIntersectContext(&context.base);
    context.collect = &hits;
    const glm::dvec3 direction = glm::normalize(ray.direction);
    RTCRayHit rh = make_rayhit(ray.origin - s.anchor, direction, tfar);
    rtcIntersect1(s.surfaces, &context.base, &rh);
    // The nearest splat disc (opaque), if any: Gaussians entered behind it do not count.
    std::optional<RayHit> disc;
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
        if (const auto it = s.surface_ids.find(rh.hit.geomID); it != s.surface_ids.end())
            disc = RayHit{it->second, rh.hit.primID, double(rh.ray.tfar), false};
    const double t_disc = disc ? disc->t : std::numeric_limits<double>::infinity();
    std::erase_if(hits, [&](const GaussianRayHit& h) { return !(h.t_entry <= t_disc); });
    std::stable_sort(hits.begin(), hits.end(), [](const GaussianRayHit& a, const GaussianRayHit& b) {
        return a.t_centre < b.t_centre;
    });
    // Front-to-back blending weights w = α T; the disc is opaque (weight T behind every Gaussian).
    double T = 1.0, best_w = 0.0;
    const GaussianRayHit* best = nullptr;
    for (const GaussianRayHit& h : hits) {
        const double w = h.alpha * T;
        if (w > best_w) best_w = w, best = &h;
        T *= 1.0 - h.alpha;
    }
    if (disc && (T > best_w || !best)) return disc;
    if (!best) return std::nullopt;
    const auto g = s.gaussian_ids.find(best->geom);
    if (g == s.gaussian_ids.end()) return std::nullopt;
    const auto rec = s.gaussian_records.find(g->second.bits());
    if (rec == s.gaussian_records.end() || best->prim >= rec->second->ellipsoids.size()) return std::nullopt;
    return RayHit{g->second, rec->second->ellipsoids[best->prim].index, best->t_entry, true};
}

std::optional<PickingState::RayHit> PickingState::intersect_controls(const Ray& ray, double tfar) const {
    return m_impl->intersect(m_impl->controls, m_impl->control_ids, ray, tfar);
}

std::optional<glm::dvec2> PickingState::splat_coordinates(ecs::Entity cloud, std::uint32_t index,
                                                          const glm::dvec3& world) const {
    const auto it = m_impl->surface_records.find(cloud.bits());
    if (it == m_impl->surface_records.end()) return std::nullopt;
    const GeomRecord& rec = *it->second;
    if (!rec.discs || index >= rec.centres.size() || index >= rec.axis_u.size()) return std::nullopt;
    const glm::dvec3 d = world - m_impl->anchor - glm::dvec3(rec.centres[index]);
    const glm::dvec3 a(rec.axis_u[index]), b(rec.axis_v[index]);
    const double A = glm::dot(a, a), B = glm::dot(a, b), C = glm::dot(b, b);
    const double det = A * C - B * B;
    if (!(det > 1e-12 * A * C)) return std::nullopt;
    const double ad = glm::dot(a, d), bd = glm::dot(b, d);
    return glm::dvec2((C * ad - B * bd) / det, (A * bd - B * ad) / det);
}

bool PickingState::surface_between(const glm::dvec3& from, const glm::dvec3& to) const {
    const glm::dvec3 d = to - from;
    const double len = glm::length(d);
    if (!(len > 0.0)) return false;
    PickContext context;
    rtcInitIntersectContext(&context.base);
    RTCRayHit rh = make_rayhit(from - m_impl->anchor, d / len, len * (1.0 - 1e-3));
    rtcOccluded1(m_impl->surfaces, &context.base, &rh.ray);
    return rh.ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace sffd::picking
