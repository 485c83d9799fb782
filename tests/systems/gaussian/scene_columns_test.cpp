// The optional point columns in saved scenes (runtime/assets/formats/surface/gltf_point_columns.h): a
// surface cloud and a Gaussian cloud (in memory, and one referenced from a file) with selected, hidden and
// deleted points and weights are saved to .glb and .gltf and reopen with exactly the points that were
// not deleted, in order, their selected/hidden bits and their weights; an older file without the columns
// opens with no PointFlags / PointWeights; bad column values name the file and are refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("sffd_scene_columns_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void hooks(ecs::Registry& r) { gaussian::register_gaussian_scene_hooks(SceneHooks::in(r)); }

SplatCloud surface_cloud(std::size_t n) {
    SplatCloud c;
    c.origin = {10.5, 0, -3};
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        c.positions.push_back({f, 0.5f * f, -f});
        c.normals.push_back({0, 0, 1});
        c.axis_u.push_back({0.1f, 0, 0});
        c.axis_v.push_back({0, 0.1f, 0});
        c.colors.push_back(0xff000000u | std::uint32_t(i * 7));
    }
    return c;
}

GaussianCloud gaussian_cloud(std::size_t n) {
    GaussianCloud g;
    g.sh_degree = 1;
    for (std::size_t i = 0; i < n; ++i) {
        const float f = float(i);
        g.positions.push_back({f, -f, 0.25f * f});
        g.scales.push_back({0.1f, 0.2f, 0.05f + 0.01f * f});
        g.rotations.push_back(glm::quat(1, 0, 0, 0));
        g.opacities.push_back(0.5f);
        for (int k = 0; k < 12; ++k) g.sh.push_back(0.01f * f + 0.001f * float(k));
    }
    return g;
}

// Point i: 0 plain, 1 selected, 2 hidden, 3 deleted, 4 selected+hidden, 5 plain, ...
std::vector<std::uint8_t> flags_for(std::size_t n) {
    std::vector<std::uint8_t> f(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t pattern[] = {
            0, kPointSelected, kPointHidden, kPointDeleted, kPointSelected | kPointHidden, 0};
        f[i] = pattern[i % 6];
    }
    return f;
}
std::vector<float> weights_for(std::size_t n) {
    std::vector<float> w(n);
    for (std::size_t i = 0; i < n; ++i) w[i] = float(i % 11) / 10.0f;
    return w;
}

template <class Cloud>
ecs::Entity only(const ecs::Registry& r) {
    ecs::Entity found;
    r.view<const Cloud>().each([&](ecs::Entity e, const Cloud&) { found = e; });
    return found;
}

TEST(SceneColumns, BothKindsKeepFlagsAndWeightsAndDropDeletedPoints) {
    const fs::path dir = fresh_dir("both");
    constexpr std::size_t n = 40;
    std::vector<std::uint32_t> kept;  // every point but the deleted ones (i % 6 == 3)
    for (std::uint32_t i = 0; i < n; ++i)
        if (i % 6 != 3) kept.push_back(i);
    // The in-memory Gaussians and a Gaussian file referenced by path, which must be embedded to keep them.
    const fs::path gfile = dir / "g.ply";
    ASSERT_TRUE(gaussian::write_ply(gfile, gaussian_cloud(n)));
    for (const char* ext : {".glb", ".gltf"}) {
        SCOPED_TRACE(ext);
        ecs::Registry r;
        hooks(r);
        const ecs::Entity s = r.create();
        r.emplace<Name>(s, Name{"surface"});
        r.emplace<SplatCloud>(s, surface_cloud(n));
        r.emplace<PointFlags>(s, PointFlags{flags_for(n)});
        r.emplace<PointWeights>(s, PointWeights{weights_for(n)});
        const ecs::Entity g = r.create();
        r.emplace<Name>(g, Name{"g"});
        r.emplace<GaussianCloud>(g, gaussian_cloud(n));
        r.emplace<PointFlags>(g, PointFlags{flags_for(n)});
        r.emplace<PointWeights>(g, PointWeights{weights_for(n)});
        auto f = gaussian::load_gaussian_entity(r, gfile);
        ASSERT_TRUE(f) << f.message();
        r.get<Name>(*f).value = "from_file";
        r.emplace<PointFlags>(*f, PointFlags{flags_for(n)});
        const fs::path out = dir / (std::string("scene") + ext);
        ASSERT_TRUE(save_scene(r, out));
        EXPECT_EQ(r.get<SplatCloud>(s).size(), n) << "saving leaves the registry as it was";

        ecs::Registry back;
        hooks(back);
        Status st = load_scene(back, out.string());
        ASSERT_TRUE(st) << st.message();
        const ecs::Entity bs = only<SplatCloud>(back);
        ASSERT_TRUE(bool(bs));
        const SplatCloud& sc = back.get<SplatCloud>(bs);
        ASSERT_EQ(sc.size(), kept.size());
        const SplatCloud src = surface_cloud(n);
        const auto flags = flags_for(n);
        const auto weights = weights_for(n);
        ASSERT_NE(back.try_get<PointFlags>(bs), nullptr);
        ASSERT_NE(back.try_get<PointWeights>(bs), nullptr);
        for (std::size_t k = 0; k < kept.size(); ++k) {
            EXPECT_EQ(sc.positions[k], src.positions[kept[k]]);
            EXPECT_EQ(sc.colors[k], src.colors[kept[k]]);
            EXPECT_EQ(back.get<PointFlags>(bs).bits[k], flags[kept[k]]);
            EXPECT_EQ(back.get<PointWeights>(bs).values[k], weights[kept[k]]);
        }
        int gaussians = 0;
        back.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& gc) {
            ++gaussians;
            const std::string name = back.get<Name>(e).value;
            SCOPED_TRACE(name);
            EXPECT_EQ(back.try_get<GaussianSource>(e), nullptr) << "embedded, with its columns";
            ASSERT_EQ(gc.size(), kept.size());
            ASSERT_NE(back.try_get<PointFlags>(e), nullptr);
            const GaussianCloud gsrc = gaussian_cloud(n);
            for (std::size_t k = 0; k < kept.size(); ++k) {
                EXPECT_EQ(back.get<PointFlags>(e).bits[k], flags[kept[k]]);
                if (name == "g") EXPECT_EQ(gc.positions[k], gsrc.positions[kept[k]]);
                for (int j = 0; j < 12; ++j)
                    ASSERT_NEAR(gc.sh[k * 12 + j], gsrc.sh[kept[k] * 12 + j], name == "g" ? 0.0 : 1e-6);
            }
            if (name == "g") {
                ASSERT_NE(back.try_get<PointWeights>(e), nullptr);
                for (std::size_t k = 0; k < kept.size(); ++k)
                    EXPECT_EQ(back.get<PointWeights>(e).values[k], weights[kept[k]]);
            } else {
                EXPECT_EQ(back.try_get<PointWeights>(e), nullptr);
            }
        });
        EXPECT_EQ(gaussians, 2);
    }
}

