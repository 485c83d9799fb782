// Named point columns (runtime/scene/point_columns.h): every name of both kinds' tables maps to the member
// the test names by hand, with its type; wrong types, absent and mis-sized columns read as empty; a
// strided view over an interleaved struct reads and writes its field. Stamps of the optional groups
// (point_pages.h): selection, visibility and weight move only their own pages and component, never the
// cloud's stamp; a mis-sized component is reported and stamps its whole group.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "runtime/core/log.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"

namespace sffd {
namespace {

SplatCloud surface_cloud(std::size_t n) {
    SplatCloud c;
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        c.positions.push_back({f, 1 + f, 2 + f});
        c.normals.push_back({0, 0, 1 + f});
        c.axis_u.push_back({0.1f + f, 0, 0});
        c.axis_v.push_back({0, 0.2f + f, 0});
        c.colors.push_back(0xff000000u | std::uint32_t(i));
        c.uvs.push_back({f / 10, 1 - f / 10});
        c.uv_axes.push_back({f, -f, 2 * f, -2 * f});
    }
    return c;
}

GaussianCloud gaussian_cloud(std::size_t n, int degree) {
    GaussianCloud g;
    g.sh_degree = degree;
    const std::size_t k = 3 * std::size_t(sh_coeffs(degree));
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        g.positions.push_back({f, -f, 2 * f});
        g.scales.push_back({0.1f + f, 0.2f, 0.3f});
        g.rotations.push_back(glm::quat(1, 0, f, 0));
        g.opacities.push_back(0.5f + f / 100);
        for (std::size_t j = 0; j < k; ++j) g.sh.push_back(f * 1000 + float(j));
    }
    return g;
}

// The address of the first value of point i of the column named `name`, written out by hand.
const void* surface_member(const SplatCloud& c, const std::string& name, std::size_t i) {
    const std::map<std::string, const void*> m = {{"position", &c.positions[i]}, {"normal", &c.normals[i]},
                                                  {"axis_u", &c.axis_u[i]},      {"axis_v", &c.axis_v[i]},
                                                  {"color", &c.colors[i]},       {"uv", &c.uvs[i]},
                                                  {"uv_axes", &c.uv_axes[i]}};
    return m.at(name);
}
const void* gaussian_member(const GaussianCloud& g, const std::string& name, std::size_t i) {
    const std::size_t k = 3 * std::size_t(sh_coeffs(g.sh_degree));
    const std::map<std::string, const void*> m = {{"position", &g.positions[i]},
                                                  {"scale", &g.scales[i]},
                                                  {"rotation", &g.rotations[i]},
                                                  {"opacity", &g.opacities[i]},
                                                  {"sh", &g.sh[i * k]}};
    return m.at(name);
}

// The typed view of `ref` for its own type, as addresses; and that every other type gives an empty view.
template <class T>
std::vector<const void*> addresses(const ColumnRef& ref) {
    std::vector<const void*> out;
    const StridedView<const T> v = typed_column<const T>(ref);
    for (std::size_t i = 0; i < v.size(); ++i) out.push_back(&v[i]);
    return out;
}
std::vector<const void*> addresses_of_type(const ColumnRef& ref, ColumnType t) {
    switch (t) {
        case ColumnType::u8: return addresses<std::uint8_t>(ref);
        case ColumnType::rgba8: return addresses<std::uint32_t>(ref);
        case ColumnType::f32: return addresses<float>(ref);
        case ColumnType::vec2: return addresses<glm::vec2>(ref);
        case ColumnType::vec3: return addresses<glm::vec3>(ref);
        case ColumnType::vec4: return addresses<glm::vec4>(ref);
        case ColumnType::quat: return addresses<glm::quat>(ref);
    }
    return {};
}
constexpr ColumnType kAllTypes[] = {ColumnType::u8,   ColumnType::rgba8, ColumnType::f32, ColumnType::vec2,
                                    ColumnType::vec3, ColumnType::vec4,  ColumnType::quat};

