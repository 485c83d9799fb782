// `splatffd convert SCENE OUT --selected` and `--entity NAME`, through the built binary, on a scene saved
// here: a surface cloud "body" and a Gaussian cloud "body.part" (as the editor's separate names it), each
// with selected, hidden and deleted points and per-point weights, and a lattice bound to "body". Every
// format convert writes is read back: the kept points are exactly the selected ones that are neither
// hidden nor deleted, in order (exact formats) or each found once within the format's quantisation (SPZ,
// compressed PLY, SOG), with their values; a cloud file never holds a hidden or deleted point, a scene
// keeps the hidden ones; the errors name the file and exit 1 (2 for a usage error).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "systems/engine/engine_frame.h"
#include "systems/gaussian/gaussian_read.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace {

using namespace sffd;
using sffd::test::CliRun;
CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

constexpr std::size_t kSurface = 40, kGaussians = 30;

fs::path temp_dir() {
    static const fs::path d = [] {
        const fs::path p = fs::temp_directory_path() / ("sffd_convert_subset_" + std::to_string(::getpid()));
        fs::remove_all(p);
        fs::create_directories(p);
        return p;
    }();
    return d;
}

// Surface flags: even points selected; 4 selected and hidden, 8 selected and deleted, 5 hidden, 7 deleted.
std::uint8_t surface_flag(std::size_t i) {
    std::uint8_t f = i % 2 == 0 ? kPointSelected : 0;
    if (i == 4 || i == 5) f |= kPointHidden;
    if (i == 7 || i == 8) f |= kPointDeleted;
    return f;
}
// Gaussian flags: every third selected; 3 selected and hidden, 6 selected and deleted, 10 hidden.
std::uint8_t gaussian_flag(std::size_t i) {
    std::uint8_t f = i % 3 == 0 ? kPointSelected : 0;
    if (i == 3 || i == 10) f |= kPointHidden;
    if (i == 6) f |= kPointDeleted;
    return f;
}

std::vector<std::size_t> kept(std::size_t n, std::uint8_t (*flag)(std::size_t), bool selected_only,
                              std::uint8_t drop) {
    std::vector<std::size_t> k;
    for (std::size_t i = 0; i < n; ++i)
        if ((!selected_only || (flag(i) & kPointSelected)) && !(flag(i) & drop)) k.push_back(i);
    return k;
}

glm::vec3 surface_position(std::size_t i) {
    return {float(i) * 0.1f - 2.0f, std::sin(float(i)) * 0.5f, float(i % 3) * 0.25f};
}
glm::vec3 gaussian_position(std::size_t i) {
    return {float(i) * 0.1f - 1.5f, 1.0f + std::cos(float(i)) * 0.3f, 0.5f};
}
float surface_weight(std::size_t i) { return float(i) / float(kSurface - 1); }
float gaussian_weight(std::size_t i) { return 1.0f - float(i) / float(kGaussians - 1); }

SplatCloud make_surface() {
    SplatCloud c;
    for (std::size_t i = 0; i < kSurface; ++i) {
        c.positions.push_back(surface_position(i));
        c.normals.emplace_back(0.0f, 0.0f, 1.0f);
        c.axis_u.emplace_back(0.02f, 0.0f, 0.0f);
        c.axis_v.emplace_back(0.0f, 0.02f, 0.0f);
        c.colors.push_back(0xff000000u | std::uint32_t(i * 5) | std::uint32_t(255 - i * 3) << 8);
    }
    return c;
}

GaussianCloud make_gaussians() {
    GaussianCloud g;
    g.sh_degree = 0;
    for (std::size_t i = 0; i < kGaussians; ++i) {
        g.positions.push_back(gaussian_position(i));
        g.scales.emplace_back(0.01f + 0.001f * float(i));
        g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        g.opacities.push_back(0.3f + 0.02f * float(i));
        g.sh.insert(g.sh.end(), {0.1f * float(i % 5), -0.2f, 0.3f});
    }
    return g;
}

