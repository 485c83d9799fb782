// Gaussian clouds embedded in our scene files as KHR_gaussian_splatting primitives: an in-memory
// cloud (no source file) saved in a .glb / .gltf scene with a lattice comes back bit for bit, bound to the
// lattice, from the scene file alone; the file's JSON holds a KHR_gaussian_splatting POINTS primitive;
// corrupted or truncated embedded data names the scene file (load_scene and `splatffd render`).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "runtime/assets/scene.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/gaussian/sh.h"
#include "tests/test_util/run_tool.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
namespace fs = std::filesystem;
using nlohmann::json;

fs::path fresh_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("sffd_gaussian_embed_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// Random degree-3 cloud far from the world origin (origin kept apart from the float positions).
GaussianCloud random_cloud(std::size_t n) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.01f, 1.0f);
    GaussianCloud g;
    g.origin = {1000.25, -3.5, 42.0};
    g.sh_degree = 3;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.01f * pos(rng), 0.02f * pos(rng), 0.03f * pos(rng));
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(pos(rng));
        for (int k = 0; k < sh_coeffs(3) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

struct Glb {
    json doc;
    std::string bin;
};

Glb read_glb(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::uint32_t jlen = 0, blen = 0;
    std::memcpy(&jlen, s.data() + 12, 4);
    Glb g;
    g.doc = json::parse(s.substr(20, jlen));
    std::memcpy(&blen, s.data() + 20 + jlen, 4);
    g.bin = s.substr(28 + jlen, blen);
    return g;
}

void write_glb(const fs::path& p, const Glb& g) {
    std::string text = g.doc.dump();
    while (text.size() % 4) text.push_back(' ');
    std::string out;
    auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(0x46546C67u), u32(2), u32(std::uint32_t(12 + 8 + text.size() + 8 + g.bin.size()));
    u32(std::uint32_t(text.size())), u32(0x4E4F534Au);
    out += text;
    u32(std::uint32_t(g.bin.size())), u32(0x004E4942u);
    out += g.bin;
    std::ofstream(p, std::ios::binary) << out;
}

class GaussianSceneEmbedded : public testing::Test {
protected:
    // Saves an in-memory cloud "made" with a transform and a 3³ lattice bound as its deformer.
    static fs::path save(const fs::path& path, const GaussianCloud& g) {
        ecs::Registry reg;
        register_gaussian_scene_hooks(SceneHooks::in(reg));
        const ecs::Entity lat = reg.create();
        reg.emplace<Name>(lat, Name{"box"});
        reg.emplace<Lattice>(
            lat,
            ffd::make_lattice({-2, -2, -2}, {glm::dvec3(4, 0, 0), glm::dvec3(0, 4, 0), glm::dvec3(0, 0, 4)},
                              {2, 2, 2}));
        const ecs::Entity e = reg.create();
        reg.emplace<Name>(e, Name{"made"});
        Transform t;
        t.translation = {0.5, -1.25, 2.0};
        t.rotation = glm::normalize(glm::dquat(0.9, 0.1, -0.3, 0.2));
        t.scale = {2.0, 2.0, 2.0};
        reg.emplace<Transform>(e, t);
        reg.emplace<GaussianCloud>(e, g);
        reg.emplace<Deformers>(e, Deformers{{lat}});
        const Status s = save_scene(reg, path);
        EXPECT_TRUE(s) << s.message();
        return path;
    }
};

TEST_F(GaussianSceneEmbedded, InMemoryCloudRoundTripsBitForBitFromTheSceneFileAlone) {
    const GaussianCloud g = random_cloud(700);
    fs::path saved_glb;
    for (const char* name : {"scene.glb", "scene.gltf"}) {
        SCOPED_TRACE(name);
        const fs::path dir = fresh_dir(std::string("rt_") + name);
        const fs::path scene = save(dir / name, g);
        if (scene.extension() == ".glb") saved_glb = scene;
        // Nothing beside the scene: the cloud is in it.
        std::size_t files = 0;
        for ([[maybe_unused]] const auto& f : fs::directory_iterator(dir)) ++files;
        EXPECT_EQ(files, 1u);
        ecs::Registry reg;
        register_gaussian_scene_hooks(SceneHooks::in(reg));
        const Status st = load_scene(reg, scene.string());
        ASSERT_TRUE(st) << st.message();
        ASSERT_EQ(reg.count<GaussianCloud>(), 1u);
        EXPECT_EQ(reg.count<SplatCloud>(), 0u);  // the KHR primitive is not read again as a surface cloud
        ecs::Entity e = ecs::null_entity;
        reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { e = x; });
        const GaussianCloud& l = reg.get<GaussianCloud>(e);
        EXPECT_FALSE(reg.has<GaussianSource>(e));
        EXPECT_EQ(reg.get<Name>(e).value, "made");
        const Transform& t = reg.get<Transform>(e);
        EXPECT_EQ(t.translation, glm::dvec3(0.5, -1.25, 2.0));
        EXPECT_EQ(t.scale, glm::dvec3(2.0));
        EXPECT_NEAR(std::abs(glm::dot(t.rotation, glm::normalize(glm::dquat(0.9, 0.1, -0.3, 0.2)))), 1.0,
                    1e-12);
        ASSERT_TRUE(reg.has<Deformers>(e));
        ASSERT_EQ(reg.get<Deformers>(e).lattices.size(), 1u);
        EXPECT_TRUE(reg.has<Lattice>(reg.get<Deformers>(e).lattices[0]));
        EXPECT_EQ(reg.get<Name>(reg.get<Deformers>(e).lattices[0]).value, "box");
        ASSERT_EQ(l.size(), g.size());
        EXPECT_EQ(l.origin, g.origin);
        EXPECT_EQ(l.sh_degree, 3);
        EXPECT_EQ(l.positions, g.positions);
        EXPECT_EQ(l.scales, g.scales);
        EXPECT_EQ(l.opacities, g.opacities);
        EXPECT_EQ(l.sh, g.sh);
        double worst = 0.0;  // rotations: renormalised on reading, so equal up to sign within float rounding
        for (std::size_t i = 0; i < g.size(); ++i)
            worst = std::max(worst, 1.0 - std::abs(double(glm::dot(l.rotations[i], g.rotations[i]))));
        EXPECT_LT(worst, 1e-6);
    }
    // The .glb's JSON: one POINTS primitive with KHR_gaussian_splatting on a node marked for clouds[0],
    // whose entry says "embedded" and names no file.
    const Glb glb = read_glb(saved_glb);
    const json& d = glb.doc;
    ASSERT_TRUE(d.contains("extensionsUsed"));
    EXPECT_NE(d["extensionsUsed"].dump().find("KHR_gaussian_splatting"), std::string::npos);
    int marked = 0;
    for (const json& node : d["nodes"])
        if (node.contains("extras") && node["extras"].contains("sffd_gaussians")) {
            ++marked;
            EXPECT_EQ(node["extras"]["sffd_gaussians"], 0);
            const json& child = d["nodes"][node["children"][0].get<std::size_t>()];
            const json& prim = d["meshes"][child["mesh"].get<std::size_t>()]["primitives"][0];
            EXPECT_EQ(prim["mode"], 0);
            EXPECT_TRUE(prim["extensions"].contains("KHR_gaussian_splatting"));
            EXPECT_TRUE(prim["attributes"].contains("KHR_gaussian_splatting:SH_DEGREE_3_COEF_6"));
            EXPECT_EQ(d["accessors"][prim["attributes"]["POSITION"].get<std::size_t>()]["count"], 700);
        }
    EXPECT_EQ(marked, 1);
    // A generic KHR_gaussian_splatting reader (read_gltf: walks the default scene's nodes, ignores
    // SFFD_scene) finds the cloud placed by its nodes: centre = Transform(origin + p), Σ' = A Σ Aᵀ with
    // A = 2R, so trace Σ' = 4 trace Σ; opacities as stored. Scene files keep the internal frame, which
    // read_gltf takes for glTF's and turns 180 degrees about z: (x, y, z) -> (-x, -y, z).
    auto generic = read_gltf(saved_glb);
    ASSERT_TRUE(generic) << generic.message();
    ASSERT_EQ(generic->size(), g.size());
    Transform t;
    t.translation = {0.5, -1.25, 2.0};
    t.rotation = glm::normalize(glm::dquat(0.9, 0.1, -0.3, 0.2));
    t.scale = {2.0, 2.0, 2.0};
    const glm::dmat4 world = model_matrix(&t);
    double pos_err = 0.0, trace_err = 0.0;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dvec3 expected =
            glm::dvec3(-1.0, -1.0, 1.0) *
            glm::dvec3(world * glm::dvec4(g.origin + glm::dvec3(g.positions[i]), 1.0));
        pos_err =
            std::max(pos_err, glm::length(generic->origin + glm::dvec3(generic->positions[i]) - expected));
        const glm::dvec3 s0(g.scales[i]), s1(generic->scales[i]);
        trace_err = std::max(trace_err,
                             std::abs(glm::dot(s1, s1) - 4.0 * glm::dot(s0, s0)) / (4.0 * glm::dot(s0, s0)));
        EXPECT_EQ(generic->opacities[i], g.opacities[i]);
    }
    std::printf("generic KHR reader: max centre error %.3g, max relative trace(Sigma) error %.3g\n", pos_err,
                trace_err);
    EXPECT_LT(pos_err, 1e-3);  // float positions about 2000 from the world origin: ulp 1.2e-4
    EXPECT_LT(trace_err, 1e-5);
    const json& entry = d["extensions"]["SFFD_scene"]["extensions"]["gaussians"]["clouds"][0];
    EXPECT_EQ(entry["embedded"], true);
    EXPECT_FALSE(entry.contains("file"));
    EXPECT_EQ(entry["lattices"].size(), 1u);
}

