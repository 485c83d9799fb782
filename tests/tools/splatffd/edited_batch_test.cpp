// The batch commands on an edited cloud, through the built binary: a scene whose cloud (surface splats, or
// 3D Gaussians) has hidden and deleted points and per-point weights 0, 0.5, 1, bound to a lattice whose
// control points all moved by D. `convert`, `deform` and `export` write the same cloud: no hidden or
// deleted point, and each kept point at P + w D (the engine's P + w (FFD(P) - P)). The weights travel
// with their points into every file that holds them (PLY `weight`, glTF `_WEIGHT`), in any point order.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/ply_weights.h"
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

constexpr std::size_t kPoints = 12;
const glm::dvec3 kMove(0.25, -0.125, 0.5);

fs::path temp_dir() {
    static const fs::path d = [] {
        const fs::path p = fs::temp_directory_path() / ("sffd_edited_batch_" + std::to_string(::getpid()));
        fs::remove_all(p);
        fs::create_directories(p);
        return p;
    }();
    return d;
}

glm::vec3 rest(std::size_t i) {
    return {0.1f * float(i) - 0.6f, 0.05f * float(i % 4), -0.2f + 0.03f * float(i)};
}
float weight(std::size_t i) { return 0.5f * float(i % 3); }
std::uint8_t flag(std::size_t i) { return i == 2 ? kPointHidden : i == 5 ? kPointDeleted : 0; }
// The points a cloud file holds: neither hidden nor deleted.
std::vector<std::size_t> shown() {
    std::vector<std::size_t> k;
    for (std::size_t i = 0; i < kPoints; ++i)
        if (!(flag(i) & kPointGone)) k.push_back(i);
    return k;
}

