// PickingState: the picking system's Embree state (device, two scenes, geometry-id maps), held as a
// registry resource and created on the first pick. Move-only RAII owner; Embree headers stay in the .cpp.
//
// Two scenes, following the Embree tutorials (point_geometry, dynamic_scene):
//   surfaces  one RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT geometry per point-cloud entity: centre, radius
//             = the longer splat axis, normal; an intersection filter trims the disc to the splat's
//             ellipse (axis_u, axis_v). Data: see splat_source.h (deformed output, read back once per
//             version when it is GPU-only, picking's own CPU deformation without a context, or the
//             authored SplatCloud). Clouds without
//             normals become sphere points.
//             Gaussian clouds (GaussianCloud, or DeformedGaussians) are in this scene too: one
//             RTC_GEOMETRY_TYPE_USER geometry per cloud whose primitives are the pickable Gaussians as
//             ellipsoids (bounds / intersect / occluded callbacks; see gaussian_source.h for the shape).
//   controls  one RTC_GEOMETRY_TYPE_SPHERE_POINT geometry per lattice entity (current control points).
// Geometry id -> entity (with generation) and primitive id -> splat / control-point index.
//
// refresh() is lazy: it compares the registry's change stamps with those the scenes were built from and
// touches only what moved (rtcUpdateGeometryBuffer + rtcCommitGeometry per geometry, then one
// rtcCommitScene per scene). It is called by pick(), never every frame.
//
// Precision: Embree works in float, so every position is stored relative to an `anchor` (the origin of
// the first point cloud seen), and rays are shifted by it; scans 1e6 units from the world origin pick
// as precisely as scans near it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/picking/components.h"

namespace sffd::picking {

class PickingState {
public:
    PickingState();
    ~PickingState();
    PickingState(PickingState&&) noexcept;
    PickingState& operator=(PickingState&&) noexcept;
    PickingState(const PickingState&) = delete;
    PickingState& operator=(const PickingState&) = delete;

    // Counters for tests and the benchmark: how much work refreshes did.
    struct Stats {
        std::uint64_t refresh_calls = 0;    // refresh() invocations
        std::uint64_t surface_commits = 0;  // rtcCommitScene on the surfaces scene
        std::uint64_t control_commits = 0;  // rtcCommitScene on the controls scene
        std::uint64_t geometries_created = 0;
        std::uint64_t geometries_updated = 0;  // in-place buffer updates (same entity, data moved)
        std::uint64_t geometries_released = 0;
        std::uint64_t cpu_deformations =
            0;  // clouds deformed on the CPU by picking (no context, no CPU output)
        std::uint64_t gpu_read_backs = 0;  // GPU-only deformed outputs read back (once per version)
        std::uint64_t gaussian_cpu_deformations =
            0;  // Gaussian clouds' centres + Jacobians computed by picking
        std::uint64_t gaussian_gpu_read_backs = 0;  // Gaussian clouds' GPU-only outputs read back
    };
    const Stats& stats() const;

    // Brings both scenes up to date with the registry. Returns true when a scene was committed.
    bool refresh(ecs::Registry& registry, const PickSettings& settings = {});

    // Closest hit along the ray in (tnear, tfar], in world units from ray.origin (direction unit length).
    struct RayHit {
        ecs::Entity entity = ecs::null_entity;
        std::uint32_t index = 0;  // splat, Gaussian or control-point index
        double t = 0.0;
        bool gaussian = false;  // a Gaussian of a GaussianCloud (surfaces scene only)
    };
    std::optional<RayHit> intersect_surfaces(const Ray& ray, double tfar) const;
    std::optional<RayHit> intersect_controls(const Ray& ray, double tfar) const;
    // The surface that contributes most to the pixel of this ray: every Gaussian ellipsoid in front of the
    // nearest splat disc gets its 3DGS blending weight α T (α = ray_alpha, T the transmittance of the
    // Gaussians before it in centre-depth order), the disc (opaque) the transmittance left; the largest
    // weight wins, ties to the nearer. t is the ellipsoid entry (or the disc hit). Without Gaussians it is
    // intersect_surfaces().
    std::optional<RayHit> most_visible_surface(const Ray& ray, double tfar) const;
    // True when a surface lies on the segment from `from` to `to` (excluding a small end margin, so a
    // control point sitting on the surface is not hidden by the splat it touches). A Gaussian counts when
    // the segment enters its ellipsoid and its alpha along the line (ray_alpha) is at least 0.5.
    bool surface_between(const glm::dvec3& from, const glm::dvec3& to) const;

    // Coordinates (x, y) of a world point in a picked splat's frame, point = centre + x a + y b with a, b
    // the splat's world-space axes as last refreshed (least squares). nullopt for unknown clouds, sphere
    // clouds or degenerate axes.
    std::optional<glm::dvec2> splat_coordinates(ecs::Entity cloud, std::uint32_t index,
                                                const glm::dvec3& world) const;

    // Number of geometries in each scene (for tests: ids are released when entities die).
    std::size_t surface_geometry_count() const;
    std::size_t control_geometry_count() const;
    std::size_t gaussian_geometry_count() const;  // Gaussian clouds with at least one pickable Gaussian

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sffd::picking
