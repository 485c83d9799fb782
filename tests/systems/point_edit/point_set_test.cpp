// PointSet: the indices it holds are exactly those asked for, in order, and its memory is at most 2 bytes
// a point plus a constant per touched page, whichever form (offsets or mask) each page takes.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "systems/point_edit/point_edit.h"

namespace sffd::point_edit {
namespace {

std::vector<std::size_t> listed(const PointSet& s) {
    std::vector<std::size_t> out;
    s.for_each([&](std::size_t i) { out.push_back(i); });
    return out;
}

std::vector<std::size_t> expected(const std::vector<std::uint8_t>& bits, std::uint8_t mask,
                                  std::uint8_t want) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < bits.size(); ++i)
        if ((bits[i] & mask) == want) out.push_back(i);
    return out;
}

std::size_t budget(const PointSet& s) {
    return 2 * s.size() + PointSet::kPageOverhead * s.pages() + sizeof(PointSet);
}

TEST(PointSet, HoldsExactlyTheMatchingIndicesAtEveryDensity) {
    // 4 pages and a partial one: sparse, at the offsets/mask boundary (4,096 and 4,097), dense, full.
    const std::size_t n = 4 * kPagePoints + 1234;
    std::vector<std::uint8_t> bits(n, 0);
    std::mt19937 rng(7);
    for (std::size_t i = 0; i < kPagePoints; i += 37) bits[i] = kPointSelected;
    for (std::size_t k = 0, placed = 0; placed < 4096; k += 13, ++placed)
        bits[kPagePoints + k] = kPointSelected;
    for (std::size_t k = 0, placed = 0; placed < 4097; k += 11, ++placed)
        bits[2 * kPagePoints + k] = kPointSelected;
    for (std::size_t i = 3 * kPagePoints; i < n; ++i) bits[i] = (rng() % 3 == 0) ? 0 : kPointSelected;
    bits[n - 1] = kPointSelected;
    const PointSet s = PointSet::where(bits, kPointSelected, kPointSelected);
    const auto want = expected(bits, kPointSelected, kPointSelected);
    EXPECT_EQ(s.size(), want.size());
    EXPECT_EQ(listed(s), want);
    EXPECT_EQ(s.pages(), 5u);
    EXPECT_LE(s.bytes(), budget(s));
}

TEST(PointSet, MaskAndWantSelectByEveryBit) {
    std::vector<std::uint8_t> bits(3 * kPagePoints + 5);
    std::mt19937 rng(3);
    for (auto& b : bits) b = std::uint8_t(rng() & 7u);
    for (std::uint8_t want : {0, 1, 2, 3, 5, 7}) {
        const PointSet s = PointSet::where(bits, 7, want);
        EXPECT_EQ(listed(s), expected(bits, 7, want)) << int(want);
        EXPECT_LE(s.bytes(), budget(s));
    }
}

TEST(PointSet, EmptyPagesCostNothing) {
    std::vector<std::uint8_t> bits(16 * kPagePoints, 0);
    bits[5 * kPagePoints + 17] = kPointHidden;
    const PointSet s = PointSet::where(bits, kPointHidden, kPointHidden);
    EXPECT_EQ(s.size(), 1u);
    EXPECT_EQ(s.pages(), 1u);
    EXPECT_EQ(listed(s), std::vector<std::size_t>{5 * kPagePoints + 17});
    EXPECT_LE(s.bytes(), sizeof(PointSet) + PointSet::kPageOverhead + 2);
    const PointSet none = PointSet::where(bits, kPointSelected, kPointSelected);
    EXPECT_TRUE(none.empty());
    EXPECT_EQ(none.bytes(), sizeof(PointSet));
}

TEST(PointSet, AFullPageIsAMaskOf8KB) {
    std::vector<std::uint8_t> bits(kPagePoints, kPointSelected);
    const PointSet s = PointSet::where(bits, kPointSelected, kPointSelected);
    EXPECT_EQ(s.size(), kPagePoints);
    EXPECT_LE(s.bytes(), sizeof(PointSet) + PointSet::kPageOverhead + 8192);
}

}  // namespace
}  // namespace sffd::point_edit
