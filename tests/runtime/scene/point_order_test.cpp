// Point order (runtime/scene/point_order.h): the Morton codes against a bit-by-bit interleave written here,
// the order sorted by them with ties in input order, and permute() moving every column of both kinds
// together, checked point by point through a map from position to all of a point's attributes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "runtime/scene/point_order.h"

namespace sffd {
namespace {

// Reference: bit b of the quantised x, y, z goes to bits 3b+2, 3b+1, 3b of the code, one bit at a time.
std::uint64_t reference_code(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    std::uint64_t code = 0;
    for (int bit = int(kMortonBits) - 1; bit >= 0; --bit) {
        code = code << 1 | ((x >> bit) & 1u);
        code = code << 1 | ((y >> bit) & 1u);
        code = code << 1 | ((z >> bit) & 1u);
    }
    return code;
}

// Reference quantisation: 2^21 cells across the box of the points, the top face in the last cell.
std::array<std::uint32_t, 3> reference_cells(const glm::vec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
    std::array<std::uint32_t, 3> q{};
    for (int a = 0; a < 3; ++a) {
        if (hi[a] <= lo[a]) continue;
        const double t = (double(p[a]) - lo[a]) / (hi[a] - lo[a]);
        q[std::size_t(a)] = std::min<std::uint32_t>(std::uint32_t(std::floor(t * 2097152.0)), 2097151u);
    }
    return q;
}

std::vector<glm::vec3> random_points(std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-3.0f, 5.0f);
    std::vector<glm::vec3> p(n);
    for (glm::vec3& v : p) v = {u(rng), u(rng) * 0.5f, u(rng) * 2.0f};
    return p;
}

TEST(PointOrder, MortonCodeIsTheBitByBitInterleave) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::uint32_t> q(0, (1u << kMortonBits) - 1);
    for (int i = 0; i < 10000; ++i) {
        const std::uint32_t x = q(rng), y = q(rng), z = q(rng);
        ASSERT_EQ(morton_code({x, y, z}), reference_code(x, y, z)) << x << " " << y << " " << z;
    }
    EXPECT_EQ(morton_code({1, 0, 0}), 4u);
    EXPECT_EQ(morton_code({0, 1, 0}), 2u);
    EXPECT_EQ(morton_code({0, 0, 1}), 1u);
    EXPECT_EQ(morton_code({2097151, 2097151, 2097151}), (std::uint64_t(1) << 63) - 1);
}

TEST(PointOrder, OrderSortsByTheReferenceCodesWithTiesInInputOrder) {
    std::vector<glm::vec3> p = random_points(20000, 11);
    // Duplicates (equal codes) and a flat axis-aligned run must keep their input order.
    for (std::size_t i = 0; i < 500; ++i) p[10000 + i] = p[200 + i];
    p[123] = glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
    glm::dvec3 lo(1e30), hi(-1e30);
    for (std::size_t i = 0; i < p.size(); ++i)
        if (i != 123) lo = glm::min(lo, glm::dvec3(p[i])), hi = glm::max(hi, glm::dvec3(p[i]));
    const std::vector<std::uint32_t> perm = morton_order(p);
    ASSERT_TRUE(is_permutation_of(perm, p.size()));
    EXPECT_EQ(perm.back(), 123u);  // the non-finite point last
    std::size_t ties = 0;
    for (std::size_t t = 0; t + 2 < perm.size(); ++t) {
        const auto a = reference_cells(p[perm[t]], lo, hi), b = reference_cells(p[perm[t + 1]], lo, hi);
        const std::uint64_t ca = reference_code(a[0], a[1], a[2]), cb = reference_code(b[0], b[1], b[2]);
        ASSERT_LE(ca, cb) << "at " << t;
        if (ca == cb) {
            ++ties;
            ASSERT_LT(perm[t], perm[t + 1]) << "tie at " << t;
        }
    }
    EXPECT_GE(ties, 500u);
    EXPECT_EQ(morton_order(p), perm);  // deterministic
}

