#include "runtime/gfx/dispatch.h"

#include <string>

#include "runtime/gfx/gl.h"

namespace sffd::gfx {

namespace {
thread_local std::uint32_t t_limit = kMinMaxComputeGroups;
}

std::optional<DispatchGrid> dispatch_grid(std::uint64_t count, std::uint32_t local_size, std::uint32_t max_x,
                                          std::uint32_t max_y) {
    if (local_size == 0 || max_x == 0 || max_y == 0) return std::nullopt;
    if (count == 0) return DispatchGrid{};
    const std::uint64_t groups = (count + local_size - 1) / local_size;
    const std::uint64_t x = groups < max_x ? groups : max_x;
    const std::uint64_t y = (groups + x - 1) / x;
    if (y > max_y) return std::nullopt;
    // Largest index any invocation computes: x * y * local_size - 1 must fit a GLSL uint.
    if (x * y * local_size - 1 > 0xffffffffull) return std::nullopt;
    return DispatchGrid{std::uint32_t(x), std::uint32_t(y)};
}

std::uint32_t dispatch_group_limit() { return t_limit; }

Status dispatch_1d(std::uint64_t count, std::uint32_t local_size, std::uint32_t max_groups_x) {
    if (max_groups_x == 0) max_groups_x = t_limit;
    const std::optional<DispatchGrid> grid = dispatch_grid(count, local_size, max_groups_x);
    if (!grid)
        return make_error("dispatch_1d(): " + std::to_string(count) + " invocations of " +
                          std::to_string(local_size) + " per group do not fit a grid of " +
                          std::to_string(max_groups_x) + " x " + std::to_string(kMinMaxComputeGroups) +
                          " groups with 32-bit indices");
    if (grid->x > 0) glDispatchCompute(grid->x, grid->y, 1);
    return {};
}

ScopedDispatchLimit::ScopedDispatchLimit(std::uint32_t max_groups_x) : m_previous(t_limit) {
    t_limit = max_groups_x < kMinMaxComputeGroups ? max_groups_x : kMinMaxComputeGroups;
}
ScopedDispatchLimit::~ScopedDispatchLimit() { t_limit = m_previous; }

}  // namespace sffd::gfx
