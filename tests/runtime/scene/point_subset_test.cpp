// Subsets of a cloud (runtime/scene/point_subset.h): kept point k of the subset holds exactly the values of
// source point keep[k] in every column of both kinds (uv axes, SH of degree 3 included), the optional
// columns move with them, the texture and origin stay; the in-place forms drop deleted (save), hidden and
// deleted (export) or keep the selected points, and stamp the cloud replaced; bad input changes nothing.
#include <gtest/gtest.h>

#include "runtime/scene/point_pages.h"
#include "runtime/scene/point_subset.h"

namespace sffd {
namespace {

SplatCloud surface_cloud(std::size_t n) {
    SplatCloud c;
    c.origin = {1e6, -2e6, 3.5};
    c.texture.width = 2, c.texture.height = 1, c.texture.rgba8 = {1, 2, 3, 4, 5, 6, 7, 8};
    c.texture.path = "checker.png";
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        c.positions.push_back({f, 1 + f, 2 + f});
        c.normals.push_back({0, 1, f});
        c.axis_u.push_back({0.1f * f, 0, 0});
        c.axis_v.push_back({0, 0.2f * f, 0});
        c.colors.push_back(0x10203000u | std::uint32_t(i));
        c.uvs.push_back({f / 8, 1 - f / 8});
        c.uv_axes.push_back({f, -f, 2 * f, 0.5f - f});
    }
    return c;
}

GaussianCloud gaussian_cloud(std::size_t n, int degree) {
    GaussianCloud g;
    g.origin = {-4, 5, 6};
    g.sh_degree = degree;
    const std::size_t k = 3 * std::size_t(sh_coeffs(degree));
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        g.positions.push_back({f, -f, 2 * f});
        g.scales.push_back({0.1f + f, 0.2f, 0.3f * f});
        g.rotations.push_back(glm::normalize(glm::quat(1, f, 0, 0.5f)));
        g.opacities.push_back(0.01f * f);
        for (std::size_t j = 0; j < k; ++j) g.sh.push_back(f * 100 + float(j) / 64);
    }
    return g;
}

void expect_surface_point(const SplatCloud& sub, std::size_t k, const SplatCloud& src, std::size_t i) {
    SCOPED_TRACE("subset point " + std::to_string(k) + " = source point " + std::to_string(i));
    EXPECT_EQ(sub.positions[k], src.positions[i]);
    EXPECT_EQ(sub.normals[k], src.normals[i]);
    EXPECT_EQ(sub.axis_u[k], src.axis_u[i]);
    EXPECT_EQ(sub.axis_v[k], src.axis_v[i]);
    EXPECT_EQ(sub.colors[k], src.colors[i]);
    EXPECT_EQ(sub.uvs[k], src.uvs[i]);
    EXPECT_EQ(sub.uv_axes[k], src.uv_axes[i]);
}

void expect_gaussian_point(const GaussianCloud& sub, std::size_t k, const GaussianCloud& src, std::size_t i) {
    SCOPED_TRACE("subset point " + std::to_string(k) + " = source point " + std::to_string(i));
    EXPECT_EQ(sub.positions[k], src.positions[i]);
    EXPECT_EQ(sub.scales[k], src.scales[i]);
    EXPECT_EQ(sub.rotations[k], src.rotations[i]);
    EXPECT_EQ(sub.opacities[k], src.opacities[i]);
    const std::size_t w = 3 * std::size_t(sh_coeffs(src.sh_degree));
    for (std::size_t j = 0; j < w; ++j) ASSERT_EQ(sub.sh[k * w + j], float(i) * 100 + float(j) / 64) << j;
}

TEST(PointSubset, SurfaceSubsetByMaskAndByIndicesKeepsEveryColumnAndTheTexture) {
    const SplatCloud src = surface_cloud(9);
    const std::vector<std::uint8_t> mask{0, 1, 1, 0, 0, 1, 0, 0, 1};
    const auto keep = mask_indices(mask);
    ASSERT_EQ(keep, (std::vector<std::uint32_t>{1, 2, 5, 8}));
    auto sub = subset_points(src, keep);
    ASSERT_TRUE(sub) << sub.message();
    ASSERT_EQ(sub->size(), 4u);
    for (std::size_t k = 0; k < keep.size(); ++k) expect_surface_point(*sub, k, src, keep[k]);
    EXPECT_EQ(sub->origin, src.origin);
    EXPECT_EQ(sub->texture.rgba8, src.texture.rgba8);
    EXPECT_EQ(sub->texture.path, "checker.png");
    // An index list in any order is a gather; empty columns stay empty.
    SplatCloud bare = src;
    bare.uvs.clear(), bare.uv_axes.clear(), bare.colors.clear();
    const std::vector<std::uint32_t> order{7, 0, 7};
    auto g = subset_points(bare, order);
    ASSERT_TRUE(g);
    ASSERT_EQ(g->size(), 3u);
    EXPECT_EQ(g->positions[0], src.positions[7]);
    EXPECT_EQ(g->positions[1], src.positions[0]);
    EXPECT_EQ(g->axis_v[2], src.axis_v[7]);
    EXPECT_TRUE(g->uvs.empty() && g->uv_axes.empty() && g->colors.empty());
}

