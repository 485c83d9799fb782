// PickingState: the Embree state's owner (device, both scenes, geometry-id maps, the cache of what picking
// computes itself), its lazy refresh and the ray casts. PickingState::Impl owns the device and both scenes;
// the geometries, their buffers and Embree's callbacks are in picking_geometry.cpp.
#include "systems/picking/picking_state.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/gaussian/components.h"
#include "systems/picking/picking_geometry.h"
#include "systems/picking/world_space.h"

namespace sffd::picking {
using namespace detail;

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
    std::array<std::uint64_t, 6> seen{~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull};
    double seen_fraction = -1.0;
    PickCache cache;  // what picking read back or deformed itself, for clouds of both kinds
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
};

PickingState::PickingState() : m_impl(std::make_unique<Impl>()) {}
PickingState::~PickingState() = default;
PickingState::PickingState(PickingState&&) noexcept = default;
PickingState& PickingState::operator=(PickingState&&) noexcept = default;

const PickingState::Stats& PickingState::stats() const { return m_impl->stats; }
std::size_t PickingState::surface_geometry_count() const { return m_impl->surface_records.size(); }
std::size_t PickingState::control_geometry_count() const { return m_impl->control_records.size(); }
std::size_t PickingState::gaussian_geometry_count() const { return m_impl->gaussian_records.size(); }

bool PickingState::Impl::refresh_gaussians(ecs::Registry& registry) {
    bool changed = release_stale<GaussianCloud>(
        registry, surfaces, gaussian_records, gaussian_ids, stats.geometries_released,
        [&](ecs::Entity e) { cache.erase(PickCloudKind::gaussian, e); });
    for (auto [e, cloud] : registry.view<const GaussianCloud>()) {
        const GaussianSource src = gaussian_source(registry, e, cache);
        const glm::dmat4 model = model_matrix(registry.try_get<Transform>(e));
        if (!anchored && !src.positions.empty()) {
            anchor = glm::dvec3(model * glm::dvec4(src.origin, 1.0));
            anchored = true;
        }
        Stamp stamp{int(src.kind), src.version, registry.version<Transform>(e), 0.0, src.positions.size()};
        auto it = gaussian_records.find(e.bits());
        if (it != gaussian_records.end() && it->second->stamp == stamp) {
            sync_gone(*it->second, registry, e);
            continue;
        }
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
            sync_gone(*rec, registry, e);  // before the geometry: the callbacks read it from the commit on
            create_gaussian_geometry(device, surfaces, *rec);
            gaussian_ids[rec->id] = e;
            it = gaussian_records.emplace(e.bits(), std::move(rec)).first;
            ++stats.geometries_created;
        } else {
            it->second->ellipsoids = std::move(ellipsoids);
            sync_gone(*it->second, registry, e);
            rtcCommitGeometry(it->second->geometry);  // bounds are re-read at the scene commit
            ++stats.geometries_updated;
        }
        it->second->stamp = stamp;
        changed = true;
    }
    stats.gaussian_cpu_deformations = cache.gaussian_deformations;
    stats.gaussian_gpu_read_backs = cache.gaussian_read_backs;
    return changed;
}

bool PickingState::Impl::refresh_surfaces(ecs::Registry& registry) {
    // Entities that died or lost their cloud: detach their geometry (its id becomes free for reuse).
    bool changed =
        release_stale<SplatCloud>(registry, surfaces, surface_records, surface_ids, stats.geometries_released,
                                  [&](ecs::Entity e) { cache.erase(PickCloudKind::surface, e); });
    for (auto [e, cloud] : registry.view<const SplatCloud>()) {
        const SplatSource src = splat_source(registry, e, cache);
        if (!anchored && !src.positions.empty()) {
            anchor = glm::dvec3(model_matrix(registry.try_get<Transform>(e)) * glm::dvec4(src.origin, 1.0));
            anchored = true;
        }
        const Stamp stamp{int(src.kind), src.version, registry.version<Transform>(e), 0.0,
                          src.positions.size()};
        auto it = surface_records.find(e.bits());
        if (it != surface_records.end() && it->second->stamp == stamp) {
            sync_gone(*it->second, registry, e);
            continue;
        }
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
        sync_gone(*it->second, registry, e);
        fill_surface(*it->second, src, model_matrix(registry.try_get<Transform>(e)), anchor);
        changed = true;
    }
    stats.cpu_deformations = cache.deformations;
    stats.gpu_read_backs = cache.read_backs;
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
    const std::array<std::uint64_t, 6> now{
        registry.storage_version<SplatCloud>(),    splat_source_storage_version(registry),
        registry.storage_version<Transform>(),     registry.storage_version<Lattice>(),
        gaussian_source_storage_version(registry), registry.storage_version<PointFlags>()};
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
