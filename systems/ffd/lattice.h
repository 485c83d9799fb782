// Lattice helpers (math convention: ../shared/notes/ffd-math.md and README.md in this folder).
// Everything here is double precision and works relative to the lattice origin, so lattices far from the
// world origin (offsets of 1e6) keep their accuracy.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

// Largest supported division count per axis (the issue asks for at least 32): the runtime's constant.
inline constexpr int kMaxDivisions = kMaxLatticeDivisions;
// Local coordinates within [-kInsideSlack, 1 + kInsideSlack] count as inside (and are clamped to [0,1]):
// points exactly on a face, edge or corner deform even when float rounding puts them a hair outside.
// Every path (reference, fast, sparse, GPU) uses the same slack so they agree at the boundary.
inline constexpr double kInsideSlack = 1e-6;

// The rest grid and a lattice at rest: defined once, with the components (runtime/scene/lattice.h).
using sffd::make_lattice;
using sffd::rest_grid;

// Divisions, finiteness, counts and a non-degenerate box: the runtime's one rule set (validate_lattice).
inline Status validate(const Lattice& lattice, const std::string& what = "lattice") {
    return validate_lattice(lattice, what);
}

// The inverse of M = [S T U] (columns): rows (T×U)/((T×U)·S), (S×U)/((S×U)·T), (S×T)/((S×T)·U).
glm::dmat3 inverse_axes(const Lattice& lattice);

// (s,t,u) = M⁻¹ (X − X0), X in world space.
glm::dvec3 local_coords(const Lattice& lattice, const glm::dvec3& world);
// Inside test, faces inclusive (with kInsideSlack).
inline bool inside(const glm::dvec3& stu) {
    return stu.x >= -kInsideSlack && stu.x <= 1.0 + kInsideSlack && stu.y >= -kInsideSlack &&
           stu.y <= 1.0 + kInsideSlack && stu.z >= -kInsideSlack && stu.z <= 1.0 + kInsideSlack;
}

// Calls f(i, j, k, d) for every control point that moved, d = current − rest ≠ 0, in flat-index order:
// the displacement form of the deformation sums over these only (the reference evaluator and the fast
// path's sparse setup both walk them this way).
template <class F>
void for_each_moved(const Lattice& l, F&& f) {
    for (int i = 0; i <= l.divisions.x; ++i)
        for (int j = 0; j <= l.divisions.y; ++j)
            for (int k = 0; k <= l.divisions.z; ++k) {
                const std::size_t c = l.index(i, j, k);
                const glm::dvec3 d = l.current[c] - l.rest[c];
                if (d != glm::dvec3(0.0)) f(i, j, k, d);
            }
}

// True when rest equals the uniform grid of (origin, axes, divisions) to 1e-12 relative: then the
// displacement form equals the classic Σ P B form and Bernstein's convex-hull property bounds the result.
bool rest_is_uniform(const Lattice& lattice);

// Axis-aligned world box.
struct Box {
    glm::dvec3 lo{0.0};
    glm::dvec3 hi{0.0};
    bool empty = true;
    void add(const glm::dvec3& p) {
        if (empty) {
            lo = hi = p;
            empty = false;
            return;
        }
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
};

// A box that contains every point the lattice can produce from points in `in` (all deformed points,
// inside or outside the lattice): in ⊕ [min(0,ΔP), max(0,ΔP)] (the weights are non-negative and sum to
// at most 1 for both bases), intersected for a uniform-rest Bernstein lattice with hull(P) ∪ in.
Box deformed_bounds(const Lattice& lattice, const Box& in);

}  // namespace sffd::ffd