TEST(PointSubset, GaussianSubsetAtEveryShDegreeKeepsEveryCoefficient) {
    for (int degree : {0, 1, 3}) {
        SCOPED_TRACE(degree);
        const GaussianCloud src = gaussian_cloud(7, degree);
        const std::vector<std::uint32_t> keep{0, 3, 4, 6};
        auto sub = subset_points(src, keep);
        ASSERT_TRUE(sub) << sub.message();
        ASSERT_EQ(sub->size(), 4u);
        EXPECT_EQ(sub->sh_degree, degree);
        EXPECT_EQ(sub->sh.size(), 4u * 3u * std::size_t(sh_coeffs(degree)));
        EXPECT_EQ(sub->origin, src.origin);
        for (std::size_t k = 0; k < keep.size(); ++k) expect_gaussian_point(*sub, k, src, keep[k]);
        EXPECT_TRUE(sub->sh_frames.empty());
    }
    // A derived cloud's SH frames move with their points.
    GaussianCloud d = gaussian_cloud(3, 0);
    d.sh_frames = {glm::mat3(1.0f), glm::mat3(2.0f), glm::mat3(3.0f)};
    const std::vector<std::uint32_t> last{2};
    auto sub = subset_points(d, last);
    ASSERT_TRUE(sub);
    ASSERT_EQ(sub->sh_frames.size(), 1u);
    EXPECT_EQ(sub->sh_frames[0], glm::mat3(3.0f));
}

TEST(PointSubset, BadIndicesAndMisSizedColumnsAreRefused) {
    SplatCloud c = surface_cloud(4);
    const std::vector<std::uint32_t> past{1, 4};
    auto r = subset_points(c, past);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.message(), "subset_points(): index 4 (entry 1) is past the cloud's 4 points");
    c.uv_axes.pop_back();
    const std::vector<std::uint32_t> ok{0};
    auto m = subset_points(c, ok);
    ASSERT_FALSE(m);
    EXPECT_EQ(m.message(), "subset_points(): column 'uv_axes' has 3 values, the cloud's 4 points need 4");
    GaussianCloud g = gaussian_cloud(2, 3);
    g.sh.pop_back();
    auto gs = subset_points(g, ok);
    ASSERT_FALSE(gs);
    EXPECT_EQ(gs.message(), "subset_points(): column 'sh' has 95 values, the cloud's 2 points need 96");
    auto f = subset_points(PointFlags{{1, 2, 3}}, 4, ok);
    ASSERT_FALSE(f);
    EXPECT_EQ(f.message(), "subset_points(): 'flags' has 3 values for 4 points");
}

