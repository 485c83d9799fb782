// Selection deltas (round trip, composition, memory bound), modes, the whole-cloud commands, colour
// selection and grow / shrink by a world distance on a lattice of points (expected sets by brute force).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "runtime/ecs/registry.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "systems/point_select/point_select.h"
#include "test_clouds.h"

namespace sffd::point_select {
namespace {

std::vector<std::uint8_t> random_bits(std::size_t n, double p_selected, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::bernoulli_distribution sel(p_selected);
    std::vector<std::uint8_t> b(n);
    for (auto& x : b) x = std::uint8_t((sel(rng) ? kPointSelected : 0) | (rng() % 5 == 0 ? 0x10 : 0));
    return b;
}

TEST(SelectionDelta, RoundTripsAndStaysWithinTwoBytesAPoint) {
    const std::size_t n = 3 * kPagePoints + 1234;  // four pages, the last one short
    const std::vector<std::uint8_t> before = random_bits(n, 0.3, 1);
    std::vector<std::uint8_t> after = before;
    std::mt19937 rng(2);
    // Page 0: a few changes (offsets); page 1: most points (mask); page 2: none; page 3: the last point.
    for (int k = 0; k < 100; ++k) after[rng() % kPagePoints] ^= kPointSelected;
    for (std::size_t i = kPagePoints; i < 2 * kPagePoints; ++i)
        if (rng() % 4) after[i] ^= kPointSelected;
    after[n - 1] ^= kPointSelected;
    const SelectionDelta d = delta_between(before, after);
    ASSERT_EQ(d.pages.size(), 3u);
    EXPECT_EQ(d.pages[0].page, 0u);
    EXPECT_FALSE(d.pages[0].offsets.empty());
    EXPECT_TRUE(d.pages[1].offsets.empty());
    EXPECT_EQ(d.pages[1].mask.size(), SelectionDelta::kMaskWords);
    EXPECT_EQ(d.pages[2].page, 3u);
    std::size_t changed = 0;
    for (std::size_t i = 0; i < n; ++i) changed += ((before[i] ^ after[i]) & kPointSelected) != 0;
    EXPECT_EQ(d.changed(), changed);
    EXPECT_LE(d.bytes(), 2 * d.changed() + SelectionDelta::kPageOverhead * d.pages.size() +
                             sizeof(SelectionDelta) + sizeof(SelectionDelta::Page) * d.pages.capacity());
    // The mask page holds 8 KiB for ~49,000 changed points: far under 2 bytes each.
    EXPECT_LT(d.pages[1].mask.size() * 8, 2u * d.pages[1].count);

    std::vector<std::uint8_t> bits = before;
    toggle(bits, d);
    EXPECT_EQ(bits, after);  // other bits untouched
    toggle(bits, d);
    EXPECT_EQ(bits, before);

    // indices() and delta_from_indices() agree; compose is a per-point XOR.
    EXPECT_EQ(delta_from_indices(d.indices(), n).indices(), d.indices());
    const std::vector<std::uint8_t> third = random_bits(n, 0.5, 3);
    const SelectionDelta d2 = delta_between(after, third);
    const SelectionDelta both = compose(d, d2);
    bits = before;
    toggle(bits, both);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(bits[i] & kPointSelected, third[i] & kPointSelected) << i;
    EXPECT_TRUE(compose(d, d).empty());
}

struct Cloud : ::testing::Test {
    ecs::Registry reg;
    ecs::Entity e = reg.create();
    void SetUp() override { reg.emplace<SplatCloud>(e, test::grid_cloud(100, 1, 0.0, 0.0, 0.1, 0.03f)); }
    std::vector<std::uint32_t> range(std::uint32_t a, std::uint32_t b) {
        std::vector<std::uint32_t> v;
        for (std::uint32_t i = a; i < b; ++i) v.push_back(i);
        return v;
    }
};

TEST_F(Cloud, ModesCombineCandidatesWithTheSelection) {
    const auto s = range(10, 40), c = range(30, 60);
    struct Case {
        Mode mode;
        std::vector<std::uint32_t> want;
    };
    std::vector<std::uint32_t> u, diff, inter;
    std::set_union(s.begin(), s.end(), c.begin(), c.end(), std::back_inserter(u));
    std::set_difference(s.begin(), s.end(), c.begin(), c.end(), std::back_inserter(diff));
    std::set_intersection(s.begin(), s.end(), c.begin(), c.end(), std::back_inserter(inter));
    for (const Case& k :
         {Case{Mode::set, c}, Case{Mode::add, u}, Case{Mode::remove, diff}, Case{Mode::intersect, inter}}) {
        select_none(reg, e);
        commit(reg, e, s, Mode::set);
        const std::vector<std::uint8_t> before = reg.get<PointFlags>(e).bits;
        const SelectionDelta d = commit(reg, e, c, k.mode);
        EXPECT_EQ(selected_points(reg, e), k.want) << int(k.mode);
        // Undo: the same delta again.
        EXPECT_TRUE(apply_delta(reg, e, d));
        EXPECT_EQ(reg.get<PointFlags>(e).bits, before);
    }
    EXPECT_EQ(select_mode(false, false), Mode::set);
    EXPECT_EQ(select_mode(true, false), Mode::add);
    EXPECT_EQ(select_mode(true, true), Mode::remove);
}

TEST_F(Cloud, CommandsAllNoneInvertAndAWrongSizedDelta) {
    EXPECT_EQ(select_all(reg, e).changed(), 100u);
    EXPECT_EQ(selected_count(reg, e), 100u);
    commit(reg, e, range(0, 25), Mode::remove);
    const SelectionDelta inv = invert_selection(reg, e);
    EXPECT_EQ(inv.changed(), 100u);
    EXPECT_EQ(selected_points(reg, e), range(0, 25));
    EXPECT_EQ(select_none(reg, e).changed(), 25u);
    EXPECT_EQ(selected_count(reg, e), 0u);
    // A delta made for another size is refused and changes nothing.
    SelectionDelta other = delta_from_indices(range(0, 5), 99);
    EXPECT_FALSE(apply_delta(reg, e, other));
    EXPECT_EQ(selected_count(reg, e), 0u);
    EXPECT_FALSE(apply_delta(reg, reg.create(), delta_from_indices(range(0, 5), 100)));
}

TEST(PointSelectColour, SplatColoursTexturesAndGaussianDc) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    SplatCloud c = test::grid_cloud(64, 1, 0.0, 0.0, 0.1, 0.03f);
    std::vector<glm::vec3> rgb;
    for (std::uint32_t i = 0; i < 64; ++i) {
        const std::uint32_t r = i * 4, g = 255 - i * 4, b = (i * 37) % 256;
        c.colors[i] = r | (g << 8) | (b << 16) | 0xff000000u;
        rgb.push_back(glm::vec3(float(r), float(g), float(b)) / 255.0f);
    }
    reg.emplace<SplatCloud>(e, c);
    const glm::vec3 ref = *point_colour(reg, e, 20);
    EXPECT_EQ(ref, rgb[20]);
    for (double tol : {0.0, 0.05, 0.2, 0.5}) {
        std::vector<std::uint32_t> want;
        for (std::uint32_t i = 0; i < 64; ++i)
            if (glm::length(glm::dvec3(rgb[i]) - glm::dvec3(ref)) <= tol) want.push_back(i);
        EXPECT_EQ(points_by_colour(reg, e, ref, tol), want) << tol;
    }
    EXPECT_EQ(select_by_colour(reg, e, ref, 0.0, Mode::set).indices(), std::vector<std::uint32_t>{20});