TEST(SceneColumns, FilesWithoutColumnsLoadWithNoComponentAndStayReferenced) {
    const fs::path dir = fresh_dir("none");
    const fs::path gfile = dir / "g.ply";
    ASSERT_TRUE(gaussian::write_ply(gfile, gaussian_cloud(8)));
    ecs::Registry r;
    hooks(r);
    const ecs::Entity s = r.create();
    r.emplace<SplatCloud>(s, surface_cloud(8));
    r.emplace<PointFlags>(s, PointFlags{std::vector<std::uint8_t>(8, 0)});  // no bit set: nothing stored
    ASSERT_TRUE(gaussian::load_gaussian_entity(r, gfile));
    const fs::path out = dir / "scene.gltf";
    ASSERT_TRUE(save_scene(r, out));
    std::ifstream in(out);
    const nlohmann::json doc = nlohmann::json::parse(in);
    for (const auto& m : doc["meshes"])
        for (const auto& p : m["primitives"]) {
            EXPECT_FALSE(p["attributes"].contains("_FLAGS"));
            EXPECT_FALSE(p["attributes"].contains("_WEIGHT"));
        }
    ecs::Registry back;
    hooks(back);
    ASSERT_TRUE(load_scene(back, out.string()));
    EXPECT_EQ(back.count<PointFlags>(), 0u);
    EXPECT_EQ(back.count<PointWeights>(), 0u);
    EXPECT_EQ(back.count<GaussianSource>(), 1u) << "a Gaussian file without columns stays referenced";
}

TEST(SceneColumns, BadColumnValuesAreRefusedNamingTheFile) {
    const fs::path dir = fresh_dir("bad");
    ecs::Registry r;
    hooks(r);
    const ecs::Entity s = r.create();
    r.emplace<Name>(s, Name{"c"});
    r.emplace<SplatCloud>(s, surface_cloud(4));
    r.emplace<PointWeights>(s, PointWeights{{0, 0.5f, 1, 0.25f}});
    r.emplace<PointFlags>(s, PointFlags{{0, 1, 2, 3}});
    const fs::path out = dir / "scene.gltf";
    ASSERT_TRUE(save_scene(r, out));
    std::ifstream in(out);
    nlohmann::json doc = nlohmann::json::parse(in);
    in.close();
    const auto& attrs = doc["meshes"][0]["primitives"][0]["attributes"];
    ASSERT_TRUE(attrs.contains("_FLAGS") && attrs.contains("_WEIGHT"));
    // The _FLAGS accessor read as floats: 4 bytes a point, the bits 0, 1, 2, 3 as 0, 1, 2, 3; a normalised
    // reinterpretation gives values that are not whole numbers, which the reader refuses.
    doc["accessors"][attrs["_FLAGS"].get<int>()]["normalized"] = true;
    std::ofstream(dir / "bad_flags.gltf") << doc.dump();
    ecs::Registry b1;
    hooks(b1);
    Status st = load_scene(b1, (dir / "bad_flags.gltf").string());
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find("bad_flags.gltf: splat node 'c': _FLAGS value"), std::string::npos)
        << st.message();
    EXPECT_EQ(b1.count<SplatCloud>(), 0u) << "nothing of a failed load stays";
    // Weights stored as one point fewer than the cloud.
    doc["accessors"][attrs["_FLAGS"].get<int>()].erase("normalized");
    doc["accessors"][attrs["_WEIGHT"].get<int>()]["count"] = 3;
    std::ofstream(dir / "bad_weights.gltf") << doc.dump();
    ecs::Registry b2;
    hooks(b2);
    st = load_scene(b2, (dir / "bad_weights.gltf").string());
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find("_WEIGHT has 3 values for 4 points"), std::string::npos) << st.message();
    // A weight out of range refuses the save.
    r.get<PointWeights>(s).values[2] = 1.5f;
    st = save_scene(r, dir / "never.glb");
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find("weight 1.5"), std::string::npos) << st.message();
    EXPECT_FALSE(fs::exists(dir / "never.glb"));
}

}  // namespace