TEST(PointColumns, EverySurfaceColumnMapsToItsMemberWithItsType) {
    const SplatCloud c = surface_cloud(5);
    std::set<std::string> seen;
    for (const PointColumnSpec& spec : kSurfaceColumns) {
        SCOPED_TRACE(std::string(spec.name));
        EXPECT_TRUE(seen.insert(std::string(spec.name)).second) << "names are unique";
        const ColumnRef ref = column_ref(c, spec.name);
        ASSERT_EQ(ref.spec, &spec);
        ASSERT_EQ(ref.count, 5u);
        EXPECT_EQ(ref.bytes(), 5 * column_type_bytes(spec.type));
        for (ColumnType t : kAllTypes) {
            const auto a = addresses_of_type(ref, t);
            if (t != spec.type) {
                EXPECT_TRUE(a.empty()) << column_type_name(t);
                continue;
            }
            ASSERT_EQ(a.size(), 5u);
            for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(a[i], surface_member(c, std::string(spec.name), i));
        }
    }
    EXPECT_EQ(seen.size(), 7u);
    // Values through the typed functions, and writes through the mutable view reach the cloud.
    SplatCloud m = c;
    EXPECT_EQ(point_column<glm::vec4>(c, "uv_axes")[3], glm::vec4(3, -3, 6, -6));
    EXPECT_EQ(point_column<std::uint32_t>(c, "color")[4], 0xff000004u);
    point_column<glm::vec3>(m, "axis_v")[2] = glm::vec3(7, 8, 9);
    EXPECT_EQ(m.axis_v[2], glm::vec3(7, 8, 9));
    EXPECT_TRUE(point_column<glm::vec3>(c, "colour").empty()) << "no such name";
    EXPECT_TRUE(point_column<glm::vec3>(c, "scale").empty()) << "a Gaussian name";
}

TEST(PointColumns, EveryGaussianColumnMapsToItsMemberWithItsTypeAtEachShDegree) {
    for (int degree = 0; degree <= 3; ++degree) {
        SCOPED_TRACE(degree);
        const GaussianCloud g = gaussian_cloud(4, degree);
        for (const PointColumnSpec& spec : kGaussianColumns) {
            SCOPED_TRACE(std::string(spec.name));
            const ColumnRef ref = column_ref(g, spec.name);
            ASSERT_EQ(ref.spec, &spec);
            ASSERT_EQ(ref.count, 4u);
            const std::size_t values = spec.per_sh ? 3 * std::size_t(sh_coeffs(degree)) : 1;
            EXPECT_EQ(ref.values, values);
            EXPECT_EQ(ref.stride, std::ptrdiff_t(values * column_type_bytes(spec.type)));
            for (ColumnType t : kAllTypes) {
                const auto a = addresses_of_type(ref, t);
                if (t != spec.type) {
                    EXPECT_TRUE(a.empty());
                    continue;
                }
                ASSERT_EQ(a.size(), 4u);
                for (std::size_t i = 0; i < 4; ++i)
                    EXPECT_EQ(a[i], gaussian_member(g, std::string(spec.name), i));
            }
        }
        // The SH view: point i's first float, its 3K coefficients after it.
        const auto sh = point_column<float>(g, "sh");
        ASSERT_EQ(sh.size(), 4u);
        const std::size_t k = 3 * std::size_t(sh_coeffs(degree));
        EXPECT_EQ((&sh[2])[k - 1], 2000.0f + float(k - 1));
    }
}

