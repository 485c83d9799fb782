// Scene files: save + load round trip of clouds, lattices, deformer bindings, cameras, lights and a
// registered extension; built-in scenes; hostile scene files refused with the file name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/scene.h"
#include "runtime/core/paths.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_scene_test_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

template <class C>
std::vector<ecs::Entity> with(const ecs::Registry& r) {
    std::vector<ecs::Entity> out;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<C>(e)) out.push_back(e);
    });
    return out;
}

ecs::Entity find_named(const ecs::Registry& r, const std::string& name) {
    ecs::Entity found;
    r.each_entity([&](ecs::Entity e) {
        if (const Name* n = r.try_get<Name>(e); n && n->value == name) found = e;
    });
    return found;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// A component only the test knows about, stored through the extension hook (as animation will).
struct Tag {
    int value = 0;
    ecs::Entity target;
};

}  // namespace

TEST(Scene, SaveLoadRoundTripKeepsEverything) {
    ecs::Registry a;
    // Two lattices, the second one edited; two clouds, one bound to both lattices in order.
    const ecs::Entity l1 = a.create();
    a.emplace<Name>(l1, Name{"outer"});
    a.emplace<Transform>(l1, Transform{glm::dvec3(0.5, 0, 0), glm::dquat(1, 0, 0, 0), glm::dvec3(1)});
    a.emplace<Lattice>(l1, assets::make_box_lattice(glm::dvec3(-1.1), glm::dvec3(1.1), glm::ivec3(3, 4, 5),
                                                    LatticeBasis::bernstein));
    const ecs::Entity l2 = a.create();
    a.emplace<Name>(l2, Name{"inner"});
    Lattice inner = assets::make_box_lattice(glm::dvec3(-0.5, -0.5, 0.0), glm::dvec3(0.5, 0.5, 1.2),
                                             glm::ivec3(2), LatticeBasis::bspline);
    inner.current[7] += glm::dvec3(0.1234567890123, -0.2, 1e-9);
    a.emplace<Lattice>(l2, inner);
    a.emplace<Transform>(l2, Transform{});
    const ecs::Entity c1 = a.create();
    a.emplace<Name>(c1, Name{"ball"});
    a.emplace<Transform>(c1, Transform{glm::dvec3(1, 2, 3), glm::normalize(glm::dquat(0.9, 0.1, 0.2, 0.3)),
                                       glm::dvec3(2, 2, 2)});
    SplatCloud ball = assets::make_sphere_cloud(500);
    ball.origin = glm::dvec3(1e6 + 0.25, 0, -3);
    a.emplace<SplatCloud>(c1, ball);
    const SplatMaterial shiny{glm::vec4(0.25f, 0.5f, 0.75f, 0.5f), 0.875f, 77.5f};
    a.emplace<SplatMaterial>(c1, shiny);
    a.emplace<Deformers>(c1, Deformers{{l2, l1}});
    const ecs::Entity c2 = a.create();
    a.emplace<Name>(c2, Name{"plain"});
    a.emplace<Transform>(c2, Transform{});
    SplatCloud plain;
    plain.positions = {{0, 0, 0}, {1, 0, 0}};
    plain.normals = {{0, 0, 1}, {0, 0, 1}};
    plain.axis_u = {{0.1f, 0, 0}, {0.1f, 0, 0}};
    plain.axis_v = {{0, 0.1f, 0}, {0, 0.1f, 0}};
    a.emplace<SplatCloud>(c2, plain);
    const ecs::Entity cam = a.create();
    a.emplace<Name>(cam, Name{"cam"});
    a.emplace<Camera>(
        cam, Camera{glm::dvec3(1, 2, 9), glm::dvec3(0, 0.5, 0), glm::dvec3(0, 1, 0), 33.0f, 0.05f, 50.0f});
    const ecs::Entity sun = a.create();
    a.emplace<DirectionalLight>(sun, DirectionalLight{glm::vec3(0, -1, 0), glm::vec3(1, 0.9f, 0.8f), 2.5f});
    const ecs::Entity amb = a.create();
    a.emplace<AmbientLight>(amb, AmbientLight{glm::vec3(0.2f, 0.3f, 0.4f), 0.5f});
    a.emplace<Tag>(l2, Tag{42, c1});

    // The extension lives in the registries' own hooks: `a` saves with it, `b` loads with it.
    SceneHooks tags;
    tags.add_extension(
        "test_tags",
        [](const ecs::Registry& r, const SceneIdOf& id_of) -> Result<std::string> {
            nlohmann::json j = nlohmann::json::array();
            r.view<const Tag>().each([&](ecs::Entity e, const Tag& t) {
                j.push_back({{"on", id_of(e)}, {"value", t.value}, {"target", id_of(t.target)}});
            });
            return j.dump();
        },
        [](ecs::Registry& r, std::string_view text, const SceneEntityOf& entity_of) -> Status {
            const auto j = nlohmann::json::parse(text);
            for (const auto& t : j)
                r.emplace<Tag>(entity_of(t["on"].get<int>()),
                               Tag{t["value"].get<int>(), entity_of(t["target"].get<int>())});
            return {};
        });
    a.set_resource<SceneHooks>(tags);

    const fs::path p = temp_dir() / "scene.glb";
    auto saved = save_scene(a, p);
    ASSERT_TRUE(saved.ok()) << saved.message();
    for (const auto& entry : fs::directory_iterator(p.parent_path()))
        EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos);

    ecs::Registry b;
    b.set_resource<SceneHooks>(tags);
    auto loaded = load_scene(b, p.string());
    ASSERT_TRUE(loaded.ok()) << loaded.message();

    const ecs::Entity bc1 = find_named(b, "ball"), bc2 = find_named(b, "plain"), bl1 = find_named(b, "outer"),
                      bl2 = find_named(b, "inner");
    ASSERT_TRUE(bc1 && bc2 && bl1 && bl2);
    const SplatCloud& got = b.get<SplatCloud>(bc1);
    EXPECT_EQ(got.origin, ball.origin);
    EXPECT_TRUE(same_bytes(got.positions, ball.positions));
    EXPECT_TRUE(same_bytes(got.normals, ball.normals));
    EXPECT_TRUE(same_bytes(got.axis_u, ball.axis_u));
    EXPECT_TRUE(same_bytes(got.axis_v, ball.axis_v));
    EXPECT_TRUE(same_bytes(got.colors, ball.colors));
    EXPECT_TRUE(same_bytes(got.uvs, ball.uvs));
    EXPECT_TRUE(same_bytes(got.texture.rgba8, ball.texture.rgba8));
    // The material is its own component; a cloud saved without one loads with the defaults.
    ASSERT_TRUE(b.has<SplatMaterial>(bc1) && b.has<SplatMaterial>(bc2));
    EXPECT_EQ(b.get<SplatMaterial>(bc1), shiny);
    EXPECT_EQ(b.get<SplatMaterial>(bc2), SplatMaterial{});
    EXPECT_TRUE(same_bytes(b.get<SplatCloud>(bc2).positions, plain.positions));
    EXPECT_TRUE(b.get<SplatCloud>(bc2).colors.empty());
    const Transform& t = b.get<Transform>(bc1);
    EXPECT_EQ(t.translation, a.get<Transform>(c1).translation);
    EXPECT_EQ(t.rotation, a.get<Transform>(c1).rotation);
    EXPECT_EQ(t.scale, a.get<Transform>(c1).scale);
    ASSERT_TRUE(b.has<Deformers>(bc1));
    EXPECT_EQ(b.get<Deformers>(bc1).lattices, (std::vector<ecs::Entity>{bl2, bl1}));
    EXPECT_FALSE(b.has<Deformers>(bc2));
    for (auto [src, dst] : {std::pair{l1, bl1}, std::pair{l2, bl2}}) {
        const Lattice& x = a.get<Lattice>(src);
        const Lattice& y = b.get<Lattice>(dst);
        EXPECT_EQ(x.origin, y.origin);
        EXPECT_EQ(x.axes, y.axes);
        EXPECT_EQ(x.divisions, y.divisions);
        EXPECT_EQ(x.basis, y.basis);
        EXPECT_EQ(x.rest, y.rest);
        EXPECT_EQ(x.current, y.current);
    }
    EXPECT_EQ(b.get<Transform>(bl1).translation, glm::dvec3(0.5, 0, 0));
    ASSERT_EQ(with<Camera>(b).size(), 1u);
    const Camera& bc = b.get<Camera>(with<Camera>(b)[0]);
    EXPECT_EQ(bc.eye, glm::dvec3(1, 2, 9));
    EXPECT_EQ(bc.fov_y_degrees, 33.0f);
    EXPECT_EQ(bc.near_plane, 0.05f);
    ASSERT_EQ(with<DirectionalLight>(b).size(), 1u);
    EXPECT_EQ(b.get<DirectionalLight>(with<DirectionalLight>(b)[0]).intensity, 2.5f);
    EXPECT_EQ(b.get<DirectionalLight>(with<DirectionalLight>(b)[0]).color, glm::vec3(1, 0.9f, 0.8f));
    ASSERT_EQ(with<AmbientLight>(b).size(), 1u);
    EXPECT_EQ(b.get<AmbientLight>(with<AmbientLight>(b)[0]).color, glm::vec3(0.2f, 0.3f, 0.4f));
    // The extension's data came back, pointing at the loaded entities.
    ASSERT_TRUE(b.has<Tag>(bl2));
    EXPECT_EQ(b.get<Tag>(bl2).value, 42);
    EXPECT_EQ(b.get<Tag>(bl2).target, bc1);

    // Saving the loaded scene again gives the same file (nothing lost or reordered).
    const fs::path p2 = temp_dir() / "scene2.glb";
    ASSERT_TRUE(save_scene(b, p2).ok());
    std::ifstream f1(p, std::ios::binary), f2(p2, std::ios::binary);
    const std::string s1((std::istreambuf_iterator<char>(f1)), {}),
        s2((std::istreambuf_iterator<char>(f2)), {});
    const auto diff = std::mismatch(s1.begin(), s1.end(), s2.begin(), s2.end());
    EXPECT_TRUE(s1 == s2)
        << "files differ at byte " << (diff.first - s1.begin()) << ": "
        << s1.substr(static_cast<std::size_t>(std::max<long>(0, diff.first - s1.begin() - 60)), 120) << " | "
        << s2.substr(static_cast<std::size_t>(std::max<long>(0, diff.second - s2.begin() - 60)), 120);
}

