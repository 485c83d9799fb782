// Lattice components: plain data, authored in scene files (runtime/assets/scene.cpp) and built-in scenes,
// edited by the editor and animation, read by the FFD system (systems/ffd), which writes its own output
// (DeformedSplats, systems/ffd/components.h). They live in the runtime so that loading a scene needs no
// system: layers only point down.
// Convention (../shared/notes/ffd-math.md): origin X0, edge vectors S, T, U, divisions (l, m, n),
// (l+1)(m+1)(n+1) control points, flat index (i*(m+1)+j)*(n+1)+k, i along S, j along T, k along U.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/ecs/entity.h"

namespace sffd {

enum class LatticeBasis : std::uint8_t { bernstein, bspline };

// Largest supported division count per axis (every reader of lattices checks against this one).
inline constexpr int kMaxLatticeDivisions = 64;

// A lattice entity: Lattice (+ Transform placing it in the world). Edits go through
// registry.patch<Lattice>(e) so the deformer sees the change stamp move.
struct Lattice {
    glm::dvec3 origin{0.0};
    std::array<glm::dvec3, 3> axes{glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};  // S, T, U
    glm::ivec3 divisions{1, 1, 1};                                                                  // l, m, n
    LatticeBasis basis = LatticeBasis::bernstein;
    std::vector<glm::dvec3> rest;     // control points at rest (world space of the lattice)
    std::vector<glm::dvec3> current;  // edited control points, same indexing

    std::size_t size() const { return std::size_t(divisions.x + 1) * (divisions.y + 1) * (divisions.z + 1); }
    std::size_t index(int i, int j, int k) const {
        return (std::size_t(i) * (divisions.y + 1) + j) * (divisions.z + 1) + k;
    }
};

// On a point-cloud entity: the lattices it follows, applied in order (e.g. a local lattice inside a
// global one: the second deforms the output of the first).
struct Deformers {
    std::vector<ecs::Entity> lattices;
};

// The uniform rest grid P0[i][j][k] = X0 + (i/l) S + (j/m) T + (k/n) U, flat index (i*(m+1)+j)*(n+1)+k.
// The one place the grid is built (FFD operations, lattice files, built-in scenes, profiling); one point
// of it, in the same arithmetic, for checks that must not allocate the grid (rest_is_uniform).
inline glm::dvec3 rest_grid_point(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                                  const glm::ivec3& d, int i, int j, int k) {
    return origin + (double(i) / d.x) * axes[0] + (double(j) / d.y) * axes[1] + (double(k) / d.z) * axes[2];
}
std::vector<glm::dvec3> rest_grid(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                                  const glm::ivec3& divisions);

// The one set of rules every lattice meets (scene files, lattice files, the deformers): divisions
// 1..kMaxLatticeDivisions, finite origin/axes/control points, (l+1)(m+1)(n+1) rest and current control
// points, a non-degenerate box (|det[S T U]| relative to |S||T||U| above 1e-9). Messages start with
// `what` (a file name or "lattice").
Status validate_lattice(const Lattice& lattice, const std::string& what = "lattice");

// A lattice at rest (rest == current == rest_grid).
Lattice make_lattice(const glm::dvec3& origin, const std::array<glm::dvec3, 3>& axes,
                     const glm::ivec3& divisions, LatticeBasis basis = LatticeBasis::bernstein);

}  // namespace sffd
