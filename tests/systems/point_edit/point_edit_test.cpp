// The point operations on both cloud kinds: the flags each leaves, the exact content of a separated or
// duplicated entity (point by point against the source), undo and redo back to identical state, and each
// step's memory against 2 bytes a changed point plus a constant.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "runtime/scene/point_pages.h"
#include "systems/point_edit/point_edit.h"
#include "tests/systems/point_edit/test_clouds.h"

namespace sffd::point_edit {
namespace {

using test::add_cloud;
using test::random_flags;

const std::vector<std::uint8_t>& bits_of(const ecs::Registry& reg, ecs::Entity e) {
    return reg.get<PointFlags>(e).bits;
}

bool selected(std::uint8_t b) { return (b & (kPointSelected | kPointGone)) == kPointSelected; }

// 2 bytes a changed point, plus a constant: the step object, its label and one page record per page of
// the cloud (at most; 16 for 1M points).
std::size_t budget(std::size_t changed, std::size_t points) {
    return 2 * changed + 256 + PointSet::kPageOverhead * page_count(points);
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Every column of `part` equals the source's at the source indices `from`, in order.
void expect_part_of(const SplatCloud& src, const SplatCloud& part, const std::vector<std::size_t>& from) {
    ASSERT_EQ(part.size(), from.size());
    EXPECT_EQ(part.origin, src.origin);
    for (std::size_t k = 0; k < from.size(); ++k) {
        const std::size_t i = from[k];
        ASSERT_EQ(part.positions[k], src.positions[i]) << k;
        ASSERT_EQ(part.normals[k], src.normals[i]);
        ASSERT_EQ(part.axis_u[k], src.axis_u[i]);
        ASSERT_EQ(part.axis_v[k], src.axis_v[i]);
        ASSERT_EQ(part.colors[k], src.colors[i]);
        ASSERT_EQ(part.uvs[k], src.uvs[i]);
        ASSERT_EQ(part.uv_axes[k], src.uv_axes[i]);
    }
    EXPECT_EQ(part.texture.path, src.texture.path);
    EXPECT_EQ(part.texture.width, src.texture.width);
    EXPECT_EQ(part.texture.rgba8, src.texture.rgba8);
}

void expect_part_of(const GaussianCloud& src, const GaussianCloud& part,
                    const std::vector<std::size_t>& from) {
    ASSERT_EQ(part.size(), from.size());
    EXPECT_EQ(part.origin, src.origin);
    EXPECT_EQ(part.sh_degree, src.sh_degree);
    const std::size_t k3 = std::size_t(sh_coeffs(src.sh_degree)) * 3;
    ASSERT_EQ(part.sh.size(), from.size() * k3);
    EXPECT_TRUE(part.sh_frames.empty());
    for (std::size_t k = 0; k < from.size(); ++k) {
        const std::size_t i = from[k];
        ASSERT_EQ(part.positions[k], src.positions[i]) << k;
        ASSERT_EQ(part.scales[k], src.scales[i]);
        ASSERT_EQ(part.rotations[k], src.rotations[i]);
        ASSERT_EQ(part.opacities[k], src.opacities[i]);
        for (std::size_t j = 0; j < k3; ++j) ASSERT_EQ(part.sh[k * k3 + j], src.sh[i * k3 + j]);
    }
}

template <class Cloud>
Cloud make_cloud(std::size_t n);
template <>
SplatCloud make_cloud<SplatCloud>(std::size_t n) {
    return test::surface_cloud(n);
}
template <>
GaussianCloud make_cloud<GaussianCloud>(std::size_t n) {
    return test::gaussian_cloud(n, 2);
}

template <class Cloud>
class PointEditTest : public ::testing::Test {};
using Kinds = ::testing::Types<SplatCloud, GaussianCloud>;
TYPED_TEST_SUITE(PointEditTest, Kinds);

TYPED_TEST(PointEditTest, HideUnhideDeleteFlipExactlyTheirPointsAndUndoToIdenticalBits) {
    using Cloud = TypeParam;
    ecs::Registry reg;
    const std::size_t n = 2 * kPagePoints + 777;
    const auto start = random_flags(n, 0.3, 11);
    const ecs::Entity e = add_cloud(reg, make_cloud<Cloud>(n), start);
    const std::uint64_t v0 = reg.version<PointFlags>(e);

    PointEditStep hide = hide_selected(reg, e);
    const auto after_hide = bits_of(reg, e);
    std::size_t hidden_now = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (selected(start[i])) {
            ++hidden_now;
            ASSERT_EQ(after_hide[i], std::uint8_t((start[i] | kPointHidden) & ~kPointSelected)) << i;
        } else {
            ASSERT_EQ(after_hide[i], start[i]) << i;
        }
    }
    EXPECT_EQ(hide.points.size(), hidden_now);
    EXPECT_GT(reg.version<PointFlags>(e), v0);
    EXPECT_LE(hide.bytes(), budget(hide.points.size(), n));
    EXPECT_EQ(count_points(reg, e).selected, 0u);

    PointEditStep unhide = unhide_all(reg, e);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t b = after_hide[i];
        const bool was = (b & kPointHidden) && !(b & kPointDeleted);
        ASSERT_EQ(bits_of(reg, e)[i], was ? std::uint8_t(b & ~kPointHidden) : b) << i;
    }
    EXPECT_LE(unhide.bytes(), budget(unhide.points.size(), n));

