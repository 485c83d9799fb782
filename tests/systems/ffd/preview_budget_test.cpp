// The preview budget's subset choice (systems/ffd/preview_budget.h): its size, order, stability, and that
// it is spread over space whatever order the points come in.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/ffd/preview_budget.h"

using namespace sffd;

namespace {

// Points on a 200 x 200 grid of the unit square (z = 0), row by row: a scanner's order, where a plain
// stride would keep whole rows and drop the others.
std::vector<glm::vec3> grid_points() {
    std::vector<glm::vec3> p;
    for (int y = 0; y < 200; ++y)
        for (int x = 0; x < 200; ++x) p.emplace_back(float(x) / 199.0f, float(y) / 199.0f, 0.0f);
    return p;
}

// Cells of an m x m partition of the unit square that hold no kept point.
int empty_cells(const std::vector<glm::vec3>& p, const std::vector<std::uint32_t>& kept, int m) {
    std::set<int> hit;
    for (std::uint32_t i : kept) {
        const int cx = std::min(m - 1, int(p[i].x * float(m))), cy = std::min(m - 1, int(p[i].y * float(m)));
        hit.insert(cy * m + cx);
    }
    return m * m - int(hit.size());
}

}  // namespace

TEST(PreviewBudget, SubsetHasTheBudgetsSizeInAscendingOrderAndIsStable) {
    const std::vector<glm::vec3> p = grid_points();
    const std::vector<std::uint32_t> a = spread_subset(p, 1000), b = spread_subset(p, 1000);
    ASSERT_EQ(a.size(), 1000u);
    EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
    EXPECT_EQ(std::adjacent_find(a.begin(), a.end()), a.end()) << "an index twice";
    EXPECT_LT(a.back(), p.size());
    EXPECT_EQ(a, b);
    EXPECT_EQ(spread_subset(p, 40000).size(), 40000u);  // the budget covers the cloud: all of it
    EXPECT_EQ(spread_subset(p, 50000).size(), 40000u);
}

TEST(PreviewBudget, SubsetIsSpreadOverSpaceInScanlineAndShuffledOrder) {
    std::vector<glm::vec3> p = grid_points();
    // 1,600 of 40,000 points: one per 5 x 5 block on average, so every cell of a 20 x 20 partition (100
    // points each) should get about 4; a stride of 25 in row order would leave 16 of every 20 rows empty.
    EXPECT_EQ(empty_cells(p, spread_subset(p, 1600), 20), 0);
    std::mt19937 rng(7);
    std::shuffle(p.begin(), p.end(), rng);
    EXPECT_EQ(empty_cells(p, spread_subset(p, 1600), 20), 0);
    // The old plain stride does leave cells empty (the test can fail).
    std::vector<glm::vec3> rows = grid_points();
    std::vector<std::uint32_t> stride;
    for (std::uint32_t i = 0; i < rows.size(); i += 25) stride.push_back(i);
    EXPECT_GT(empty_cells(rows, stride, 20), 0);
}

TEST(PreviewBudget, AppliesOnlyToActiveFramesOfCloudsOverTheBudget) {
    ecs::Registry reg;
    EXPECT_EQ(preview_budget_for(reg, 1'000'000), 0u);  // no resource: no budget
    set_preview_active(reg, false);
    EXPECT_EQ(reg.try_resource<PreviewBudget>(), nullptr);  // nothing created to say "off"
    set_preview_active(reg, true);
    EXPECT_EQ(preview_budget_for(reg, 1'000'000), kDefaultPreviewBudget);
    EXPECT_EQ(preview_budget_for(reg, kDefaultPreviewBudget), 0u);  // fits: every point
    reg.resource<PreviewBudget>().points = 0;                       // the setting's "off"
    EXPECT_EQ(preview_budget_for(reg, 1'000'000), 0u);
    reg.resource<PreviewBudget>().points = 10;
    set_preview_active(reg, false);
    EXPECT_EQ(preview_budget_for(reg, 1'000'000), 0u);
    EXPECT_EQ(preview_radius_scale(1000, 1000), 1.0f);          // nothing left out: unchanged
    EXPECT_GE(preview_radius_scale(1'000'000, 10'000), 10.0f);  // at least the same area in all
    EXPECT_LE(preview_radius_scale(1'000'000, 10'000), 15.0f);
}

TEST(PreviewBudget, GaussianCloudsGetTheSmallerOfTheirOwnCapAndTheSetting) {
    ecs::Registry reg;
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), 0u);  // no resource: no budget
    set_preview_active(reg, true);
    static_assert(kDefaultGaussianPreviewBudget < kDefaultPreviewBudget);
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), kDefaultGaussianPreviewBudget);
    EXPECT_EQ(preview_budget_for(reg, 1'000'000), kDefaultPreviewBudget);  // surface splats unchanged
    EXPECT_EQ(gaussian_preview_budget_for(reg, kDefaultGaussianPreviewBudget), 0u);  // fits
    auto& b = reg.resource<PreviewBudget>();
    b.points = 10'000;  // a smaller setting wins
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), 10'000u);
    b.points = 200'000, b.gaussians = 0;  // no cap of their own: the setting
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), 200'000u);
    b.points = 0;  // the setting's "off" turns Gaussians' off too
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), 0u);
    b.points = 10'000;
    set_preview_active(reg, false);
    EXPECT_EQ(gaussian_preview_budget_for(reg, 1'000'000), 0u);
}