// The scene every test converts (saved once): save drops the deleted points, so it holds the others.
const fs::path& scene_file() {
    static const fs::path path = [] {
        ecs::Registry r;
        use_engine_scene_hooks(r);
        const ecs::Entity body = r.create();
        r.emplace<Name>(body, Name{"body"});
        r.emplace<Transform>(body, Transform{});
        r.emplace<SplatCloud>(body, make_surface());
        PointFlags sf;
        PointWeights sw;
        for (std::size_t i = 0; i < kSurface; ++i)
            sf.bits.push_back(surface_flag(i)), sw.values.push_back(surface_weight(i));
        r.emplace<PointFlags>(body, sf);
        r.emplace<PointWeights>(body, sw);
        const ecs::Entity lattice = r.create();
        r.emplace<Name>(lattice, Name{"body.lattice"});
        r.emplace<Transform>(lattice, Transform{});
        r.emplace<Lattice>(lattice,
                           make_lattice(glm::dvec3(-2.5, -1, -0.5),
                                        {glm::dvec3(5, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 1.5)},
                                        glm::ivec3(1, 1, 1)));
        r.emplace<Deformers>(body, Deformers{{lattice}});
        const ecs::Entity part = r.create();
        r.emplace<Name>(part, Name{"body.part"});
        r.emplace<Transform>(part, Transform{});
        r.emplace<GaussianCloud>(part, make_gaussians());
        PointFlags gf;
        PointWeights gw;
        for (std::size_t i = 0; i < kGaussians; ++i)
            gf.bits.push_back(gaussian_flag(i)), gw.values.push_back(gaussian_weight(i));
        r.emplace<PointFlags>(part, gf);
        r.emplace<PointWeights>(part, gw);
        const fs::path p = temp_dir() / "scene.glb";
        const Status s = save_scene(r, p);
        EXPECT_TRUE(s.ok()) << s.message();
        return p;
    }();
    return path;
}

void convert(const std::string& args) {
    const CliRun r = tool("convert " + scene_file().string() + " " + args);
    ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
}

// Each expected position found once in `got` within `tol` (any order); the matches, by expected index.
std::vector<std::size_t> match(const std::vector<glm::vec3>& want, const std::vector<glm::vec3>& got,
                               float tol, const std::string& what) {
    EXPECT_EQ(got.size(), want.size()) << what;
    std::vector<std::size_t> at(want.size(), 0);
    std::vector<bool> used(got.size(), false);
    for (std::size_t k = 0; k < want.size(); ++k) {
        std::size_t best = got.size();
        float best_d = tol;
        for (std::size_t j = 0; j < got.size(); ++j)
            if (!used[j] && glm::length(got[j] - want[k]) <= best_d)
                best = j, best_d = glm::length(got[j] - want[k]);
        if (best == got.size()) {
            ADD_FAILURE() << what << ": expected point " << k << " not found";
            continue;
        }
        used[best] = true;
        at[k] = best;
    }
    return at;
}

std::vector<glm::vec3> positions_of(const std::vector<std::size_t>& idx, glm::vec3 (*pos)(std::size_t)) {
    std::vector<glm::vec3> p;
    for (std::size_t i : idx) p.push_back(pos(i));
    return p;
}

// The one cloud of a scene file, with its optional columns.
struct Loaded {
    ecs::Registry r;
    std::vector<ecs::Entity> clouds;
    std::size_t lattices = 0;
};
void load(const fs::path& p, Loaded& l) {
    use_engine_scene_hooks(l.r);
    const Status s = load_scene(l.r, p.string());
    ASSERT_TRUE(s.ok()) << s.message();
    l.r.each_entity([&](ecs::Entity e) {
        if (l.r.has<SplatCloud>(e) || l.r.has<GaussianCloud>(e)) l.clouds.push_back(e);
        if (l.r.has<Lattice>(e)) ++l.lattices;
    });
}