TEST(Scene, BuiltinSphereHasThePapersCounts) {
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(r, "sphere").ok());
    const auto clouds = with<SplatCloud>(r);
    ASSERT_EQ(clouds.size(), 1u);
    const SplatCloud& c = r.get<SplatCloud>(clouds[0]);
    EXPECT_EQ(c.size(), 59650u);
    EXPECT_EQ(c.uvs.size(), c.size());
    EXPECT_EQ(c.texture.rgba8.size(), static_cast<std::size_t>(c.texture.width * c.texture.height * 4));
    for (const auto& uv : c.uvs) {
        ASSERT_GE(uv.x, 0.0f);
        ASSERT_LE(uv.x, 1.0f);
        ASSERT_GE(uv.y, 0.0f);
        ASSERT_LE(uv.y, 1.0f);
    }
    ASSERT_TRUE(r.has<Deformers>(clouds[0]));
    const auto& d = r.get<Deformers>(clouds[0]);
    ASSERT_EQ(d.lattices.size(), 1u);
    const Lattice& l = r.get<Lattice>(d.lattices[0]);
    EXPECT_EQ(l.size(), 11u * 11u * 11u);
    EXPECT_EQ(l.basis, LatticeBasis::bernstein);
    // Every splat lies strictly inside the lattice box.
    for (const auto& p : c.positions)
        for (int a = 0; a < 3; ++a) {
            const double s = (static_cast<double>(p[a]) - l.origin[a]) / l.axes[a][a];
            ASSERT_GT(s, 0.0);
            ASSERT_LT(s, 1.0);
        }
    EXPECT_EQ(with<Camera>(r).size(), 1u);
    EXPECT_EQ(with<DirectionalLight>(r).size(), 1u);
    EXPECT_EQ(builtin_scene_names(), (std::vector<std::string>{"sphere", "face"}));
}