TEST(PointSubset, PointsWithFlags) {
    const PointFlags f{{0, kPointSelected, kPointHidden, kPointDeleted, kPointSelected | kPointHidden,
                        kPointSelected | kPointDeleted, kPointSelected}};
    EXPECT_EQ(points_with(&f, 7, 0, kPointDeleted), (std::vector<std::uint32_t>{0, 1, 2, 4, 6}));
    EXPECT_EQ(points_with(&f, 7, 0, kPointGone), (std::vector<std::uint32_t>{0, 1, 6}));
    EXPECT_EQ(points_with(&f, 7, kPointSelected, kPointGone), (std::vector<std::uint32_t>{1, 6}));
    EXPECT_EQ(points_with(nullptr, 3, 0, kPointGone), (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_TRUE(points_with(nullptr, 3, kPointSelected, 0).empty());
    EXPECT_TRUE(points_with(&f, 8, kPointSelected, 0).empty()) << "flags of another size: none";
    EXPECT_TRUE(any_point_flagged(&f, 7, kPointDeleted));
    EXPECT_FALSE(any_point_flagged(&f, 8, kPointDeleted));
}

// Flags of the 6 points: 0 plain, 1 selected, 2 hidden, 3 deleted, 4 selected+hidden, 5 selected.
const std::vector<std::uint8_t> kFlags{
    0, kPointSelected, kPointHidden, kPointDeleted, kPointSelected | kPointHidden, kPointSelected};
const std::vector<float> kWeights{0.0f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f};

template <class Cloud, class Check>
void check_in_place(const Cloud& src, Check&& point_equal) {
    struct Case {
        const char* what;
        std::vector<std::uint32_t> kept;
    };
    for (const Case& k :
         {Case{"save", {0, 1, 2, 4, 5}}, Case{"export", {0, 1, 5}}, Case{"selected", {1, 5}}}) {
        SCOPED_TRACE(k.what);
        ecs::Registry r;
        const ecs::Entity e = r.create();
        r.emplace<Cloud>(e, src);
        r.emplace<PointFlags>(e, PointFlags{kFlags});
        r.emplace<PointWeights>(e, PointWeights{kWeights});
        refresh_point_pages(r, e);
        const std::uint64_t v = r.version<Cloud>(e), clock = r.get<PointPages>(e).clock;
        const std::string what = k.what;
        Result<std::size_t> n = what == "save"     ? drop_gone_points(r, e, PointDrop::deleted)
                                : what == "export" ? drop_gone_points(r, e, PointDrop::hidden_and_deleted)
                                                   : extract_points(r, e);
        ASSERT_TRUE(n) << n.message();
        EXPECT_EQ(*n, 6 - k.kept.size());
        const Cloud& c = r.get<Cloud>(e);
        ASSERT_EQ(c.size(), k.kept.size());
        for (std::size_t j = 0; j < k.kept.size(); ++j) {
            point_equal(c, j, src, k.kept[j]);
            EXPECT_EQ(r.get<PointFlags>(e).bits[j], kFlags[k.kept[j]]);
            EXPECT_EQ(r.get<PointWeights>(e).values[j], kWeights[k.kept[j]]);
        }
        EXPECT_GT(r.version<Cloud>(e), v);
        EXPECT_EQ(r.get<PointPages>(e).points, k.kept.size());
        EXPECT_GT(r.get<PointPages>(e).clock, clock);
        // Nothing left to drop: no change, no stamp.
        const std::uint64_t v2 = r.version<Cloud>(e);
        auto again = what == "selected" ? extract_points(r, e) : drop_gone_points(r, e, PointDrop::deleted);
        ASSERT_TRUE(again);
        EXPECT_EQ(*again, 0u);
        EXPECT_EQ(r.version<Cloud>(e), v2);
    }
}

TEST(PointSubset, InPlaceDropAndExtractOnSurfaceClouds) {
    check_in_place(surface_cloud(6),
                   [](const SplatCloud& a, std::size_t k, const SplatCloud& b, std::size_t i) {
                       expect_surface_point(a, k, b, i);
                       EXPECT_EQ(a.texture.rgba8, b.texture.rgba8);
                   });
}

TEST(PointSubset, InPlaceDropAndExtractOnGaussianCloudsOfDegree3) {
    check_in_place(gaussian_cloud(6, 3), [](const GaussianCloud& a, std::size_t k, const GaussianCloud& b,
                                            std::size_t i) { expect_gaussian_point(a, k, b, i); });
}

TEST(PointSubset, InPlaceRefusalsChangeNothing) {
    ecs::Registry r;
    const ecs::Entity none = r.create(), e = r.create();
    auto a = drop_gone_points(r, none, PointDrop::deleted);
    ASSERT_FALSE(a);
    EXPECT_EQ(a.message(), "drop_gone_points(): the entity has no point cloud");
    r.emplace<SplatCloud>(e, surface_cloud(6));
    r.emplace<PointFlags>(e, PointFlags{kFlags});
    r.emplace<PointWeights>(e, PointWeights{{1.0f, 0.5f}});  // two weights for six points
    const std::uint64_t v = r.version<SplatCloud>(e);
    auto b = drop_gone_points(r, e, PointDrop::deleted);
    ASSERT_FALSE(b);
    EXPECT_EQ(b.message(), "subset_points(): 'weight' has 2 values for 6 points");
    EXPECT_EQ(r.get<SplatCloud>(e).size(), 6u);
    EXPECT_EQ(r.get<PointFlags>(e).bits, kFlags);
    EXPECT_EQ(r.version<SplatCloud>(e), v);
    // Without flags nothing is gone or selected.
    r.remove<PointFlags>(e);
    r.get<PointWeights>(e).values.assign(6, 1.0f);
    auto c = drop_gone_points(r, e, PointDrop::hidden_and_deleted);
    ASSERT_TRUE(c);
    EXPECT_EQ(*c, 0u);
    auto d = extract_points(r, e);
    ASSERT_TRUE(d);
    EXPECT_EQ(*d, 6u);
    EXPECT_EQ(r.get<SplatCloud>(e).size(), 0u);
    EXPECT_TRUE(r.get<PointWeights>(e).values.empty());
}

}  // namespace
}  // namespace sffd