TEST(ConvertSubset, SelectedSurfacePointsInEveryFormatTheyAreWritten) {
    const std::vector<std::size_t> want = kept(kSurface, surface_flag, true, kPointGone);
    ASSERT_EQ(want.size(), 18u);  // 20 even points less 4 (hidden) and 8 (deleted)
    for (const std::string ext : {"bin.ply", "ascii.ply"}) {
        const fs::path out = temp_dir() / ("surface_selected." + ext);
        convert(out.string() + " --selected --entity body" + (ext == "ascii.ply" ? " --ascii" : ""));
        auto c = assets::import_splat_cloud(out);
        ASSERT_TRUE(c.ok()) << c.message();
        ASSERT_EQ(c->size(), want.size()) << ext;
        ASSERT_EQ(c->colors.size(), want.size()) << ext << ": written as surface splats";
        for (std::size_t k = 0; k < want.size(); ++k) {
            EXPECT_EQ(c->positions[k], surface_position(want[k])) << ext << " " << k;
            EXPECT_EQ(c->colors[k], make_surface().colors[want[k]]) << ext << " " << k;
        }
    }
    // The same points as Gaussians (3DGS PLY): each once, at its place.
    const fs::path g = temp_dir() / "surface_selected_gaussians.ply";
    convert(g.string() + " --selected --entity body --gaussians");
    auto gc = gaussian::read_gaussians(g);
    ASSERT_TRUE(gc.ok()) << gc.message();
    std::vector<glm::vec3> turned;  // written y down as captures are: (x, -y, -z)
    for (const glm::vec3& p : gc->positions) turned.emplace_back(p.x, -p.y, -p.z);
    match(positions_of(want, surface_position), turned, 1e-5f, "3DGS PLY of splats");
    // The same points as SPZ Gaussians, each once.
    const fs::path spz = temp_dir() / "surface_selected.spz";
    convert(spz.string() + " --selected --entity body --gaussians");
    auto sg = gaussian::read_gaussians(spz);
    ASSERT_TRUE(sg.ok()) << sg.message();
    std::vector<glm::vec3> spz_turned;
    for (const glm::vec3& p : sg->positions) spz_turned.emplace_back(p.x, -p.y, -p.z);
    match(positions_of(want, surface_position), spz_turned, 5e-3f, "SPZ of splats");
    // A new scene with a fitted lattice: the selected points and their weights.
    const fs::path fitted = temp_dir() / "surface_selected_fit.glb";
    convert(fitted.string() + " --selected --entity body --lattice fit:2,2,2");
    {
        Loaded lf;
        load(fitted, lf);
        ASSERT_EQ(lf.clouds.size(), 1u);
        EXPECT_EQ(lf.lattices, 1u);
        const PointWeights* fw = lf.r.try_get<PointWeights>(lf.clouds[0]);
        ASSERT_TRUE(fw);
        ASSERT_EQ(fw->values.size(), want.size());
        for (std::size_t k = 0; k < want.size(); ++k) EXPECT_EQ(fw->values[k], surface_weight(want[k]));
    }
    // A scene OUT keeps the selected points with their weights and flags (all selected), and the lattice.
    const fs::path scene = temp_dir() / "surface_selected.glb";
    convert(scene.string() + " --selected --entity body");
    Loaded l;
    load(scene, l);
    ASSERT_EQ(l.clouds.size(), 1u);
    EXPECT_EQ(l.lattices, 1u);
    const SplatCloud& sc = l.r.get<SplatCloud>(l.clouds[0]);
    ASSERT_EQ(sc.size(), want.size());
    const PointWeights* w = l.r.try_get<PointWeights>(l.clouds[0]);
    const PointFlags* f = l.r.try_get<PointFlags>(l.clouds[0]);
    ASSERT_TRUE(w && f);
    for (std::size_t k = 0; k < want.size(); ++k) {
        EXPECT_EQ(sc.positions[k], surface_position(want[k]));
        EXPECT_EQ(w->values[k], surface_weight(want[k]));
        EXPECT_EQ(f->bits[k], kPointSelected);
    }
}

