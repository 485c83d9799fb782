#include "systems/editor/lattice_tools.h"

#include <numeric>

#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

using namespace sffd;
using namespace sffd::editor;

namespace {
Lattice grid(int l, int m, int n) {
    Lattice lat;
    lat.divisions = {l, m, n};
    lat.origin = {-1, -1, -1};
    lat.axes = {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)};
    for (int i = 0; i <= l; ++i)
        for (int j = 0; j <= m; ++j)
            for (int k = 0; k <= n; ++k)
                lat.rest.push_back(lat.origin + double(i) / l * lat.axes[0] + double(j) / m * lat.axes[1] +
                                   double(k) / n * lat.axes[2]);
    lat.current = lat.rest;
    return lat;
}
}  // namespace

TEST(LatticeTools, OuterLayerIsEverythingButTheInterior) {
    const Lattice lat = grid(3, 4, 5);
    const auto mask = outer_layer_mask(lat);
    const int outer = std::accumulate(mask.begin(), mask.end(), 0);
    EXPECT_EQ(outer, 4 * 5 * 6 - 2 * 3 * 4);
    EXPECT_EQ(mask[lat.index(1, 2, 3)], 0);
    EXPECT_EQ(mask[lat.index(3, 2, 3)], 1);
    EXPECT_EQ(mask[lat.index(1, 0, 3)], 1);
    EXPECT_EQ(mask[lat.index(1, 2, 5)], 1);
}

TEST(LatticeTools, LocalEditsSkipPinnedPointsGlobalEditsTakeAll) {
    const Lattice lat = grid(2, 2, 2);
    const std::uint32_t centre = static_cast<std::uint32_t>(lat.index(1, 1, 1));
    const std::vector<std::uint32_t> sel = {0, centre, centre, 999};
    EXPECT_EQ(editable_points(lat, sel, ToolScope::local, true), std::vector<std::uint32_t>{centre});
    EXPECT_EQ(editable_points(lat, sel, ToolScope::local, false), (std::vector<std::uint32_t>{0, centre}));
    EXPECT_EQ(editable_points(lat, sel, ToolScope::global, true).size(), lat.size());
}

TEST(LatticeTools, InsideBoxMask) {
    const Lattice lat = grid(4, 4, 4);  // points at -1, -0.5, 0, 0.5, 1 per axis
    const auto mask = inside_box_mask(lat, glm::dvec3(-0.6), glm::dvec3(0.6));
    EXPECT_EQ(std::accumulate(mask.begin(), mask.end(), 0), 27);
    EXPECT_EQ(mask[lat.index(2, 2, 2)], 1);
    EXPECT_EQ(mask[lat.index(0, 2, 2)], 0);
}

TEST(LatticeTools, StretchMovesOnlyTheChosenPoints) {
    const Lattice lat = grid(2, 2, 2);
    std::vector<glm::dvec3> out(lat.size());
    const std::vector<std::uint32_t> idx = {4, 13};
    stretch_points(lat.current, out, idx, {0.25, -0.5, 1.0});
    for (std::size_t c = 0; c < out.size(); ++c) {
        const bool moved = c == 4 || c == 13;
        EXPECT_EQ(out[c], lat.current[c] + (moved ? glm::dvec3(0.25, -0.5, 1.0) : glm::dvec3(0.0))) << c;
    }
}

TEST(LatticeTools, TwistMatchesAQuaternionRotationAboutThePivot) {
    const Lattice lat = grid(3, 3, 3);
    std::vector<std::uint32_t> all(lat.size());
    std::iota(all.begin(), all.end(), 0u);
    const glm::dvec3 axis = glm::normalize(glm::dvec3(1, 2, -0.5)), pivot(0.2, -0.3, 0.1);
    const double angle = 2.4;
    std::vector<glm::dvec3> out(lat.size());
    twist_points(lat.current, out, all, pivot, axis, angle);
    const glm::dquat q = glm::angleAxis(angle, axis);
    for (std::size_t c = 0; c < out.size(); ++c) {
        const glm::dvec3 ref = pivot + q * (lat.current[c] - pivot);
        EXPECT_NEAR(glm::length(out[c] - ref), 0.0, 1e-12) << c;
    }
    // The pivot of a selection is its centroid.
    const std::vector<std::uint32_t> two = {0, static_cast<std::uint32_t>(lat.size() - 1)};
    EXPECT_NEAR(glm::length(centroid(lat, two)), 0.0, 1e-15);
}
