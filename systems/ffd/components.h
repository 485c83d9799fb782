// FFD components: plain data. Owned by the FFD system (systems/ffd); other systems read them.
// Lattice convention (../shared/notes/ffd-math.md): origin X0, edge vectors S, T, U, divisions (l, m, n),
// (l+1)(m+1)(n+1) control points, flat index (i*(m+1)+j)*(n+1)+k, i along S, j along T, k along U.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"

namespace sffd {

enum class LatticeBasis : std::uint8_t { bernstein, bspline };

// A lattice entity: Lattice (+ Transform placing it in the world). Edits go through
// registry.patch<Lattice>(e) so the deformer sees the change stamp move.
struct Lattice {
    glm::dvec3 origin{0.0};
    std::array<glm::dvec3, 3> axes{glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};  // S, T, U
    glm::ivec3 divisions{1, 1, 1};                // l, m, n
    LatticeBasis basis = LatticeBasis::bernstein;
    std::vector<glm::dvec3> rest;                 // control points at rest (world space of the lattice)
    std::vector<glm::dvec3> current;              // edited control points, same indexing

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

}  // namespace sffd
