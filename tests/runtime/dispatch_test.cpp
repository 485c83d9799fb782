// gfx::dispatch_grid (runtime/gfx/dispatch.h): every element index in [0, count) is produced by exactly one
// invocation of the grid under sffd_dispatch_index()'s formula, within GL's per-dimension limits.
#include <gtest/gtest.h>

#include <vector>

#include "runtime/gfx/dispatch.h"

using namespace sffd;

namespace {

// Walks every invocation of the grid with the shader's index formula (dispatch_index) and checks that
// the ones passing the bounds check cover [0, count) once each.
void expect_covers_once(std::uint64_t count, std::uint32_t local, std::uint32_t max_x, std::uint32_t max_y) {
    const auto grid = gfx::dispatch_grid(count, local, max_x, max_y);
    ASSERT_TRUE(grid) << count << " / " << local << " / " << max_x;
    EXPECT_LE(grid->x, max_x);
    EXPECT_LE(grid->y, max_y);
    std::vector<int> hits(count, 0);
    for (std::uint32_t gy = 0; gy < grid->y; ++gy)
        for (std::uint32_t gx = 0; gx < grid->x; ++gx)
            for (std::uint32_t lx = 0; lx < local; ++lx) {
                const std::uint64_t i = gfx::dispatch_index(*grid, local, gx, gy, lx);
                if (i < count) ++hits[i];
            }
    for (std::uint64_t i = 0; i < count; ++i) ASSERT_EQ(hits[i], 1) << "index " << i << " of " << count;
    // No row is wholly empty: the grid is as small as the limits allow.
    if (count > 0) {
        EXPECT_LT(std::uint64_t(grid->y - 1) * grid->x * local, count);
    }
}

TEST(DispatchGrid, SmallCountsAreOneRow) {
    EXPECT_EQ(gfx::dispatch_grid(1, 64)->x, 1u);
    EXPECT_EQ(gfx::dispatch_grid(1, 64)->y, 1u);
    EXPECT_EQ(gfx::dispatch_grid(64, 64)->x, 1u);  // exact multiple
    EXPECT_EQ(gfx::dispatch_grid(65, 64)->x, 2u);
    EXPECT_EQ(gfx::dispatch_grid(65, 64)->y, 1u);
    const auto empty = gfx::dispatch_grid(0, 64);
    ASSERT_TRUE(empty);
    EXPECT_EQ(empty->x, 0u);
    EXPECT_EQ(empty->y, 0u);
}

TEST(DispatchGrid, BeyondTheGuaranteedLimitOfOneDimensionUsesRows) {
    // GL guarantees 65,535 groups per dimension: 64 x 65,535 = 4,194,240 invocations fit one row.
    const auto full = gfx::dispatch_grid(64ull * 65535, 64);
    ASSERT_TRUE(full);
    EXPECT_EQ(full->x, 65535u);
    EXPECT_EQ(full->y, 1u);
    const auto over = gfx::dispatch_grid(64ull * 65535 + 1, 64);
    ASSERT_TRUE(over);
    EXPECT_EQ(over->x, 65535u);
    EXPECT_EQ(over->y, 2u);
    // The 16M-splat target, with the cull pass's 128-wide groups too.
    const auto s16 = gfx::dispatch_grid(16'000'000, 64);
    ASSERT_TRUE(s16);
    EXPECT_EQ(s16->x, 65535u);
    EXPECT_EQ(s16->y, 4u);  // 250,000 groups
    const auto c16 = gfx::dispatch_grid(16'000'000, 128);
    ASSERT_TRUE(c16);
    EXPECT_EQ(c16->y, 2u);  // 125,000 groups
    // Exact multiple of a full row.
    const auto rows3 = gfx::dispatch_grid(64ull * 65535 * 3, 64);
    ASSERT_TRUE(rows3);
    EXPECT_EQ(rows3->x, 65535u);
    EXPECT_EQ(rows3->y, 3u);
}

TEST(DispatchGrid, EveryIndexOnceUnderSmallLimits) {
    for (std::uint32_t local : {1u, 3u, 64u})
        for (std::uint32_t max_x : {1u, 2u, 4u, 7u})
            for (std::uint64_t count :
                 {1ull, 2ull, 63ull, 64ull, 65ull, 255ull, 256ull, 257ull, 1000ull, 1024ull})
                if ((count + local - 1) / local <= std::uint64_t(max_x) * 65535)
                    expect_covers_once(count, local, max_x, 65535);
    // Both dimensions limited (the grid is exactly full at 4 x 4 groups of 64).
    expect_covers_once(1024, 64, 4, 4);
    expect_covers_once(1000, 64, 4, 4);
}

TEST(DispatchGrid, RefusesWhatNoGridOrIndexCanHold) {
    EXPECT_FALSE(gfx::dispatch_grid(1025, 64, 4, 4));  // 17 groups, 4 x 4 at most
    EXPECT_FALSE(gfx::dispatch_grid(10, 0));
    EXPECT_FALSE(gfx::dispatch_grid(10, 64, 0));
    // 2^32 elements would need index 2^32: sffd_dispatch_index() is a 32-bit uint.
    EXPECT_FALSE(gfx::dispatch_grid(1ull << 32, 64));
    // A count whose grid of 65,535 x 1,024 groups of 64 (2^32 - 2^16 invocations) indexes within 32 bits.
    const auto big = gfx::dispatch_grid(65535ull * 1024 * 64, 64);
    ASSERT_TRUE(big);
    EXPECT_EQ(big->y, 1024u);
    // Rows of 65,535 groups: a count just under 2^32 would round its last row past 2^32.
    EXPECT_FALSE(gfx::dispatch_grid(0xffffffffull, 64));
}

TEST(DispatchGrid, ScopedLimitLowersTheDefaultAndRestoresIt) {
    EXPECT_EQ(gfx::dispatch_group_limit(), gfx::kMinMaxComputeGroups);
    {
        gfx::ScopedDispatchLimit four(4);
        EXPECT_EQ(gfx::dispatch_group_limit(), 4u);
        {
            gfx::ScopedDispatchLimit two(2);
            EXPECT_EQ(gfx::dispatch_group_limit(), 2u);
        }
        EXPECT_EQ(gfx::dispatch_group_limit(), 4u);
    }
    EXPECT_EQ(gfx::dispatch_group_limit(), gfx::kMinMaxComputeGroups);
}

}  // namespace