TEST(ConvertSubset, SelectedGaussiansInEveryFormatTheyAreWritten) {
    const std::vector<std::size_t> want = kept(kGaussians, gaussian_flag, true, kPointGone);
    ASSERT_EQ(want.size(), 8u);  // 0 3 6 9 12 15 18 21 24 27 less 3 (hidden) and 6 (deleted)
    const std::vector<glm::vec3> where = positions_of(want, gaussian_position);
    struct Format {
        std::string file;
        float tol;
        bool ordered;
    };
    for (const Format& f : {Format{"g.ply", 1e-6f, true}, Format{"g.compressed.ply", 5e-3f, false},
                            Format{"g.spz", 5e-3f, false}, Format{"g.sog", 5e-3f, false},
                            Format{"sog_folder/meta.json", 5e-3f, false}}) {
        const fs::path out = temp_dir() / f.file;
        fs::create_directories(out.parent_path());
        convert(out.string() + " --selected --entity body.part");
        auto g = gaussian::read_gaussians(out);
        ASSERT_TRUE(g.ok()) << f.file << ": " << g.message();
        const std::vector<std::size_t> at = match(where, g->positions, f.tol, f.file);
        for (std::size_t k = 0; k < want.size() && k < g->size(); ++k) {
            if (f.ordered) {
                EXPECT_EQ(at[k], k) << f.file;
            }
            EXPECT_NEAR(g->opacities[at[k]], make_gaussians().opacities[want[k]], 0.01f)
                << f.file << " " << k;
            const float scale = make_gaussians().scales[want[k]].x;  // SPZ: 8-bit log scales, ~3 %
            EXPECT_NEAR(g->scales[at[k]].x, scale, 0.05f * scale) << f.file << " " << k;
        }
    }
    const fs::path scene = temp_dir() / "g_selected.glb";
    convert(scene.string() + " --selected --entity body.part");
    Loaded l;
    load(scene, l);
    ASSERT_EQ(l.clouds.size(), 1u);
    EXPECT_EQ(l.lattices, 0u);  // the lattice was bound to "body" only
    const GaussianCloud& gc = l.r.get<GaussianCloud>(l.clouds[0]);
    ASSERT_EQ(gc.size(), want.size());
    const PointWeights* w = l.r.try_get<PointWeights>(l.clouds[0]);
    ASSERT_TRUE(w);
    for (std::size_t k = 0; k < want.size(); ++k) {
        EXPECT_EQ(gc.positions[k], where[k]);
        EXPECT_EQ(w->values[k], gaussian_weight(want[k]));
    }
}

TEST(ConvertSubset, EntityAloneDropsHiddenAndDeletedInCloudFilesAndKeepsHiddenInScenes) {
    const std::vector<std::size_t> shown = kept(kGaussians, gaussian_flag, false, kPointGone);
    const fs::path ply = temp_dir() / "part.ply";
    convert(ply.string() + " --entity body.part");
    auto g = gaussian::read_gaussians(ply);
    ASSERT_TRUE(g.ok()) << g.message();
    ASSERT_EQ(g->size(), shown.size());
    for (std::size_t k = 0; k < shown.size(); ++k) EXPECT_EQ(g->positions[k], gaussian_position(shown[k]));
    // A scene keeps the hidden points, hidden (deleted ones were never saved).
    const fs::path scene = temp_dir() / "part.glb";
    convert(scene.string() + " --entity body.part");
    Loaded l;
    load(scene, l);
    ASSERT_EQ(l.clouds.size(), 1u);
    EXPECT_EQ(l.r.get<GaussianCloud>(l.clouds[0]).size(),
              kept(kGaussians, gaussian_flag, false, kPointDeleted).size());
    // Every writer of the surface cloud leaves out hidden and deleted points too.
    const fs::path surface = temp_dir() / "body.ply";
    convert(surface.string() + " --entity body");
    auto c = assets::import_splat_cloud(surface);
    ASSERT_TRUE(c.ok()) << c.message();
    EXPECT_EQ(c->size(), kept(kSurface, surface_flag, false, kPointGone).size());
}