TEST(Scene, BuiltinFaceLoadsFromTheCacheOrSaysHowToMakeIt) {
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    auto s = load_scene(r, "face");
    if (!fs::exists(assets::face_cache_path())) {
        ASSERT_FALSE(s.ok());
        EXPECT_NE(s.message().find("tools/fetch_content.sh"), std::string::npos) << s.message();
        GTEST_SKIP() << "face cache not built; run tools/fetch_content.sh";
    }
    ASSERT_TRUE(s.ok()) << s.message();
    const auto clouds = with<SplatCloud>(r);
    ASSERT_EQ(clouds.size(), 1u);
    EXPECT_EQ(r.get<SplatCloud>(clouds[0]).size(), 40880u);
    EXPECT_EQ(r.get<SplatCloud>(clouds[0]).normals.size(), 40880u);
    EXPECT_EQ(r.get<Lattice>(r.get<Deformers>(clouds[0]).lattices[0]).size(), 1331u);
}

struct BadScene {
    const char* label;
    std::string extension_json;
    const char* expected;
};

class HostileScene : public ::testing::TestWithParam<BadScene> {};

TEST_P(HostileScene, IsRefusedWithTheFileNameAndLeavesTheRegistryAlone) {
    const fs::path p = temp_dir() / (std::string(GetParam().label) + ".gltf");
    {
        std::ofstream f(p);
        f << R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[]}],"extensionsUsed":["SFFD_scene"],"extensions":{"SFFD_scene":)"
          << GetParam().extension_json << "}}";
    }
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    auto s = load_scene(r, p.string());
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find(p.string()), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(GetParam().expected), std::string::npos) << s.message();
    EXPECT_EQ(r.alive(), 0u);
}

