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

// Replaces the storage of a small buffer that the GPU may still be reading (the last frame's dispatch)
// with `bytes` of `data`: new storage, the old released once that work is done. Writing into the storage in
// use instead (glBufferSubData) made the CPU wait for that dispatch on an NVIDIA H200: the GPU path's CPU
// time grew with the splat count (0.64 ms at 1M, 8.5 ms at 16M, the dispatch's own time).
inline void orphan_upload(GLuint buffer, std::size_t bytes, const void* data) {
    glNamedBufferData(buffer, GLsizeiptr(bytes), data, GL_DYNAMIC_DRAW);
}

// Writes the lattice's control data into `buffer` (new storage each time: orphan_upload); `capacity`
// tracks its size.
inline void upload_control_points(GLuint buffer, std::size_t& capacity, const Lattice& lattice,
                                  const Prepared& P) {
    const std::vector<float>& data = lattice.basis == LatticeBasis::bspline ? P.grid : P.dp4;
    std::vector<float> padded;
    const std::vector<float>* upload = &data;
    if (data.size() < 4) {  // never an empty buffer: the shaders bind it whatever the lattice
        padded = data;
        padded.resize(4, 0.0f);
        upload = &padded;
    }
    capacity = upload->size() * sizeof(float);
    orphan_upload(buffer, capacity, upload->data());
}

}  // namespace sffd::ffd::detail
