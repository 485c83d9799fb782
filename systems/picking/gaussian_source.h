// Which Gaussians picking sees for a Gaussian-cloud entity, and the ellipsoid each one is
// picked as.
//
// Source, in this order:
//   1. the deformation's CPU output (DeformedGaussians, written by systems/gaussian's deformation phase)
//      when the entity has Deformers and the output is current (its `seen` stamps equal the inputs') and
//      has one Gaussian per authored one;
//   2. an entity with Deformers whose current output lives only on the GPU (GpuGaussianStore state
//      deformed_gpu, a GL context current): read back once per GpuGaussians::deformed_version (centres,
//      scales, rotations) into the PickCache;
//   3. an entity with Deformers whose output is missing, stale or not readable: picking's own
//      deformation of what it needs, centres and Jacobians through every lattice in order
//      (ffd::deform with PointsOut::jacobians, the cheap part of the Gaussian deformation: no
//      eigen-decomposition, no SH), kept in the PickCache keyed by the input stamps and computed only
//      when a pick needs it; the ellipsoid is then {c' + J R S x : |x| <= k};
//   4. the authored GaussianCloud.
// Opacities are always the authored cloud's (a deformation does not change them and does not copy them).
//
// The pickable shape of a Gaussian with opacity α is the ellipsoid where its 3DGS alpha
// α·exp(−m²/2) reaches the renderer's cut 1/255 (m = Mahalanobis distance from the centre):
//   m ≤ k(α) = sqrt(2 ln(255 α)),   k = 3.33 standard deviations at α = 1, 2.97 at α = 0.5.
// A ray's least Mahalanobis distance to a Gaussian equals the Mahalanobis distance of its 2D marginal
// at the pixel, so (up to the renderer's 0.3 px low-pass and its 3σ screen box, and the perspective
// linearisation) a ray picks exactly the Gaussians the 3DGS forward pass blends at that pixel.
// Gaussians with α ≤ 1/255 (never drawn) or non-finite data are not pickable.
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"  // DeformInputStamps
#include "systems/picking/pick_cache.h"

namespace sffd::picking {

struct GaussianSource {
    enum class Kind : int {
        none = 10,
        authored,
        deformed,
        cpu_deformed,
        gpu_read_back
    };  // disjoint from SplatSource::Kind
    Kind kind = Kind::none;
    std::uint64_t version = 0;  // identifies the data (a change stamp, or the cache entry's serial)
    glm::dvec3 origin{0.0};     // positions are relative to this (entity space)
    std::span<const glm::vec3> positions, scales;
    std::span<const glm::quat> rotations;
    std::span<const float> opacities;
    std::span<const glm::mat3> jacobians;  // cpu_deformed only: the deformation's J per Gaussian
};

GaussianSource gaussian_source(ecs::Registry& registry, ecs::Entity cloud, PickCache& cache);

// Changes whenever GaussianCloud or DeformedGaussians storage changes.
std::uint64_t gaussian_source_storage_version(const ecs::Registry& registry);

// Mahalanobis radius of the pickable ellipsoid for opacity α: sqrt(2 ln(255 α)); 0 when α ≤ 1/255 or
// not finite (not pickable).
double gaussian_pick_sigmas(double opacity);

// One pickable Gaussian in world space: points p with |to_unit (p − centre)| ≤ k.
struct PickEllipsoid {
    glm::dvec3 centre{0.0};
    glm::dmat3 to_unit{1.0};      // S⁻¹ Rᵀ L⁻¹ (L: the entity's linear transform)
    glm::dvec3 half_extent{0.0};  // axis-aligned half size of the ellipsoid (bounds)
    double k = 0.0;
    double opacity = 0.0;
};

// The ellipsoid of Gaussian (position, scale, rotation, opacity) under the model matrix `model`
// (`shifted_centre` = origin + position, entity space), its axes first mapped by `jacobian` (a
// deformation's J; identity for none). k == 0 when not pickable (also for a singular J). Zero scales
// (flat Gaussians) are raised to 1e-6 of the largest scale so the ellipsoid stays invertible.
PickEllipsoid gaussian_ellipsoid(const glm::dmat4& model, const glm::dvec3& shifted_centre,
                                 const glm::vec3& scale, const glm::quat& rotation, float opacity,
                                 const glm::mat3& jacobian = glm::mat3(1.0f));

// Ray parameter t ∈ [tnear, tfar] where the ray (origin, direction) enters the ellipsoid (or leaves it,
// when the origin is inside); negative when it misses. Double precision, independent of Embree.
// The largest 3DGS alpha of the Gaussian along the (infinite) line: min(0.99, α exp(−m²/2)) with m the
// least Mahalanobis distance of the line to the centre: what the forward pass blends at the pixel of
// this ray (up to its low-pass and perspective linearisation).
double ray_alpha(const PickEllipsoid& e, const glm::dvec3& origin, const glm::dvec3& direction);

double intersect_ellipsoid(const PickEllipsoid& e, const glm::dvec3& origin, const glm::dvec3& direction,
                           double tnear, double tfar);

}  // namespace sffd::picking