    // Texture: a 2x1 texture, left texel red, right blue; uvs pick one of them.
    SplatCloud t = test::grid_cloud(4, 1, 0.0, 0.0, 0.1, 0.03f);
    t.colors.clear();
    t.texture.width = 2, t.texture.height = 1;
    t.texture.rgba8 = {255, 0, 0, 255, 0, 0, 255, 255};
    t.uvs = {{0.25f, 0.5f}, {0.75f, 0.5f}, {1.25f, 0.5f}, {0.9f, 0.2f}};  // u repeats
    const ecs::Entity te = reg.create();
    reg.emplace<SplatCloud>(te, t);
    EXPECT_EQ(points_by_colour(reg, te, {1, 0, 0}, 0.01), (std::vector<std::uint32_t>{0, 2}));
    EXPECT_EQ(points_by_colour(reg, te, {0, 0, 1}, 0.01), (std::vector<std::uint32_t>{1, 3}));

    // Gaussians: colour = 0.5 + C0 * dc, clamped.
    GaussianCloud g = test::gaussians_of(test::grid_cloud(3, 1, 0.0, 0.0, 0.1, 0.03f), 0.01f);
    const float c0 = 0.28209479177387814f;
    g.sh = {0.4f / c0, -0.2f / c0, 0.0f, /**/ 0.4f / c0, -0.2f / c0, 0.05f / c0, /**/ 9.0f, -9.0f, 0.0f};
    const ecs::Entity ge = reg.create();
    reg.emplace<GaussianCloud>(ge, g);
    const glm::vec3 c1 = *point_colour(reg, ge, 0);
    EXPECT_NEAR(c1.x, 0.9f, 1e-6f);
    EXPECT_NEAR(c1.y, 0.3f, 1e-6f);
    EXPECT_NEAR(c1.z, 0.5f, 1e-6f);
    EXPECT_EQ(*point_colour(reg, ge, 2), glm::vec3(1.0f, 0.0f, 0.5f));
    EXPECT_EQ(points_by_colour(reg, ge, c1, 0.04), std::vector<std::uint32_t>{0});
    EXPECT_EQ(points_by_colour(reg, ge, c1, 0.06), (std::vector<std::uint32_t>{0, 1}));
    EXPECT_FALSE(point_colour(reg, ge, 3).has_value());
}

// A 9x9x9 lattice of points, spacing h: neighbours at h (6), h√2 (12), h√3 (8), 2h (6).
struct Lattice9 : ::testing::Test {
    static constexpr int kN = 9;
    static constexpr double kH = 0.1;
    ecs::Registry reg;
    ecs::Entity e = reg.create();
    PointSelectState state;
    std::vector<glm::dvec3> p;
    void SetUp() override {
        SplatCloud c;
        for (int z = 0; z < kN; ++z)
            for (int y = 0; y < kN; ++y)
                for (int x = 0; x < kN; ++x) {
                    c.positions.emplace_back(float(x * kH), float(y * kH), float(z * kH));
                    p.emplace_back(double(c.positions.back().x), double(c.positions.back().y),
                                   double(c.positions.back().z));
                }
        reg.emplace<SplatCloud>(e, c);
    }
    static std::uint32_t at(int x, int y, int z) { return std::uint32_t((z * kN + y) * kN + x); }
    // Brute force: the points of `from` (by `pred` on the current selection) within d of a point of `to`.
    std::vector<std::uint32_t> near(const std::vector<bool>& selected, bool want_selected, double d) {
        std::vector<std::uint32_t> out;
        for (std::uint32_t i = 0; i < p.size(); ++i) {
            if (selected[i] == want_selected) continue;
            for (std::uint32_t j = 0; j < p.size(); ++j)
                if (selected[j] == want_selected && glm::length(p[i] - p[j]) <= d) {
                    out.push_back(i);
                    break;
                }
        }
        return out;
    }
    std::vector<bool> mask() {
        std::vector<bool> m(p.size(), false);
        for (std::uint32_t i : selected_points(reg, e)) m[i] = true;
        return m;
    }
};

TEST_F(Lattice9, GrowAddsThePointsWithinTheDistance) {
    const std::uint32_t centre = at(4, 4, 4);
    const std::vector<std::uint32_t> one{centre};
    for (auto [d, count] : {std::pair{0.05, 0u}, {0.12, 6u}, {0.15, 18u}, {0.18, 26u}, {0.21, 32u}}) {
        commit(reg, e, one, Mode::set);
        const SelectionDelta g = grow_selection(reg, state, e, d);
        EXPECT_EQ(g.changed(), count) << d;
        EXPECT_EQ(selected_count(reg, e), count + 1) << d;
    }
    // A two-point selection near a corner, against brute force.
    commit(reg, e, std::vector<std::uint32_t>{at(0, 0, 0), at(3, 1, 0)}, Mode::set);
    const std::vector<bool> m = mask();
    const std::vector<std::uint32_t> want = near(m, true, 0.25);
    EXPECT_EQ(grow_selection(reg, state, e, 0.25).indices(), want);
}

TEST_F(Lattice9, ShrinkRemovesSelectedPointsNearUnselectedOnes) {
    // Select the 5x5x5 block in the middle; shrinking by 0.12 keeps only its 3x3x3 core.
    std::vector<std::uint32_t> block;
    for (int z = 2; z <= 6; ++z)
        for (int y = 2; y <= 6; ++y)
            for (int x = 2; x <= 6; ++x) block.push_back(at(x, y, z));
    std::sort(block.begin(), block.end());
    commit(reg, e, block, Mode::set);
    const std::vector<bool> m = mask();
    const std::vector<std::uint32_t> want = near(m, false, 0.15);  // selected, near an unselected point
    const SelectionDelta s = shrink_selection(reg, state, e, 0.15);
    EXPECT_EQ(s.indices(), want);
    EXPECT_EQ(selected_count(reg, e), 27u);
    // Undo brings the block back.
    apply_delta(reg, e, s);
    EXPECT_EQ(selected_points(reg, e), block);
    // Hidden points take no part: hiding every unselected point leaves nothing to erode against.
    PointFlags& f = reg.patch<PointFlags>(e);
    for (std::uint32_t i = 0; i < p.size(); ++i)
        if (!(f.bits[i] & kPointSelected)) f.bits[i] |= kPointHidden;
    EXPECT_TRUE(shrink_selection(reg, state, e, 0.15).empty());
    EXPECT_TRUE(grow_selection(reg, state, e, 0.15).empty());
}

}  // namespace
}  // namespace sffd::point_select
