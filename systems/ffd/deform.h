// CPU deformation API: deform splats (positions, normals, tangent axes) through one lattice.
//
//   ffd::PointsIn in{cloud.positions.data(), cloud.normals.data(), cloud.axis_u.data(), cloud.axis_v.data(),
//                    cloud.size(), cloud.origin};
//   ffd::PointsOut out{pos.data(), nrm.data(), au.data(), av.data()};
//   auto stats = ffd::deform(lattice, in, out);           // Backend::automatic
//
// Deformation (displacement form, see README.md): X' = X + Σ (P − P0)[i][j][k] B_i(s) B_j(t) B_k(u) for
// points inside the lattice (faces inclusive), X' = X outside. Normals by the cofactor of the world
// Jacobian J = I + [∂D/∂s ∂D/∂t ∂D/∂u] M⁻¹ (normalised), splat axes by J. Positions are relative to
// `origin` (double) in and out, so far-away scans keep float precision.
//
// Backends: `reference` (double, unfactorised, for tests), `fast` (float, factorised tensor sums, 16 points
// per AVX-512 vector, TBB across cores), `sparse` (only moved control points contribute),
// `automatic` (sparse when few control points moved, else fast). All agree to ~1e-6 relative.
// In-place use (out arrays == in arrays) is allowed: chained deformers do it.
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

enum class Backend : std::uint8_t { automatic, fast, sparse, reference };
const char* backend_name(Backend b);

// Any of normals / axis_u / axis_v may be null (then that output is skipped; positions are required).
// An output is written when both its input and output pointers are non-null.
struct PointsIn {
    const glm::vec3* positions = nullptr;
    const glm::vec3* normals = nullptr;
    const glm::vec3* axis_u = nullptr;
    const glm::vec3* axis_v = nullptr;
    std::size_t count = 0;
    glm::dvec3 origin{0.0};
    // Optional per-point weight in [0, 1] (PointWeights, runtime/scene/point_columns.h): the point moves by
    // w times its displacement and its Jacobian is J_w = I + w (J - I), which normals (cofactor of J_w),
    // axes (J_w a) and `PointsOut::jacobians` follow. Null: weight 1 everywhere, the unweighted code. A
    // weight of 0 (or NaN) leaves the point as it is, like a point outside. The weight is a per-point
    // constant, so its gradient is no term of J_w.
    const float* weights = nullptr;
};
struct PointsOut {
    glm::vec3* positions = nullptr;
    glm::vec3* normals = nullptr;
    glm::vec3* axis_u = nullptr;
    glm::vec3* axis_v = nullptr;
    // Optional: the world Jacobian J per point (identity outside the lattice), for consumers that need
    // all of it (3D Gaussians: Σ' = J Σ Jᵀ and the polar rotation of J, systems/gaussian).
    glm::mat3* jacobians = nullptr;
};

struct DeformStats {
    std::size_t inside = 0;                // points inside the lattice (deformed)
    std::size_t inverted = 0;              // inside points with det J < 0 (their normal flips with the cell)
    Backend backend = Backend::automatic;  // the backend that ran
};

// Validates the lattice (message "lattice: ...") and deforms. Never throws.
Result<DeformStats> deform(const Lattice& lattice, const PointsIn& in, const PointsOut& out,
                           Backend backend = Backend::automatic);

// Number of control points with current != rest (what `automatic` looks at).
std::size_t moved_count(const Lattice& lattice);
// automatic's choice for this lattice.
Backend choose_backend(const Lattice& lattice);

// Double-precision reference for one point, for tests: position (world), Jacobian (world) and whether
// the point is inside. Unfactorised sums over all control points. With `weight` (PointsIn::weights):
// position X + w D and Jacobian I + w (J - I); weight 0 (or not > 0) is the rest point and J = I.
struct ReferencePoint {
    glm::dvec3 position{0.0};
    glm::dmat3 jacobian{1.0};
    bool inside = false;
};
ReferencePoint reference_point(const Lattice& lattice, const glm::dvec3& world, double weight = 1.0);

// A normal n carried by the Jacobian J: cof(J) n = (J⁻ᵀ det J) n, normalised (left as is when zero). The
// one copy of that rule for the double paths (the reference backend, streamed `deform --backend
// reference`); the float kernels inline it.
glm::dvec3 deformed_normal(const glm::dmat3& J, const glm::dvec3& n);

}  // namespace sffd::ffd