TEST(PointOrder, AFlatCloudOrdersByItsOtherAxes) {
    // Every z equal: the z cell is 0 for all, the order is the 2D Morton order of x and y.
    std::vector<glm::vec3> p = {{1, 1, 2}, {0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
    EXPECT_EQ(morton_order(p), (std::vector<std::uint32_t>{1, 3, 2, 0}));
}

// Every attribute of a surface point, as bytes, keyed by its position's bytes.
using Key = std::array<float, 3>;
Key key(const glm::vec3& p) { return {p.x, p.y, p.z}; }

SplatCloud full_surface_cloud(std::size_t n) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    SplatCloud c;
    c.origin = glm::dvec3(1e6, -2.0, 3.0);
    c.positions = random_points(n, 3);
    for (std::size_t i = 0; i < n; ++i) {
        c.normals.push_back({u(rng), u(rng), u(rng)});
        c.axis_u.push_back({u(rng), u(rng), u(rng)});
        c.axis_v.push_back({u(rng), u(rng), u(rng)});
        c.colors.push_back(std::uint32_t(rng()));
        c.uvs.push_back({u(rng), u(rng)});
        c.uv_axes.push_back({u(rng), u(rng), u(rng), u(rng)});
    }
    return c;
}

TEST(PointOrder, PermuteMovesEverySurfaceColumnWithItsPoint) {
    const SplatCloud in = full_surface_cloud(5000);
    using Attrs = std::tuple<Key, Key, Key, std::uint32_t, std::array<float, 2>, std::array<float, 4>>;
    std::map<Key, Attrs> by_position;
    for (std::size_t i = 0; i < in.size(); ++i)
        by_position[key(in.positions[i])] = {
            key(in.normals[i]),
            key(in.axis_u[i]),
            key(in.axis_v[i]),
            in.colors[i],
            std::array<float, 2>{in.uvs[i].x, in.uvs[i].y},
            std::array<float, 4>{in.uv_axes[i].x, in.uv_axes[i].y, in.uv_axes[i].z, in.uv_axes[i].w}};
    ASSERT_EQ(by_position.size(), in.size());
    SplatCloud out = in;
    const std::vector<std::uint32_t> perm = morton_order(out.positions);
    ASSERT_TRUE(permute(out, perm));
    ASSERT_EQ(out.size(), in.size());
    EXPECT_EQ(out.origin, in.origin);
    std::size_t moved = 0;
    for (std::size_t t = 0; t < out.size(); ++t) {
        EXPECT_EQ(key(out.positions[t]), key(in.positions[perm[t]]));
        const auto it = by_position.find(key(out.positions[t]));
        ASSERT_NE(it, by_position.end());
        const Attrs got{
            key(out.normals[t]),
            key(out.axis_u[t]),
            key(out.axis_v[t]),
            out.colors[t],
            std::array<float, 2>{out.uvs[t].x, out.uvs[t].y},
            std::array<float, 4>{out.uv_axes[t].x, out.uv_axes[t].y, out.uv_axes[t].z, out.uv_axes[t].w}};
        EXPECT_EQ(got, it->second) << "point " << t;
        moved += perm[t] != t;
        by_position.erase(it);  // each input point appears once
    }
    EXPECT_TRUE(by_position.empty());
    EXPECT_GT(moved, in.size() / 2);
}

TEST(PointOrder, PermuteMovesEveryGaussianColumnWithItsPoint) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    GaussianCloud g;
    g.sh_degree = 2;
    const std::size_t n = 3000, K = std::size_t(sh_coeffs(2)) * 3;
    g.positions = random_points(n, 4);
    for (std::size_t i = 0; i < n; ++i) {
        g.scales.push_back({u(rng), u(rng), u(rng)});
        g.rotations.push_back(glm::quat(u(rng), u(rng), u(rng), u(rng)));
        g.opacities.push_back(u(rng));
        for (std::size_t k = 0; k < K; ++k) g.sh.push_back(u(rng));
        g.sh_frames.push_back(glm::mat3(u(rng)));
    }
    std::map<Key, std::vector<float>> by_position;
    auto attrs = [&](const GaussianCloud& c, std::size_t i) {
        std::vector<float> a = {c.scales[i].x,    c.scales[i].y,    c.scales[i].z,
                                c.rotations[i].w, c.rotations[i].x, c.rotations[i].y,
                                c.rotations[i].z, c.opacities[i],   c.sh_frames[i][0][0]};
        a.insert(a.end(), c.sh.begin() + std::ptrdiff_t(i * K), c.sh.begin() + std::ptrdiff_t((i + 1) * K));
        return a;
    };
    for (std::size_t i = 0; i < n; ++i) by_position[key(g.positions[i])] = attrs(g, i);
    GaussianCloud out = g;
    ASSERT_TRUE(permute(out, morton_order(out.positions)));
    ASSERT_EQ(out.sh.size(), g.sh.size());
    for (std::size_t t = 0; t < n; ++t) {
        const auto it = by_position.find(key(out.positions[t]));
        ASSERT_NE(it, by_position.end());
        EXPECT_EQ(attrs(out, t), it->second) << "Gaussian " << t;
        by_position.erase(it);
    }
    EXPECT_TRUE(by_position.empty());
}

TEST(PointOrder, PermuteRefusesABadOrderOrAColumnOfTheWrongLengthAndChangesNothing) {
    SplatCloud c = full_surface_cloud(10);
    const SplatCloud before = c;
    Status s = permute(c, std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 8});
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message(), "permute(): the order is not a permutation of the cloud's 10 points");
    c.colors.pop_back();
    s = permute(c, morton_order(c.positions));
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message(), "permute(): column 'colors' has 9 values, the cloud's points need 10");
    EXPECT_EQ(std::memcmp(c.positions.data(), before.positions.data(), 10 * sizeof(glm::vec3)), 0);
}

TEST(PointOrder, PageCompactnessOfSlabsAndBlocks) {
    // 4 pages of a 64 x 64 x 64 grid in x-fastest order: each page is a slab of 16 z-layers (the whole x
    // and y). In Morton order each page is two octants (x and y halved, the whole z): a larger volume
    // share here, a smaller diagonal.
    std::vector<glm::vec3> p;
    for (int z = 0; z < 64; ++z)
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) p.push_back(glm::vec3(x, y, z));
    const PageCompactness slabs = page_compactness(p);
    EXPECT_EQ(slabs.pages, 4u);
    EXPECT_NEAR(slabs.mean_volume_share, 15.0 / 63.0, 1e-12);
    EXPECT_NEAR(slabs.mean_diagonal_share, std::sqrt(2.0 + (15.0 / 63.0) * (15.0 / 63.0)) / std::sqrt(3.0),
                1e-12);
    std::vector<glm::vec3> m = p;
    const std::vector<std::uint32_t> perm = morton_order(m);
    for (std::size_t t = 0; t < perm.size(); ++t) m[t] = p[perm[t]];
    const PageCompactness blocks = page_compactness(m);
    EXPECT_NEAR(blocks.mean_volume_share, 31.0 / 63.0 * 31.0 / 63.0, 1e-12);
    EXPECT_LT(blocks.mean_diagonal_share, slabs.mean_diagonal_share);
    EXPECT_EQ(page_compactness(std::vector<glm::vec3>{}).pages, 0u);
}

}  // namespace
}  // namespace sffd
