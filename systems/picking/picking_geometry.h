// Internals of PickingState shared by picking_state.cpp (the state, its refresh and the ray casts) and
// picking_geometry.cpp (the Embree device, geometries, their buffers and callbacks). Included only by those
// two files, so Embree's headers stay out of the picking system's public headers.
#pragma once

#include <cstdint>
#include <memory>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/splat_source.h"

namespace sffd::picking::detail {

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
    // Point clouds with PointFlags: 1 for a point that is hidden or deleted (never hit), by point index
    // (a disc's primitive id, an ellipsoid's `index`); empty when no point is gone. Of the flags at
    // `flags_version`: a flag edit rewrites this, never the geometry.
    std::vector<std::uint8_t> gone;
    std::uint64_t flags_version = 0;
    bool is_gone(std::size_t point) const { return point < gone.size() && gone[point] != 0; }

    GeomRecord() = default;
    GeomRecord(const GeomRecord&) = delete;
    GeomRecord& operator=(const GeomRecord&) = delete;
    ~GeomRecord() {
        if (geometry) rtcReleaseGeometry(geometry);
    }
};

using RecordMap = std::unordered_map<std::uint64_t, std::unique_ptr<GeomRecord>>;

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

RTCDevice create_device();
RTCScene create_scene(RTCDevice device);

// The pickable Gaussians of a cloud (opacity above the 3DGS alpha cut, finite, invertible), in world
// space minus the anchor.
std::vector<GeomRecord::Ellipsoid> gaussian_ellipsoids(const GaussianSource& src, const glm::dmat4& model,
                                                       const glm::dvec3& anchor);
// Fills (or refills) a point cloud's geometry buffers from its splats, in world space minus the anchor.
void fill_surface(GeomRecord& rec, const SplatSource& src, const glm::dmat4& model, const glm::dvec3& anchor);
// Control points as spheres; radius a fraction of the smallest (world) cell edge of the lattice.
void fill_controls(GeomRecord& rec, const Lattice& lattice, const glm::dmat4& model, const glm::dvec3& anchor,
                   double fraction);
// New Embree geometry sized for `count` primitives, attached to `scene`.
void create_geometry(RTCDevice device, RTCScene scene, GeomRecord& rec, RTCGeometryType type,
                     std::size_t count);
// One RTC_GEOMETRY_TYPE_USER geometry per Gaussian cloud: Embree calls the ellipsoid bounds callback per
// primitive at the scene commit and the intersect / occluded callbacks for the rays that reach its box.
void create_gaussian_geometry(RTCDevice device, RTCScene scene, GeomRecord& rec);
void release_geometry(RTCScene scene, RecordMap& map, RecordMap::iterator it);
// Brings rec.gone in step with entity e's PointFlags (a copy of the gone bits, by point index).
void sync_gone(GeomRecord& rec, const ecs::Registry& registry, ecs::Entity e);
RTCRayHit make_rayhit(const glm::dvec3& origin, const glm::dvec3& direction, double tfar);

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

}  // namespace sffd::picking::detail
