// Shared by the compute deformers (gpu_kernel.cpp) and paper mode (paper_mode.cpp): the std140 mirror of
// FfdBlock in shaders/ffd/ffd_common.glsl, filled from the same preparation as the CPU kernels, and the
// control-point upload (float displacements, or the zero-bordered B-spline grid).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "runtime/gfx/gl.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_kernels.h"

namespace sffd::ffd::detail {

struct FfdBlock {
    float minv[3][4];
    float stu0[4];
    std::int32_t div[4];
    float cull_lo[4];
    float cull_hi[4];
    std::uint32_t count[4];
};
static_assert(sizeof(FfdBlock) == 128);

inline FfdBlock make_ffd_block(const Lattice& lattice, const Prepared& P, std::uint32_t count) {
    FfdBlock block{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) block.minv[r][c] = P.minv[r * 3 + c];
    for (int a = 0; a < 3; ++a) {
        block.stu0[a] = P.stu0[a];
        block.div[a] = lattice.divisions[a];
        block.cull_lo[a] = P.cull_lo[a];
        block.cull_hi[a] = P.cull_hi[a];
    }
    block.div[3] = lattice.basis == LatticeBasis::bspline ? 1 : 0;
    block.count[0] = count;
    block.count[1] = P.any_moved ? 0u : 1u;
    return block;
}

// Replaces the storage of a small buffer that the GPU may still be reading (the last frame's dispatch)
// with `bytes` of `data`: new storage, the old released once that work is done. Writing into the storage in
// use instead (glBufferSubData) made the CPU wait for that dispatch on an NVIDIA H200: the GPU path's CPU
// time grew with the splat count (0.64 ms at 1M, 8.5 ms at 16M, the dispatch's own time).
inline void orphan_upload(GLuint buffer, std::size_t bytes, const void* data) {
    glNamedBufferData(buffer, GLsizeiptr(bytes), data, GL_DYNAMIC_DRAW);
}

// The B-spline grid (Prepared::grid: (L+3)(M+3)(N+3) points of x, y, z, 0) as runs: for each start
// (i, j, k), k < N (a point's cell index along the third axis is at most N - 1), the points (i, j, k..k+3)
// as three vec4, their x, their y, their z: run ((i (M+3) + j) N + k) at float 12 run. Twice the grid's
// bytes, but a splat reads its 4x4x4 points in 48 aligned 16-byte loads instead of 64, and each of its
// 16 sums over k becomes three dot products.
inline std::vector<float> bspline_runs(const Lattice& lattice, const Prepared& P) {
    const std::size_t L = std::size_t(lattice.divisions.x), M = std::size_t(lattice.divisions.y),
                      N = std::size_t(lattice.divisions.z);
    std::vector<float> runs((L + 3) * (M + 3) * N * 12);
    for (std::size_t i = 0; i < L + 3; ++i)
        for (std::size_t j = 0; j < M + 3; ++j)
            for (std::size_t k = 0; k < N; ++k) {
                float* run = &runs[((i * (M + 3) + j) * N + k) * 12];
                const float* point = &P.grid[((i * (M + 3) + j) * (N + 3) + k) * 4];
                for (std::size_t t = 0; t < 4; ++t)
                    for (std::size_t axis = 0; axis < 3; ++axis) run[axis * 4 + t] = point[t * 4 + axis];
            }
    return runs;
}

// Writes the lattice's control data into `buffer` (new storage each time: orphan_upload): Bernstein's
// displacements, the B-spline's zero-bordered grid, or with `runs` that grid as bspline_runs(). `capacity`
// tracks its size.
inline void upload_control_points(GLuint buffer, std::size_t& capacity, const Lattice& lattice,
                                  const Prepared& P, bool runs = false) {
    const bool bspline = lattice.basis == LatticeBasis::bspline;
    std::vector<float> own;
    if (bspline && runs) own = bspline_runs(lattice, P);
    const std::vector<float>& data = bspline && runs ? own : bspline ? P.grid : P.dp4;
    const float zeros[4] = {};
    // Never an empty buffer: the shaders bind it whatever the lattice.
    const float* bytes = data.size() < 4 ? zeros : data.data();
    capacity = std::max<std::size_t>(data.size(), 4) * sizeof(float);
    orphan_upload(buffer, capacity, bytes);
}

}  // namespace sffd::ffd::detail
