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

// Derived output of the deformation phase on a point-cloud entity (authored SplatCloud stays as loaded).
// Written by ffd_system only. Positions are relative to `origin` (= the cloud's SplatCloud::origin).
// When the GPU path ran, the deformed splats live in GpuSplatStore::clouds[e].deformed and the CPU arrays
// are left empty (`cpu_valid == false`); bounds, inverted count and version are always valid.
struct DeformedSplats {
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec3> axis_u;
    std::vector<glm::vec3> axis_v;
    bool cpu_valid = false;              // the arrays above hold the current deformation
    bool gpu_valid = false;              // GpuSplatStore's `deformed` buffer holds it
    glm::dvec3 bounds_min{0.0};          // world-space box that never under-covers the deformed splats
    glm::dvec3 bounds_max{0.0};          // (from the control points' displacement hull, see README)
    std::size_t inverted = 0;            // inside splats whose Jacobian has det < 0 (normal flipped)
    std::uint64_t version = 0;           // bumped every time the output is rewritten

    // Inputs this output was computed from (change stamps), so the system skips unchanged clouds.
    std::uint64_t seen_cloud = 0;
    std::uint64_t seen_deformers = 0;
    std::vector<std::uint64_t> seen_lattices;
    bool seen_force_cpu = false;
};

}  // namespace sffd