const std::string kGoodLattice =
    R"({"id":0,"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1],"rest":[0,0,0,0,0,1,0,1,0,0,1,1,1,0,0,1,0,1,1,1,0,1,1,1]})";

INSTANTIATE_TEST_SUITE_P(
    Files, HostileScene,
    ::testing::Values(
        BadScene{"version", R"({"version":99})", "version not supported"},
        BadScene{"lattices_type", R"({"lattices":5})", "'lattices' must be an array"},
        BadScene{
            "huge_divisions",
            R"({"lattices":[{"id":0,"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[100000,100000,100000],"rest":[]}]})",
            "divisions must be between 1 and 64 (got 100000)"},
        BadScene{
            "short_rest",
            R"({"lattices":[{"id":0,"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1],"rest":[0,0,0]}]})",
            "\"rest\" must hold 24 numbers (8 points x, y, z in a row), got 3"},
        BadScene{
            "flat_axes",
            R"({"lattices":[{"id":0,"origin":[0,0,0],"axes":[[1,0,0],[2,0,0],[0,0,1]],"divisions":[1,1,1],"rest":[]}]})",
            "degenerate"},
        BadScene{
            "string_origin",
            R"({"lattices":[{"id":0,"origin":"here","axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1]}]})",
            "\"origin\" must be an array of 3 numbers"},
        BadScene{"missing_cloud",
                 R"({"lattices":[)" + kGoodLattice + R"(],"deformers":[{"cloud":7,"lattices":[0]}]})",
                 "missing cloud 7"},
        BadScene{"duplicate_id", R"({"lattices":[)" + kGoodLattice + "," + kGoodLattice + "]}",
                 "duplicate id 0"},
        BadScene{"bad_camera", R"({"cameras":[{"eye":[0,0,1],"target":[0,0,0],"fov_y_degrees":0}]})",
                 "fov must be"},
        BadScene{
            "basis",
            R"({"lattices":[{"id":0,"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1],"basis":"nurbs"}]})",
            "unknown basis"}),
    [](const auto& param_info) { return std::string(param_info.param.label); });

// Scene lattices meet the same rules as lattice files and the deformers (validate_lattice in
// runtime/scene/lattice.h): a box that is flat relative to its edges (|det| / (|S||T||U|) = 7e-13) is
// refused at load, not skipped with a warning by every deformation afterwards.
INSTANTIATE_TEST_SUITE_P(
    LatticeRules, HostileScene,
    ::testing::Values(BadScene{
        "nearly_flat_axes",
        R"({"lattices":[{"id":0,"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[1,1,1e-12]],"divisions":[1,1,1],"rest":[]}]})",
        "zero-volume box"}),
    [](const auto& param_info) { return std::string(param_info.param.label); });

TEST(Scene, UnknownNameSaysWhatExists) {
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    auto s = load_scene(r, "teapot");
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message(), "teapot: no such file or built-in scene (built-ins: sphere, face)");
}
