// Internal interface between deform.cpp (API, validation, reference path) and deform_fast.cpp (the float
// kernels). Not part of the public API.
#pragma once

#include <cstdint>
#include <vector>

#include "systems/ffd/deform.h"

namespace sffd::ffd::detail {

// A lattice prepared for the float kernels: displacements ΔP = current − rest relative to nothing (they
// are differences, so far-away lattices lose no precision), the inverse axes and the cloud's offset in
// local coordinates (computed in double: local = stu0 + M⁻¹ p for a point p relative to the cloud origin).
struct Prepared {
    int L = 1, M = 1, N = 1;  // divisions
    LatticeBasis basis = LatticeBasis::bernstein;
    std::vector<float> dp4;                 // Bernstein: ΔP as x,y,z,0 per control point, flat index
    std::vector<std::uint8_t> row_nonzero;  // Bernstein: (i,j) rows with any nonzero ΔP
    // The dense Bernstein kernel sums only the coordinates of ΔP that move, coord[0..coords-1], in that
    // order: from dp4 when all three do, else from dk4 (those coordinates first, per control point).
    int coords = 3;
    int coord[3] = {0, 1, 2};
    std::vector<float> dk4;  // empty when coords == 3
    std::vector<float> du4;  // N (ΔP[k+1] − ΔP[k]), k < N, per (i,j) row, the coordinates in coord order
    struct Moved {
        int i, j, k;
        float d[3];
    };
    std::vector<Moved> moved;                // sparse path: moved control points only
    std::vector<std::uint8_t> need[3];       // sparse path: per axis, indices some moved point uses
    std::vector<float> binom[3], binom1[3];  // C(n,i) and C(n-1,i) per axis
    std::vector<float> grid;                 // B-spline: zero-bordered ΔP grid, (L+3)(M+3)(N+3) x,y,z,0
    float minv[9] = {};                      // row-major M⁻¹
    float stu0[3] = {};                      // M⁻¹ (cloud origin − lattice origin)
    float cull_lo[3] = {0, 0, 0};            // local box outside which ΔP has no influence (B-spline)
    float cull_hi[3] = {1, 1, 1};
    bool any_moved = false;  // some control point is off its rest position
};

// What the preparation is for. The GPU kernels read only ΔP (dp4 or grid), M⁻¹, the origin offset, the
// cull box and any_moved. With the CPU kernels' tables the GPU path's preparation took 11 µs, without them
// 3.5 µs (an 11³ lattice, hot cache, the 2-core machine), every frame a lattice moves.
enum class PrepareFor : std::uint8_t { cpu_kernels, gpu_controls };

Prepared prepare(const Lattice& lattice, const glm::dvec3& cloud_origin,
                 PrepareFor use = PrepareFor::cpu_kernels);

// Runs the fast (dense Bernstein / B-spline) or sparse kernel over all points with TBB.
DeformStats run_fast(const Prepared& prepared, const PointsIn& in, const PointsOut& out, bool sparse);

}  // namespace sffd::ffd::detail