// A scene of one cloud of either kind with flags, weights and a lattice moved by kMove, saved.
fs::path scene_file(bool gaussians) {
    ecs::Registry r;
    use_engine_scene_hooks(r);
    const ecs::Entity c = r.create();
    r.emplace<Name>(c, Name{"edited"});
    r.emplace<Transform>(c, Transform{});
    if (gaussians) {
        GaussianCloud g;
        for (std::size_t i = 0; i < kPoints; ++i) {
            g.positions.push_back(rest(i));
            g.scales.emplace_back(0.01f);
            g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
            g.opacities.push_back(0.8f);
            g.sh.insert(g.sh.end(), {0.1f, 0.2f, 0.3f});
        }
        r.emplace<GaussianCloud>(c, std::move(g));
    } else {
        SplatCloud s;
        for (std::size_t i = 0; i < kPoints; ++i) {
            s.positions.push_back(rest(i));
            s.normals.emplace_back(0.0f, 0.0f, 1.0f);
            s.axis_u.emplace_back(0.01f, 0.0f, 0.0f);
            s.axis_v.emplace_back(0.0f, 0.01f, 0.0f);
        }
        r.emplace<SplatCloud>(c, std::move(s));
    }
    PointFlags f;
    PointWeights w;
    for (std::size_t i = 0; i < kPoints; ++i) f.bits.push_back(flag(i)), w.values.push_back(weight(i));
    r.emplace<PointFlags>(c, std::move(f));
    r.emplace<PointWeights>(c, std::move(w));
    const ecs::Entity l = r.create();
    r.emplace<Name>(l, Name{"edited.lattice"});
    r.emplace<Transform>(l, Transform{});
    Lattice lattice =
        make_lattice(glm::dvec3(-1.0), {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                     glm::ivec3(2, 2, 2));
    for (glm::dvec3& p : lattice.current) p += kMove;
    r.emplace<Lattice>(l, std::move(lattice));
    r.emplace<Deformers>(c, Deformers{{l}});
    const fs::path p = temp_dir() / (gaussians ? "gaussians.glb" : "surface.glb");
    const Status s = save_scene(r, p);
    EXPECT_TRUE(s.ok()) << s.message();
    return p;
}

void expect_weighted(const std::vector<glm::vec3>& got, const std::string& what) {
    const std::vector<std::size_t> k = shown();
    ASSERT_EQ(got.size(), k.size()) << what << ": the hidden and the deleted point are left out";
    for (std::size_t j = 0; j < k.size(); ++j)
        for (int a = 0; a < 3; ++a)
            EXPECT_NEAR(double(got[j][a]), double(rest(k[j])[a]) + double(weight(k[j])) * kMove[a], 1e-5)
                << what << ": point " << k[j] << " (weight " << weight(k[j]) << "), axis " << a;
}

sffd::test::CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

TEST(EditedBatch, SurfaceCloudIsWrittenWithoutGonePointsAndByItsWeights) {
    const fs::path scene = scene_file(false);
    const fs::path dir = temp_dir() / "surface_frames";
    const std::vector<std::pair<std::string, fs::path>> runs = {
        {"convert " + scene.string() + " " + (temp_dir() / "c.ply").string(), temp_dir() / "c.ply"},
        {"deform " + scene.string() + " " + (temp_dir() / "d.ply").string(), temp_dir() / "d.ply"},
        {"export " + scene.string() + " --format ply --out " + dir.string(), dir / "frame0000.ply"},
    };
    for (const auto& [args, out] : runs) {
        const sffd::test::CliRun r = tool(args);
        ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
        auto c = assets::import_splat_cloud(out);
        ASSERT_TRUE(c.ok()) << c.message();
        expect_weighted(c->positions, args);
    }
}

TEST(EditedBatch, GaussiansAreWrittenWithoutGonePointsAndByTheirWeights) {
    const fs::path scene = scene_file(true);
    const fs::path dir = temp_dir() / "gaussian_frames";
    const std::vector<std::pair<std::string, fs::path>> runs = {
        {"convert " + scene.string() + " " + (temp_dir() / "gc.ply").string(), temp_dir() / "gc.ply"},
        {"deform " + scene.string() + " " + (temp_dir() / "gd.ply").string(), temp_dir() / "gd.ply"},
        {"export " + scene.string() + " --format ply --out " + dir.string(), dir / "frame0000.ply"},
    };
    for (const auto& [args, out] : runs) {
        const sffd::test::CliRun r = tool(args);
        ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
        auto g = gaussian::read_gaussians(out);
        ASSERT_TRUE(g.ok()) << g.message();
        expect_weighted(g->positions, args);
    }
}

// The weights of the points of `cloud_file` (a PLY's column, or a scene's PointWeights), by position.
std::map<std::array<float, 3>, float> weights_by_position(const fs::path& file) {
    std::map<std::array<float, 3>, float> out;
    ecs::Registry r;
    use_engine_scene_hooks(r);
    const Status s = load_scene(r, file.string());
    EXPECT_TRUE(s.ok()) << s.message();
    r.each_entity([&](ecs::Entity e) {
        const PointWeights* w = r.try_get<PointWeights>(e);
        std::vector<glm::vec3> p;
        if (const SplatCloud* c = r.try_get<SplatCloud>(e)) p = c->positions;
        if (const GaussianCloud* g = r.try_get<GaussianCloud>(e)) p = g->positions;
        if (p.empty()) return;
        EXPECT_TRUE(w && w->values.size() == p.size()) << file << ": no weights beside the cloud";
        for (std::size_t i = 0; w && i < p.size() && i < w->values.size(); ++i)
            out[{p[i].x, p[i].y, p[i].z}] = w->values[i];
    });
    return out;
}

void expect_weights(const fs::path& file, const std::vector<std::size_t>& points, const std::string& what) {
    const auto got = weights_by_position(file);
    ASSERT_EQ(got.size(), points.size()) << what;
    for (std::size_t i : points) {
        const glm::vec3 p = rest(i);
        const auto it = got.find({p.x, p.y, p.z});
        ASSERT_NE(it, got.end()) << what << ": point " << i;
        EXPECT_EQ(it->second, weight(i)) << what << ": point " << i;
    }
}

TEST(EditedBatch, WeightsTravelWithTheirPointsIntoEveryFileThatHoldsThem) {
    // A point-cloud PLY with a weight column.
    const fs::path ply = temp_dir() / "weighted.ply";
    {
        std::ofstream f(ply);
        f.precision(9);  // every float exactly
        f << "ply\nformat ascii 1.0\nelement vertex " << kPoints << "\n";
        for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "axis_ux", "axis_uy", "axis_uz", "axis_vx",
                              "axis_vy", "axis_vz", "weight"})
            f << "property float " << p << "\n";
        f << "end_header\n";
        for (std::size_t i = 0; i < kPoints; ++i)
            f << rest(i).x << " " << rest(i).y << " " << rest(i).z << " 0 0 1 0.01 0 0 0 0.01 0 " << weight(i)
              << "\n";
    }
    std::vector<std::size_t> all;
    for (std::size_t i = 0; i < kPoints; ++i) all.push_back(i);
    const std::vector<std::pair<std::string, fs::path>> plain = {
        {"convert " + ply.string() + " " + (temp_dir() / "w.glb").string(), temp_dir() / "w.glb"},
        {"convert " + ply.string() + " " + (temp_dir() / "wm.ply").string() + " --order morton",
         temp_dir() / "wm.ply"},
        {"convert " + ply.string() + " " + (temp_dir() / "wl.glb").string() + " --lattice fit:2,2,2",
         temp_dir() / "wl.glb"},
        {"deform " + ply.string() + " " + (temp_dir() / "wd.glb").string() + " --lattice fit:2,2,2",
         temp_dir() / "wd.glb"},
    };
    for (const auto& [args, out] : plain) {
        const sffd::test::CliRun r = tool(args);
        ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
        expect_weights(out, all, args);
    }
    // A scene's cloud written out: the weights of the points kept, for both kinds (3DGS PLY, surface PLY),
    // and a Gaussian PLY's weights into a scene with a fitted lattice.
    const fs::path gply = temp_dir() / "gw.ply", sply = temp_dir() / "sw.ply", gscene = temp_dir() / "gw.glb";
    for (const std::string& args :
         {"convert " + scene_file(true).string() + " " + gply.string() + " --rest",
          "convert " + scene_file(false).string() + " " + sply.string() + " --rest",
          "convert " + gply.string() + " " + gscene.string() + " --lattice fit:2,2,2"}) {
        const sffd::test::CliRun r = tool(args);
        ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
    }
    expect_weights(sply, shown(), "surface scene to PLY");
    auto gw = assets::read_ply_weights(gply);
    ASSERT_TRUE(gw.ok()) << gw.message();
    ASSERT_EQ(gw->values.size(), shown().size());
    for (std::size_t j = 0; j < shown().size(); ++j) EXPECT_EQ(gw->values[j], weight(shown()[j])) << j;
    ecs::Registry r;
    use_engine_scene_hooks(r);
    ASSERT_TRUE(load_scene(r, gscene.string()).ok());
    std::size_t weighted = 0;
    r.each_entity([&](ecs::Entity e) {
        if (const PointWeights* w = r.try_get<PointWeights>(e); w && r.has<GaussianCloud>(e)) {
            EXPECT_EQ(w->values, gw->values);
            ++weighted;
        }
    });
    EXPECT_EQ(weighted, 1u);
}

}  // namespace