TEST(PointColumns, AbsentAndMisSizedColumnsReadAsEmpty) {
    SplatCloud c = surface_cloud(3);
    c.uvs.clear();
    c.normals.pop_back();  // two normals for three points
    EXPECT_TRUE(point_column<glm::vec2>(c, "uv").empty());
    EXPECT_TRUE(point_column<glm::vec3>(c, "normal").empty());
    EXPECT_FALSE(column_ref(c, "normal").present());
    EXPECT_EQ(column_ref(c, "normal").spec->name, "normal");
    GaussianCloud g = gaussian_cloud(3, 2);
    g.sh.resize(g.sh.size() - 1);
    EXPECT_TRUE(point_column<float>(g, "sh").empty());
    EXPECT_EQ(point_column<float>(g, "opacity").size(), 3u);
}

TEST(PointColumns, TheOptionalColumnsOfAnEntityOfEitherKind) {
    ecs::Registry r;
    const ecs::Entity s = r.create(), g = r.create(), none = r.create();
    r.emplace<SplatCloud>(s, surface_cloud(3));
    r.emplace<GaussianCloud>(g, gaussian_cloud(3, 1));
    // Absent components: present in the list, empty.
    for (ecs::Entity e : {s, g}) {
        const auto all = point_columns(r, e);
        ASSERT_EQ(all.size(), (e == s ? 7u : 5u) + 2u);
        EXPECT_EQ(all[all.size() - 2].spec, &kOptionalColumns[0]);
        EXPECT_FALSE(all.back().present());
        EXPECT_TRUE(point_column<std::uint8_t>(r, e, "flags").empty());
    }
    EXPECT_TRUE(point_columns(r, none).empty());
    r.emplace<PointFlags>(s, PointFlags{{kPointSelected, 0, kPointHidden}});
    r.emplace<PointWeights>(g, PointWeights{{0.25f, 0.5f, 1.0f}});
    const auto flags = point_column<std::uint8_t>(r, s, "flags");
    ASSERT_EQ(flags.size(), 3u);
    EXPECT_EQ(&flags[2], &r.get<PointFlags>(s).bits[2]);
    EXPECT_TRUE(point_column<float>(r, s, "flags").empty()) << "wrong type";
    const auto w = point_column<float>(r, g, "weight");
    ASSERT_EQ(w.size(), 3u);
    EXPECT_EQ(&w[1], &r.get<PointWeights>(g).values[1]);
    EXPECT_EQ(point_column<glm::quat>(r, g, "rotation")[2], glm::quat(1, 0, 2, 0));
    // One value short: absent, so nothing reads past the end.
    r.get<PointWeights>(g).values.pop_back();
    EXPECT_TRUE(point_column<float>(r, g, "weight").empty());
    EXPECT_EQ(point_weight(&r.get<PointWeights>(g), 2), 1.0f);
}

TEST(PointColumns, StridedViewOverAnInterleavedStruct) {
    struct Splat {
        glm::vec3 position;
        float opacity;
        std::uint8_t flags;
    };
    std::vector<Splat> splats(6);
    for (std::size_t i = 0; i < splats.size(); ++i)
        splats[i] = {glm::vec3(float(i), 2.0f * float(i), 0.0f), 0.1f * float(i), std::uint8_t(i)};
    StridedView<glm::vec3> pos(&splats[0].position, splats.size(), sizeof(Splat));
    StridedView<const float> op(&splats[0].opacity, splats.size(), sizeof(Splat));
    StridedView<std::uint8_t> fl(&splats[0].flags, splats.size(), sizeof(Splat));
    EXPECT_FALSE(pos.contiguous());
    for (std::size_t i = 0; i < splats.size(); ++i) {
        EXPECT_EQ(pos[i], splats[i].position);
        EXPECT_EQ(op[i], splats[i].opacity);
        EXPECT_EQ(fl[i], std::uint8_t(i));
    }
    pos[4] = glm::vec3(9, 9, 9);
    fl[5] = kPointHidden;
    EXPECT_EQ(splats[4].position, glm::vec3(9, 9, 9));
    EXPECT_EQ(splats[5].flags, kPointHidden);
    const StridedView<const float> tail = op.slice(2, 3);
    ASSERT_EQ(tail.size(), 3u);
    EXPECT_EQ(&tail[0], &splats[2].opacity);
    EXPECT_EQ(&tail[2], &splats[4].opacity);
    // A view of a vector is contiguous.
    std::vector<float> v{1, 2, 3};
    const StridedView<const float> cv(v);
    EXPECT_TRUE(cv.contiguous());
    EXPECT_EQ(cv[2], 3.0f);
}