    undo(reg, unhide);
    EXPECT_EQ(bits_of(reg, e), after_hide);
    undo(reg, hide);
    EXPECT_EQ(bits_of(reg, e), start);
    redo(reg, hide);
    EXPECT_EQ(bits_of(reg, e), after_hide);
    undo(reg, hide);

    PointEditStep del = delete_selected(reg, e);
    for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(bits_of(reg, e)[i],
                  selected(start[i]) ? std::uint8_t((start[i] | kPointDeleted) & ~kPointSelected) : start[i]);
    EXPECT_EQ(reg.get<Cloud>(e).size(), n);  // the points stay for undo
    const auto after_del = bits_of(reg, e);
    for (int round = 0; round < 3; ++round) {
        undo(reg, del);
        ASSERT_EQ(bits_of(reg, e), start);
        redo(reg, del);
        ASSERT_EQ(bits_of(reg, e), after_del);
    }
    EXPECT_LE(del.bytes(), budget(del.points.size(), n));
}

TYPED_TEST(PointEditTest, SeparateMakesAPartWithEveryColumnOfTheSelectedPoints) {
    using Cloud = TypeParam;
    ecs::Registry reg;
    const std::size_t n = kPagePoints + 4321;
    const auto start = random_flags(n, 0.4, 5);
    const ecs::Entity e = add_cloud(reg, make_cloud<Cloud>(n), start);
    const Cloud source = reg.get<Cloud>(e);
    std::vector<std::size_t> from;
    for (std::size_t i = 0; i < n; ++i)
        if (selected(start[i])) from.push_back(i);
    ASSERT_GT(from.size(), 1000u);

    PointEditStep step = separate_selected(reg, e);
    ASSERT_TRUE(reg.valid(step.created));
    const ecs::Entity part = step.created;
    ASSERT_TRUE(reg.has<Cloud>(part));
    expect_part_of(source, reg.get<Cloud>(part), from);
    const auto& w = reg.get<PointWeights>(part).values;
    ASSERT_EQ(w.size(), from.size());
    for (std::size_t k = 0; k < from.size(); ++k) ASSERT_EQ(w[k], reg.get<PointWeights>(e).values[from[k]]);
    EXPECT_EQ(reg.get<Name>(part).value, "scan.part");
    EXPECT_EQ(reg.get<Transform>(part).translation, reg.get<Transform>(e).translation);
    EXPECT_EQ(reg.get<Transform>(part).scale, reg.get<Transform>(e).scale);
    EXPECT_EQ(reg.get<SplatMaterial>(part), reg.get<SplatMaterial>(e));
    EXPECT_FALSE(reg.has<Deformers>(part));
    EXPECT_FALSE(reg.has<PointFlags>(part));
    EXPECT_TRUE(reg.has<PointPages>(part));
    // The originals are deleted and out of the selection; the source cloud is untouched.
    for (std::size_t i : from)
        ASSERT_EQ(bits_of(reg, e)[i], std::uint8_t(kPointDeleted | (start[i] & ~kPointSelected)));
    EXPECT_EQ(count_points(reg, e).selected, 0u);
    EXPECT_EQ(reg.get<Cloud>(e).size(), n);
    EXPECT_LE(step.bytes(), budget(from.size(), n));
    const auto after = bits_of(reg, e);

    undo(reg, step);
    EXPECT_FALSE(reg.valid(part));
    EXPECT_FALSE(step.created);
    EXPECT_EQ(bits_of(reg, e), start);
    EXPECT_EQ(reg.count<Cloud>(), 1u);

    const ecs::Entity again = redo(reg, step);
    ASSERT_TRUE(reg.valid(again));
    EXPECT_EQ(step.created, again);
    EXPECT_NE(again, part);  // a new id: the editor maps the old one to it
    expect_part_of(source, reg.get<Cloud>(again), from);
    EXPECT_EQ(reg.get<Name>(again).value, "scan.part");
    EXPECT_EQ(bits_of(reg, e), after);
    EXPECT_LE(step.bytes(), budget(from.size(), n));
}

TYPED_TEST(PointEditTest, DuplicateCopiesTheSelectionAndLeavesTheOriginals) {
    using Cloud = TypeParam;
    ecs::Registry reg;
    const std::size_t n = 5000;
    const auto start = random_flags(n, 0.2, 9);
    const ecs::Entity e = add_cloud(reg, make_cloud<Cloud>(n), start);
    std::vector<std::size_t> from;
    for (std::size_t i = 0; i < n; ++i)
        if (selected(start[i])) from.push_back(i);

    PointEditStep step = duplicate_selected(reg, e);
    ASSERT_TRUE(reg.valid(step.created));
    expect_part_of(reg.get<Cloud>(e), reg.get<Cloud>(step.created), from);
    EXPECT_EQ(reg.get<Name>(step.created).value, "scan.copy");
    EXPECT_EQ(bits_of(reg, e), start);
    EXPECT_LE(step.bytes(), budget(from.size(), n));
    undo(reg, step);
    EXPECT_EQ(reg.count<Cloud>(), 1u);
    EXPECT_EQ(bits_of(reg, e), start);
    redo(reg, step);
    EXPECT_EQ(reg.count<Cloud>(), 2u);
    expect_part_of(reg.get<Cloud>(e), reg.get<Cloud>(step.created), from);
}

TYPED_TEST(PointEditTest, NothingSelectedIsAnEmptyStep) {
    using Cloud = TypeParam;
    ecs::Registry reg;
    const ecs::Entity e =
        add_cloud(reg, make_cloud<Cloud>(100), std::vector<std::uint8_t>(100, kPointHidden));
    EXPECT_TRUE(hide_selected(reg, e).empty());
    EXPECT_TRUE(delete_selected(reg, e).empty());
    const PointEditStep sep = separate_selected(reg, e);
    EXPECT_TRUE(sep.empty());
    EXPECT_FALSE(sep.created);
    EXPECT_EQ(reg.count<Cloud>(), 1u);
    // Selected but hidden points are not the selection either.
    reg.patch<PointFlags>(e).bits.assign(100, kPointSelected | kPointHidden);
    EXPECT_TRUE(duplicate_selected(reg, e).empty());
    // No flags at all: no selection.
    const ecs::Entity bare = reg.create();
    reg.emplace<Cloud>(bare, make_cloud<Cloud>(10));
    EXPECT_TRUE(separate_selected(reg, bare).empty());
    EXPECT_TRUE(unhide_all(reg, bare).empty());
    EXPECT_TRUE(hide_selected(reg, reg.create()).empty());
}

// Memory of a step on 1M points: a sparse selection costs its 2 bytes a point, a whole-cloud selection is
// held by masks (8 KB a page: 1/8 byte a point).
TEST(PointEditMemory, StepsOn1MPointsStayWithinTwoBytesAChangedPoint) {
    ecs::Registry reg;
    const std::size_t n = 1'000'000;
    std::vector<std::uint8_t> bits(n, 0);
    for (std::size_t i = 0; i < n; i += 3) bits[i] = kPointSelected;
    const ecs::Entity e = add_cloud(reg, test::gaussian_cloud(n, 0), bits);
    PointEditStep del = delete_selected(reg, e);
    EXPECT_EQ(del.points.size(), (n + 2) / 3);
    EXPECT_LE(del.bytes(), budget(del.points.size(), n));
    EXPECT_LE(del.bytes(), 16 * (8192 + PointSet::kPageOverhead) + 256);  // masks, not offsets
    PointEditStep unhide = unhide_all(reg, e);
    EXPECT_TRUE(unhide.empty());
    EXPECT_LE(unhide.bytes(), 256u);
    undo(reg, del);
    reg.patch<PointFlags>(e).bits.assign(n, 0);
    for (std::size_t i = 0; i < n; i += 1000) reg.patch<PointFlags>(e).bits[i] = kPointSelected;
    PointEditStep sep = separate_selected(reg, e);
    EXPECT_EQ(sep.points.size(), 1000u);
    EXPECT_LE(sep.bytes(), budget(1000, n));
}

}  // namespace
}  // namespace sffd::point_edit