TEST(ConvertSubset, SelectedIntoASceneKeepsEveryCloudWithASelection) {
    const fs::path scene = temp_dir() / "both.glb";
    convert(scene.string() + " --selected");
    Loaded l;
    load(scene, l);
    ASSERT_EQ(l.clouds.size(), 2u);
    std::size_t surface = 0, gaussians = 0;
    for (ecs::Entity e : l.clouds) {
        if (const SplatCloud* c = l.r.try_get<SplatCloud>(e)) surface = c->size();
        if (const GaussianCloud* g = l.r.try_get<GaussianCloud>(e)) gaussians = g->size();
    }
    EXPECT_EQ(surface, 18u);
    EXPECT_EQ(gaussians, 8u);
}

TEST(ConvertSubset, ErrorsNameTheFile) {
    const std::string in = scene_file().string();
    const std::string out = (temp_dir() / "err.ply").string();
    CliRun r = tool("convert " + in + " " + out + " --selected");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(in + ": points are selected in 2 clouds ('body', 'body.part')"), std::string::npos)
        << r.out;
    r = tool("convert " + in + " " + out + " --entity nope");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(in + ": no cloud named 'nope' (its clouds: 'body', 'body.part')"), std::string::npos)
        << r.out;
    r = tool("convert " + in + " " + out + " --entity body.lattice");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(in + ": 'body.lattice' is a lattice, not a cloud"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));

    // No selection; two clouds of one name.
    ecs::Registry reg;
    use_engine_scene_hooks(reg);
    for (int k = 0; k < 2; ++k) {
        const ecs::Entity e = reg.create();
        reg.emplace<Name>(e, Name{"twin"});
        reg.emplace<SplatCloud>(e, make_surface());
    }
    const fs::path twins = temp_dir() / "twins.glb";
    ASSERT_TRUE(save_scene(reg, twins).ok());
    r = tool("convert " + twins.string() + " " + out + " --selected");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(twins.string() + ": no point is selected"), std::string::npos) << r.out;
    r = tool("convert " + twins.string() + " " + out + " --entity twin");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(twins.string() + ": 2 clouds are named 'twin'"), std::string::npos) << r.out;
    // Only a scene has selections and names: a usage error.
    const fs::path ply = temp_dir() / "plain.ply";
    convert(ply.string() + " --entity body");
    r = tool("convert " + ply.string() + " " + out + " --selected");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("--selected applies to a scene IN"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));
}

TEST(ConvertSubset, InfoListsTheColumns) {
    const CliRun r = tool("info " + scene_file().string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(
        r.out.find("columns  position vec3, normal vec3, axis_u vec3, axis_v vec3, color rgba8, flags u8, "
                   "weight f32"),
        std::string::npos)
        << r.out;
    // Saved without the deleted points: body keeps 38 of 40 (selected 0 2 4 6 10 ..., hidden 4 and 5).
    EXPECT_NE(r.out.find("flags    19 selected, 2 hidden, 0 deleted of 38 points"), std::string::npos)
        << r.out;
    EXPECT_NE(
        r.out.find("columns  position vec3, scale vec3, rotation quat, opacity f32, sh f32 x3, flags u8, "
                   "weight f32"),
        std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("flags    9 selected, 2 hidden, 0 deleted of 29 points"), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("weight   min 0, max 1, mean"), std::string::npos) << r.out;
}

}  // namespace