TEST_F(GaussianSceneEmbedded, DeformedCloudsSHFramesAreBakedIntoTheEmbeddedCoefficients) {
    // A cloud in view-direction mode (per-splat SH frames, as the deformation leaves it) is saved with
    // its coefficients rotated by the frames (bake_sh_frames), and without frames.
    GaussianCloud g = random_cloud(50);
    const glm::mat3 frame = glm::mat3_cast(glm::normalize(glm::quat(0.8f, 0.3f, -0.4f, 0.1f)));
    g.sh_frames.assign(g.size(), frame);
    GaussianCloud expected = g;
    bake_sh_frames(expected);
    ASSERT_NE(expected.sh, g.sh);
    const fs::path scene = save(fresh_dir("frames") / "scene.glb", g);
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    const Status st = load_scene(reg, scene.string());
    ASSERT_TRUE(st) << st.message();
    ecs::Entity e = ecs::null_entity;
    reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { e = x; });
    ASSERT_NE(e, ecs::null_entity);
    EXPECT_TRUE(reg.get<GaussianCloud>(e).sh_frames.empty());
    EXPECT_EQ(reg.get<GaussianCloud>(e).sh, expected.sh);
}

TEST_F(GaussianSceneEmbedded, CorruptedEmbeddedDataNamesTheSceneFile) {
    const fs::path dir = fresh_dir("bad");
    const fs::path good = save(dir / "good.glb", random_cloud(200));
    const Glb glb = read_glb(good);
    auto attribute = [&](const char* name) {
        for (const json& m : glb.doc["meshes"])
            for (const json& p : m["primitives"])
                if (p.contains("extensions") && p["attributes"].contains(name))
                    return p["attributes"][name].get<std::size_t>();
        return std::size_t(0);
    };
    auto expect_refused = [&](const fs::path& scene, const std::string& problem) {
        ecs::Registry reg;
        register_gaussian_scene_hooks(SceneHooks::in(reg));
        const Status st = load_scene(reg, scene.string());
        ASSERT_FALSE(st) << scene;
        std::printf("%s\n", st.message().c_str());
        EXPECT_EQ(st.message().rfind(scene.string() + ": ", 0), 0u) << st.message();
        EXPECT_NE(st.message().find(problem), std::string::npos) << st.message();
        EXPECT_EQ(reg.count<GaussianCloud>(), 0u);  // nothing half-loaded
        EXPECT_EQ(reg.count<Lattice>(), 0u);
        const sffd::test::CliRun r = sffd::test::run_headless("render " + scene.string() + " --out " +
                                                              (dir / "frames").string() + " --size 32x24");
        EXPECT_EQ(r.code, 1) << r.out;
        EXPECT_NE(r.out.find(scene.string()), std::string::npos) << r.out;
    };
    {  // The opacity accessor claims more elements than its buffer view holds.
        Glb bad = glb;
        bad.doc["accessors"][attribute("KHR_gaussian_splatting:OPACITY")]["count"] = 100000;
        write_glb(dir / "count.glb", bad);
        expect_refused(dir / "count.glb", "KHR_gaussian_splatting:OPACITY");
    }
    {  // A NaN centre.
        Glb bad = glb;
        const json& view =
            bad.doc["bufferViews"]
                   [bad.doc["accessors"][attribute("POSITION")]["bufferView"].get<std::size_t>()];
        const float nan = std::numeric_limits<float>::quiet_NaN();
        std::memcpy(bad.bin.data() + view["byteOffset"].get<std::size_t>() + 4 * 12 + 4, &nan, 4);
        write_glb(dir / "nan.glb", bad);
        expect_refused(dir / "nan.glb", "clouds[0]");
    }
    {  // The entry says embedded, but no node carries its mark.
        Glb bad = glb;
        for (json& node : bad.doc["nodes"])
            if (node.contains("extras")) node["extras"].erase("sffd_gaussians");
        write_glb(dir / "unmarked.glb", bad);
        expect_refused(dir / "unmarked.glb", "clouds[0]: 'embedded' but no node");
    }
    {  // The file cut short inside the binary chunk.
        fs::copy_file(good, dir / "short.glb");
        fs::resize_file(dir / "short.glb", fs::file_size(good) - 1000);
        expect_refused(dir / "short.glb", "");
    }
}

}  // namespace
