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
    block.count[1] = P.moved.empty() ? 1u : 0u;
    return block;
}

// Writes the lattice's control data into `buffer`, growing it (tracked by `capacity`) when needed.
inline void upload_control_points(GLuint buffer, std::size_t& capacity, const Lattice& lattice,
                                  const Prepared& P) {
    const std::vector<float>& data = lattice.basis == LatticeBasis::bspline ? P.grid : P.dp4;
    const std::size_t bytes = std::max<std::size_t>(data.size(), 4) * sizeof(float);
    if (bytes > capacity) {
        glNamedBufferData(buffer, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_DRAW);
        capacity = bytes;
    }
    if (!data.empty()) glNamedBufferSubData(buffer, 0, GLsizeiptr(data.size() * sizeof(float)), data.data());
}

}  // namespace sffd::ffd::detail
