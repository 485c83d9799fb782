// 1D compute work over a 2D grid of work groups. GL guarantees only 65,535 work groups per dimension
// (GL_MAX_COMPUTE_WORK_GROUP_COUNT may be exactly that), so a 1D dispatch of 64-wide groups stops at
// 4,194,240 invocations. dispatch_1d() spreads ceil(count / local_size) groups over rows of at most
// `max_groups` groups; the shader recovers its element index with sffd_dispatch_index()
// (shaders/common/dispatch.glsl) and must bounds-check it (the last row is partly empty):
//
//   C++:  gfx::dispatch_1d(count, 64);
//   GLSL: #include "common/dispatch.glsl"
//         layout(local_size_x = 64) in;
//         void main() { uint i = sffd_dispatch_index(); if (i >= count) return; ... }
//
// The limit used is 65,535, GL's guaranteed minimum, not the queried value: it is right on every
// conforming implementation, needs no glGet (which can stall a threaded driver), and a 65,535-wide grid
// costs a GPU nothing more than a wider one. Tests lower it (ScopedDispatchLimit) to exercise the 2D grid
// on small clouds.
#pragma once

#include <cstdint>
#include <optional>

#include "runtime/core/result.h"

namespace sffd::gfx {

inline constexpr std::uint32_t kMinMaxComputeGroups = 65535;  // GL 4.5 §19.1: guaranteed per dimension

struct DispatchGrid {
    std::uint32_t x = 0, y = 0;  // work groups per dimension (z is 1); {0, 0} for count 0
};

// CPU only: the grid for `count` invocations of `local_size`-wide groups with at most `max_x` groups per
// row and `max_y` rows. nullopt when it cannot be done: a zero argument, more than max_y rows, or an index
// past 2^32 - 1 (sffd_dispatch_index() is a uint and would wrap).
std::optional<DispatchGrid> dispatch_grid(std::uint64_t count, std::uint32_t local_size,
                                          std::uint32_t max_x = kMinMaxComputeGroups,
                                          std::uint32_t max_y = kMinMaxComputeGroups);

// The index sffd_dispatch_index() computes for invocation `local_x` of group (group_x, group_y) (CPU
// mirror, for tests): row-major over the grid's groups.
inline std::uint64_t dispatch_index(const DispatchGrid& grid, std::uint32_t local_size, std::uint32_t group_x,
                                    std::uint32_t group_y, std::uint32_t local_x) {
    return (std::uint64_t(group_y) * grid.x + group_x) * local_size + local_x;
}

// The groups per row dispatch_1d() uses when given none: kMinMaxComputeGroups, or the innermost
// ScopedDispatchLimit of this thread.
std::uint32_t dispatch_group_limit();

// glDispatchCompute of dispatch_grid(count, local_size, max_groups_x) with the bound program (count 0:
// nothing; rows up to kMinMaxComputeGroups). max_groups_x 0 = dispatch_group_limit(). Fails, dispatching
// nothing, when no grid fits.
Status dispatch_1d(std::uint64_t count, std::uint32_t local_size, std::uint32_t max_groups_x = 0);

// Tests: lowers dispatch_group_limit() on this thread while alive (e.g. 4 groups per row, so a cloud of a
// few thousand splats is dispatched as a 2D grid through the real system code).
class ScopedDispatchLimit {
public:
    explicit ScopedDispatchLimit(std::uint32_t max_groups_x);
    ~ScopedDispatchLimit();
    ScopedDispatchLimit(const ScopedDispatchLimit&) = delete;
    ScopedDispatchLimit& operator=(const ScopedDispatchLimit&) = delete;

private:
    std::uint32_t m_previous;
};

}  // namespace sffd::gfx