TEST(PointColumns, EveryColumnBelongsToAStampGroupOfItsKind) {
    for (const auto& spec : kSurfaceColumns)
        EXPECT_TRUE(spec.stamp == PointColumn::position || spec.stamp == PointColumn::frame ||
                    spec.stamp == PointColumn::colour)
            << spec.name;
    for (const auto& spec : kGaussianColumns)
        EXPECT_TRUE(spec.stamp == PointColumn::position || spec.stamp == PointColumn::scale ||
                    spec.stamp == PointColumn::rotation || spec.stamp == PointColumn::opacity ||
                    spec.stamp == PointColumn::sh)
            << spec.name;
    for (const auto& spec : kOptionalColumns) EXPECT_TRUE(optional_point_column(spec.stamp)) << spec.name;
    EXPECT_EQ(kOptionalColumns[0].stamp, PointColumn::selection);
    EXPECT_EQ(kOptionalColumns[0].also_stamp, PointColumn::visibility);
    EXPECT_EQ(kOptionalColumns[1].stamp, PointColumn::weight);
}

// ---- stamps of the optional groups ----------------------------------------------------------------------

constexpr std::size_t kThreePages = 2 * kPagePoints + 10;

template <class Cloud>
void check_optional_stamps(Cloud cloud) {
    ecs::Registry r;
    const ecs::Entity e = r.create();
    const std::size_t n = cloud.size();
    r.emplace<Cloud>(e, std::move(cloud));
    r.emplace<PointFlags>(e, PointFlags{std::vector<std::uint8_t>(n, 0)});
    r.emplace<PointWeights>(e, PointWeights{std::vector<float>(n, 1.0f)});
    const PointPages* p = refresh_point_pages(r, e);
    ASSERT_NE(p, nullptr);
    ASSERT_EQ(p->stamps[0].size(), 3u);
    const std::uint64_t cloud_version = r.version<Cloud>(e), since = p->clock;
    const auto before = p->stamps;

    // Selection of a point in page 1: that page of the selection group, nothing else.
    r.get<PointFlags>(e).bits[kPagePoints + 3] = kPointSelected;
    const std::uint64_t flags_before = r.version<PointFlags>(e);
    mark_points_changed(r, e, PointColumn::selection, kPagePoints + 3, 1);
    p = r.try_get<PointPages>(e);
    EXPECT_EQ(r.version<Cloud>(e), cloud_version) << "the cloud is not stamped";
    EXPECT_GT(r.version<PointFlags>(e), flags_before);
    EXPECT_EQ(p->flags_version, r.version<PointFlags>(e));
    const PointColumn sel[] = {PointColumn::selection}, vis[] = {PointColumn::visibility},
                      wgt[] = {PointColumn::weight}, pos[] = {PointColumn::position};
    EXPECT_EQ(pages_changed_since(*p, since, sel), (std::vector<std::uint32_t>{1}));
    EXPECT_TRUE(pages_changed_since(*p, since, vis).empty());
    EXPECT_TRUE(pages_changed_since(*p, since, pos).empty());
    // The next refresh keeps the record (no replacement): the position stamps are as they were.
    p = refresh_point_pages(r, e);
    EXPECT_EQ(p->stamps[std::size_t(PointColumn::position)], before[std::size_t(PointColumn::position)]);

    // Hiding points of pages 0 and 2: visibility only.
    const std::uint64_t since2 = p->clock;
    mark_points_changed(r, e, PointColumn::visibility, 5, 1);
    mark_points_changed(r, e, PointColumn::visibility, 2 * kPagePoints + 1, 4);
    p = r.try_get<PointPages>(e);
    EXPECT_EQ(pages_changed_since(*p, since2, vis), (std::vector<std::uint32_t>{0, 2}));
    EXPECT_TRUE(pages_changed_since(*p, since2, sel).empty());

    // A weight over the page boundary 0|1: PointWeights' stamp, pages 0 and 1.
    const std::uint64_t since3 = p->clock, weights_before = r.version<PointWeights>(e);
    mark_points_changed(r, e, PointColumn::weight, kPagePoints - 2, 4);
    p = r.try_get<PointPages>(e);
    EXPECT_GT(r.version<PointWeights>(e), weights_before);
    EXPECT_EQ(p->weights_version, r.version<PointWeights>(e));
    EXPECT_EQ(pages_changed_since(*p, since3, wgt), (std::vector<std::uint32_t>{0, 1}));
    EXPECT_EQ(r.version<Cloud>(e), cloud_version);

    // A component of the wrong size: reported, and every page of the group stamped; no read past it.
    r.get<PointWeights>(e).values.resize(7);
    const std::uint64_t since4 = p->clock;
    {
        log::ScopedLogCapture logs;
        mark_points_changed(r, e, PointColumn::weight, 0, 1);
        EXPECT_TRUE(
            logs.contains("PointWeights holds 7 values for a cloud of " + std::to_string(n) + " points"));
    }
    p = r.try_get<PointPages>(e);
    EXPECT_EQ(pages_changed_since(*p, since4, wgt), (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_TRUE(pages_changed_since(*p, since4, sel).empty());
    // Removed (every point back to the default): a mark still stamps the pages it names.
    r.remove<PointFlags>(e);
    const std::uint64_t since5 = p->clock;
    mark_points_changed(r, e, PointColumn::selection, 0, n);
    p = r.try_get<PointPages>(e);
    EXPECT_EQ(pages_changed_since(*p, since5, sel), (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_EQ(p->flags_version, 0u);
    EXPECT_EQ(r.version<Cloud>(e), cloud_version);
}

TEST(PointPagesOptional, SelectionVisibilityAndWeightStampTheirOwnPagesOnSurfaceClouds) {
    check_optional_stamps(surface_cloud(kThreePages));
}

TEST(PointPagesOptional, SelectionVisibilityAndWeightStampTheirOwnPagesOnGaussianClouds) {
    check_optional_stamps(gaussian_cloud(kThreePages, 0));
}

TEST(PointPagesOptional, AMarkWithoutARecordMakesOneAndKeepsAnUnmarkedCloudEditVisible) {
    ecs::Registry r;
    const ecs::Entity e = r.create();
    r.emplace<SplatCloud>(e, surface_cloud(10));
    r.emplace<PointFlags>(e, PointFlags{std::vector<std::uint8_t>(10, 0)});
    mark_points_changed(r, e, PointColumn::selection, 0, 1);  // no record yet: made, every page stamped
    ASSERT_NE(r.try_get<PointPages>(e), nullptr);
    const std::uint64_t cloud_version = r.version<SplatCloud>(e);
    EXPECT_EQ(r.get<PointPages>(e).cloud_version, cloud_version);
    refresh_point_pages(r, e);
    // An unmarked cloud edit, then a selection mark: the record must not take the cloud's new stamp.
    r.patch<SplatCloud>(e).positions[0].x = 5;
    mark_points_changed(r, e, PointColumn::selection, 0, 1);
    EXPECT_NE(r.get<PointPages>(e).cloud_version, r.version<SplatCloud>(e));
    const std::uint64_t since = r.get<PointPages>(e).clock;
    const PointPages* p = refresh_point_pages(r, e);  // the unmarked edit: replaced, every column stamped
    const PointColumn pos[] = {PointColumn::position};
    EXPECT_EQ(pages_changed_since(*p, since, pos), (std::vector<std::uint32_t>{0}));
}

}  // namespace
}  // namespace sffd
