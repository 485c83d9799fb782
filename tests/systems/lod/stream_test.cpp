// Streaming a hierarchy (systems/lod/stream.h, streaming.h) on real files made by our writers: a streamed
// SOG of synthetic Gaussians and a Potree 2 octree of synthetic splats. Full detail streams to exactly
// the whole-file readers' points; a cut stays within its splat budget and, while it refines, leaves no
// region undrawn; the memory budget holds while the camera moves and evicts what the new view does not
// use; a lattice that stretches the model refines more; a damaged unit is refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>
#include <vector>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/lattice.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/operations.h"
#include "systems/lod/stream.h"
#include "systems/lod/streaming.h"
#include "systems/picking/picking_system.h"
#include "tests/assets/test_util.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

lod::CutView view_from(glm::dvec3 eye, glm::dvec3 target = glm::dvec3(0.0)) {
    lod::CutView v;
    v.camera.eye = eye;
    v.camera.target = target;
    v.camera.fov_y_degrees = 50.0f;
    v.camera.near_plane = 0.05f;
    v.camera.far_plane = 1000.0f;
    v.viewport = {640, 480};
    return v;
}

// The clouds' points in the world, sorted, compared one to one within `tol` (pieces are shifted to the
// stream's origin in double and stored as float, so they differ from the whole read by float rounding).
using Key = std::array<double, 3>;
std::vector<Key> world_points(const glm::dvec3& origin, const std::vector<glm::vec3>& p) {
    std::vector<Key> k;
    for (const glm::vec3& x : p) {
        const glm::dvec3 w = origin + glm::dvec3(x);
        k.push_back({w.x, w.y, w.z});
    }
    std::sort(k.begin(), k.end());
    return k;
}
void expect_same_points(const glm::dvec3& ao, const std::vector<glm::vec3>& a, const glm::dvec3& bo,
                        const std::vector<glm::vec3>& b, double tol = 1e-4) {
    const auto ka = world_points(ao, a), kb = world_points(bo, b);
    ASSERT_EQ(ka.size(), kb.size());
    std::size_t off = 0;
    for (std::size_t i = 0; i < ka.size(); ++i)
        for (int c = 0; c < 3; ++c)
            if (std::abs(ka[i][std::size_t(c)] - kb[i][std::size_t(c)]) > tol) ++off;
    EXPECT_EQ(off, 0u);
}

fs::path sog_fixture(const std::string& name, std::uint64_t count = 20000) {
    const fs::path d = test::fresh_dir("lod_stream", name);
    lod::LodBuildOptions o;
    o.levels = 3, o.chunk_count = 1024;
    EXPECT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(count), d / "lod-meta.json", o));
    return d / "lod-meta.json";
}

fs::path potree_fixture(const std::string& name, std::uint64_t count = 20000) {
    const fs::path d = test::fresh_dir("lod_stream", name);
    assets::Potree2BuildOptions o;
    o.max_leaf = 1024, o.grid_cells = 16;
    auto built = assets::build_potree2(assets::synthetic_splat_source(count), d / "metadata.json", o);
    EXPECT_TRUE(built) << built.message();
    return d / "metadata.json";
}

lod::StreamOptions everything() {
    lod::StreamOptions o;
    o.tau_pixels = 1e-9, o.splat_budget = std::uint64_t(1) << 40, o.memory_budget = std::uint64_t(1) << 34;
    o.cull = false;
    o.rebound_interval_s = 0.0;
    return o;
}

}  // namespace

TEST(LodStream, SogFullDetailIsTheWholeLevelZero) {
    const fs::path meta = sog_fixture("full");
    auto sog = lod::open_streamed_sog(meta);
    ASSERT_TRUE(sog) << sog.message();
    auto level0 = lod::read_level(*sog, 0);
    ASSERT_TRUE(level0) << level0.message();
    auto s = lod::HierarchyStream::open(meta, everything());
    ASSERT_TRUE(s) << s.message();
    EXPECT_TRUE((*s)->gaussians());
    EXPECT_EQ((*s)->full_detail(), sog->counts[0]);
    (*s)->update(view_from(glm::dvec3(0, 0, 30)));
    ASSERT_TRUE((*s)->wait_complete());
    GaussianCloud g;
    (*s)->assemble(g);
    EXPECT_TRUE((*s)->complete());
    ASSERT_EQ(g.size(), level0->size());
    expect_same_points(g.origin, g.positions, level0->origin, level0->positions);
    const lod::StreamStats st = (*s)->stats();
    EXPECT_EQ(st.drawn_splats, g.size());
    EXPECT_EQ(st.missing_pieces, 0u);
    EXPECT_GT(st.loads, 1u);
    // The same view again: nothing to load, nothing to redraw.
    EXPECT_FALSE((*s)->update(view_from(glm::dvec3(0, 0, 30))));
}

TEST(LodStream, SogCutKeepsItsBudgetAndRefinesWithoutHoles) {
    const fs::path meta = sog_fixture("budget");
    auto sog = lod::open_streamed_sog(meta);
    ASSERT_TRUE(sog);
    lod::StreamOptions o = everything();
    o.tau_pixels = 1.0;
    o.splat_budget = (sog->counts[0] + sog->counts[1]) / 2;
    auto s = lod::HierarchyStream::open(meta, o);
    ASSERT_TRUE(s);
    // From afar: the coarsest level everywhere.
    (*s)->update(view_from(glm::dvec3(0, 0, 5000)));
    ASSERT_TRUE((*s)->wait_complete());
    GaussianCloud coarse;
    (*s)->assemble(coarse);
    EXPECT_EQ(coarse.size(), sog->counts[2]);
    glm::dvec3 clo(1e30), chi(-1e30);
    for (const auto& p : coarse.positions)
        clo = glm::min(clo, glm::dvec3(p)), chi = glm::max(chi, glm::dvec3(p));
    // Close up: the budget holds, and straight after the move (before anything new arrived) the drawn
    // set still spans the whole model: leaves not refined yet draw a coarser level.
    (*s)->update(view_from(glm::dvec3(0, 0, 25)));
    GaussianCloud moving;
    (*s)->assemble(moving);
    glm::dvec3 mlo(1e30), mhi(-1e30);
    for (const auto& p : moving.positions)
        mlo = glm::min(mlo, glm::dvec3(p)), mhi = glm::max(mhi, glm::dvec3(p));
    EXPECT_LT(glm::length(mlo - clo), 0.5);
    EXPECT_LT(glm::length(mhi - chi), 0.5);
    ASSERT_TRUE((*s)->wait_complete());
    GaussianCloud fine;
    (*s)->assemble(fine);
    const lod::StreamStats st = (*s)->stats();
    EXPECT_LE(fine.size(), o.splat_budget);
    EXPECT_GT(fine.size(), sog->counts[1] / 2);
    EXPECT_TRUE(st.budget_limited);
    EXPECT_EQ(st.drawn_splats, fine.size());
    EXPECT_EQ(st.wanted_splats, fine.size());
}

TEST(LodStream, MemoryBudgetHoldsWhileTheCameraMoves) {
    const fs::path meta = sog_fixture("memory", 40000);
    // Close to one side of the sphere (radius 10), then the other: the near side refines further.
    const auto side = [](double x) { return view_from(glm::dvec3(x * 14.0, 0, 0)); };
    lod::StreamOptions o = everything();
    o.tau_pixels = 4.0, o.cull = true;
    // What one side needs, and both together, with room for everything.
    std::uint64_t one = 0, both = 0;
    {
        auto ref = lod::HierarchyStream::open(meta, o);
        ASSERT_TRUE(ref);
        (*ref)->update(side(-1.0));
        ASSERT_TRUE((*ref)->wait_complete());
        one = (*ref)->stats().resident_bytes;
        (*ref)->update(side(1.0));
        ASSERT_TRUE((*ref)->wait_complete());
        both = (*ref)->stats().resident_bytes;
        EXPECT_EQ((*ref)->stats().evictions, 0u);
    }
    ASSERT_GT(both, one + one / 5) << "the two views must want different pieces";
    o.memory_budget = (one + both) / 2;
    auto s = lod::HierarchyStream::open(meta, o);
    ASSERT_TRUE(s);
    for (const double x : {-1.0, 1.0, -1.0, 1.0}) {
        (*s)->update(side(x));
        const Status done = (*s)->wait_complete();
        ASSERT_TRUE(done) << done.message();
        GaussianCloud g;
        (*s)->assemble(g);
        EXPECT_TRUE((*s)->complete());
        EXPECT_GT(g.size(), 0u);
        EXPECT_LE((*s)->stats().peak_resident_bytes, o.memory_budget);
    }
    EXPECT_GT((*s)->stats().evictions, 0u);
    // Everything at once does not fit: refused by name, not loaded past the budget.
    lod::StreamOptions all = everything();
    all.memory_budget = o.memory_budget;
    (*s)->set_options(all);
    (*s)->update(view_from(glm::dvec3(0, 0, 25)));
    const Status st = (*s)->wait_complete();
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find("memory budget"), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(meta.string()), std::string::npos) << st.message();
    EXPECT_LE((*s)->stats().peak_resident_bytes, o.memory_budget);
}

TEST(LodStream, StretchingLatticeRefinesMore) {
    const fs::path meta = sog_fixture("lattice");
    lod::StreamOptions o = everything();
    o.tau_pixels = 6.0;
    auto s = lod::HierarchyStream::open(meta, o);
    ASSERT_TRUE(s);
    const lod::CutView v = view_from(glm::dvec3(0, 0, 60));
    (*s)->update(v);
    const std::uint64_t rest = (*s)->stats().wanted_splats;
    Lattice l =
        make_lattice(glm::dvec3(-11.0), {glm::dvec3(22, 0, 0), glm::dvec3(0, 22, 0), glm::dvec3(0, 0, 22)},
                     glm::ivec3(3), LatticeBasis::bernstein);
    // Scaled up three times about the centre: seen three times larger, so finer levels are needed.
    for (std::size_t i = 0; i < l.current.size(); ++i) l.current[i] = 3.0 * l.rest[i];
    const std::array<const Lattice*, 1> chain{&l};
    (*s)->update(v, chain, 1);
    const std::uint64_t stretched = (*s)->stats().wanted_splats;
    EXPECT_GT(stretched, rest);
    // Back at rest (a new stamp): the rest cut again.
    (*s)->update(v, {}, 2);
    EXPECT_EQ((*s)->stats().wanted_splats, rest);
}

TEST(LodStream, DamagedUnitIsRefusedByName) {
    const fs::path meta = sog_fixture("damaged");
    auto sog = lod::open_streamed_sog(meta);
    ASSERT_TRUE(sog);
    // Truncate one image of the finest level's first unit: open() sized it, decoding finds the damage.
    fs::path victim;
    for (const auto& u : sog->units)
        if (u.level == 0 && u.parts.size() > 1) {
            victim = u.parts[1].path;
            break;
        }
    ASSERT_FALSE(victim.empty());
    const std::string bytes = test::slurp(victim);
    test::write(victim, bytes.substr(0, bytes.size() / 3));
    auto s = lod::HierarchyStream::open(meta, everything());
    ASSERT_TRUE(s) << s.message();
    (*s)->update(view_from(glm::dvec3(0, 0, 30)));
    const Status st = (*s)->wait_complete();
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find(victim.parent_path().filename().string()), std::string::npos) << st.message();
    EXPECT_FALSE((*s)->error());
    // What did load is still drawn.
    GaussianCloud g;
    (*s)->assemble(g);
    EXPECT_GT(g.size(), 0u);
}

TEST(LodStream, RefusesWhatIsNotAHierarchy) {
    const fs::path d = test::fresh_dir("lod_stream", "not");
    test::write(d / "cloud.ply", "ply\n");
    auto s = lod::HierarchyStream::open(d / "cloud.ply");
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("cloud.ply"), std::string::npos) << s.message();
    test::write(d / "lod-meta.json", "{\"lodLevels\": 1, \"filenames\": [], \"tree\": 7}");
    auto bad = lod::HierarchyStream::open(d / "lod-meta.json");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.message().find("lod-meta.json"), std::string::npos) << bad.message();
}

TEST(LodStream, PotreeFullDetailIsTheWholeOctree) {
    const fs::path meta = potree_fixture("full");
    auto oc = assets::open_potree2(meta);
    ASSERT_TRUE(oc) << oc.message();
    auto whole = assets::read_potree2(*oc);
    ASSERT_TRUE(whole);
    auto s = lod::HierarchyStream::open(meta, everything());
    ASSERT_TRUE(s) << s.message();
    EXPECT_FALSE((*s)->gaussians());
    (*s)->update(view_from(glm::dvec3(0, 0, 3)));
    ASSERT_TRUE((*s)->wait_complete());
    SplatCloud c;
    (*s)->assemble(c);
    ASSERT_EQ(c.size(), whole->size());
    expect_same_points(c.origin, c.positions, whole->origin, whole->positions);
    // Every node drawn with its children: every splat at its own radius, as the whole read gives them.
    double a = 0.0, b = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        a += double(glm::length(c.axis_u[i]));
        b += double(glm::length(whole->axis_u[i]));
    }
    EXPECT_NEAR(a, b, 1e-6 * b);
}

TEST(LodStream, PotreeRootAloneStandsForTheWholeModel) {
    const fs::path meta = potree_fixture("root");
    auto oc = assets::open_potree2(meta);
    ASSERT_TRUE(oc);
    auto root = assets::read_potree2_node(*oc, 0);  // grown to cover its children
    ASSERT_TRUE(root);
    lod::StreamOptions o = everything();
    o.tau_pixels = 1e12;  // nothing refines
    auto s = lod::HierarchyStream::open(meta, o);
    ASSERT_TRUE(s);
    (*s)->update(view_from(glm::dvec3(0, 0, 3)));
    ASSERT_TRUE((*s)->wait_complete());
    SplatCloud c;
    (*s)->assemble(c);
    ASSERT_EQ(c.size(), root->size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_EQ(c.positions[i], root->positions[i]);
        EXPECT_EQ(c.axis_u[i], root->axis_u[i]);
        EXPECT_EQ(c.axis_v[i], root->axis_v[i]);
    }
    // A budget between the root and everything: the parents of every drawn node are drawn.
    o.tau_pixels = 1e-9, o.splat_budget = oc->points / 3;
    (*s)->set_options(o);
    (*s)->update(view_from(glm::dvec3(0, 0, 3)));
    ASSERT_TRUE((*s)->wait_complete());
    SplatCloud part;
    (*s)->assemble(part);
    EXPECT_LE(part.size(), o.splat_budget);
    EXPECT_GT(part.size(), root->size());
    EXPECT_TRUE((*s)->stats().budget_limited);
}

TEST(LodStream, StreamingSystemDrawsTheCutInTheEngine) {
    const fs::path meta = sog_fixture("engine");
    auto sog = lod::open_streamed_sog(meta);
    ASSERT_TRUE(sog);
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    lod::StreamSettings settings;
    settings.options = everything();
    settings.wait = true;
    settings.first_cut_budget = 2000;  // below the coarsest level's count: the coarsest level alone
    lod::enable_streaming(registry, settings);
    ASSERT_TRUE(load_scene(registry, meta.string()));
    std::vector<ecs::Entity> clouds;
    registry.view<const GaussianCloud>().each(
        [&](ecs::Entity e, const GaussianCloud&) { clouds.push_back(e); });
    ASSERT_EQ(clouds.size(), 1u);
    ASSERT_TRUE(registry.has<lod::StreamedCloud>(clouds[0]));
    EXPECT_EQ(registry.count<Camera>(), 1u);
    // The first cut is small and whole; the streaming system then draws the camera's full-detail cut.
    const std::size_t first = registry.get<GaussianCloud>(clouds[0]).size();
    EXPECT_GT(first, 0u);
    EXPECT_EQ(first, sog->counts.back());
    const std::uint64_t before = registry.version<GaussianCloud>(clouds[0]);
    lod::streaming_system(registry, {});
    EXPECT_EQ(registry.get<GaussianCloud>(clouds[0]).size(), sog->counts[0]);
    EXPECT_GT(registry.version<GaussianCloud>(clouds[0]), before);
    const std::uint64_t stamped = registry.version<GaussianCloud>(clouds[0]);
    lod::streaming_system(registry, {});  // nothing changed: not written again
    EXPECT_EQ(registry.version<GaussianCloud>(clouds[0]), stamped);
    const lod::StreamSummary sum = lod::stream_summary(registry);
    EXPECT_EQ(sum.clouds, 1u);
    EXPECT_EQ(sum.stats.drawn_splats, sog->counts[0]);
}

// A final render's cut that does not fit the memory budget: the system keeps the failure for the caller
// (stream_status), which refuses the frame; it prints nothing itself.
TEST(LodStream, WaitedCutOverTheMemoryBudgetIsReportedToTheCaller) {
    const fs::path meta = sog_fixture("over_budget");
    auto sog = lod::open_streamed_sog(meta);
    ASSERT_TRUE(sog);
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    lod::StreamSettings settings;
    settings.options = everything();
    // The coarsest level fits, full detail (56 bytes a Gaussian of SH degree 0) does not.
    settings.options.memory_budget = sog->counts[0] * 56 / 3;
    ASSERT_LT(sog->counts.back() * 56 * 2, settings.options.memory_budget);
    settings.wait = true;
    settings.first_cut_budget = 2000;
    lod::enable_streaming(registry, settings);
    ASSERT_TRUE(load_scene(registry, meta.string()));
    EXPECT_TRUE(lod::stream_status(registry));
    testing::internal::CaptureStderr();
    lod::streaming_system(registry, {});
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    const Status st = lod::stream_status(registry);
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find(meta.string() + ": the cut of " + std::to_string(sog->counts[0]) + " splats"),
              std::string::npos)
        << st.message();
    EXPECT_NE(st.message().find("memory budget"), std::string::npos) << st.message();
}

// Picking casts against what is drawn: the first, coarse cut of a streamed unit sphere and, once the
// streaming system has drawn the full detail, the finest splats, both hit on the sphere's surface.
TEST(LodStream, PickingHitsTheDrawnCut) {
    const fs::path meta = potree_fixture("pick");
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    lod::StreamSettings settings;
    settings.options = everything();
    settings.wait = true;
    settings.first_cut_budget = 1;  // the root alone
    lod::enable_streaming(registry, settings);
    ASSERT_TRUE(load_scene(registry, meta.string()));
    ecs::Entity cloud = ecs::null_entity;
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud&) { cloud = e; });
    ASSERT_NE(cloud, ecs::null_entity);
    const std::size_t coarse = registry.get<SplatCloud>(cloud).size();
    const picking::PickQuery q =
        picking::query_from_ray(Ray{glm::dvec3(0.1, 0.2, 5.0), glm::dvec3(0, 0, -1)});
    const double surface = std::sqrt(1.0 - 0.1 * 0.1 - 0.2 * 0.2);
    const picking::PickHit a = picking::pick(registry, picking::picking_state(registry), q);
    ASSERT_TRUE(a);
    EXPECT_EQ(a.entity, cloud);
    EXPECT_LT(a.index, coarse);
    EXPECT_NEAR(a.position.z, surface, 0.15);  // the root's splats are grown to cover the octree's detail
    lod::streaming_system(registry, {});
    const std::size_t fine = registry.get<SplatCloud>(cloud).size();
    EXPECT_GT(fine, coarse);
    const picking::PickHit b = picking::pick(registry, picking::picking_state(registry), q);
    ASSERT_TRUE(b);
    EXPECT_EQ(b.entity, cloud);
    EXPECT_LT(b.index, fine);
    EXPECT_NEAR(b.position.z, surface, 0.02);
}

// A drag keeps what is drawn (the deformers show the edit on it), and the first still frame draws the
// cut of the deformed shape: a lattice that scales the model three times needs finer levels.
TEST(LodStream, DrawnSetIsKeptWhileTheLatticeMovesAndRefinedWhenItStops) {
    const fs::path meta = sog_fixture("hold");
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    lod::StreamSettings settings;
    settings.options = everything();
    settings.options.tau_pixels = 10.0;  // at 1280x720 from 60 units: a cut between the levels
    settings.assemble_interval_s = 0.0;
    lod::enable_streaming(registry, settings);
    ASSERT_TRUE(load_scene(registry, meta.string()));
    ecs::Entity cloud = ecs::null_entity;
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud&) { cloud = e; });
    ASSERT_NE(cloud, ecs::null_entity);
    registry.view<Camera>().each([&](Camera& c) { c = view_from(glm::dvec3(0, 0, 60)).camera; });
    Lattice rest =
        make_lattice(glm::dvec3(-11.0), {glm::dvec3(22, 0, 0), glm::dvec3(0, 22, 0), glm::dvec3(0, 0, 22)},
                     glm::ivec3(3), LatticeBasis::bernstein);
    const ecs::Entity lattice = registry.create();
    registry.emplace<Lattice>(lattice, rest);
    if (const Transform* t = registry.try_get<Transform>(cloud)) registry.emplace<Transform>(lattice, *t);
    registry.emplace<Deformers>(cloud, Deformers{{lattice}});
    // Settled at rest: one frame that waits for the cut.
    registry.resource<lod::StreamSettings>().wait = true;
    lod::streaming_system(registry, {});
    registry.resource<lod::StreamSettings>().wait = false;
    const std::size_t at_rest = registry.get<GaussianCloud>(cloud).size();
    ASSERT_LT(at_rest, 20000u) << "the rest cut must not be full detail already";
    const std::uint64_t stamp = registry.version<GaussianCloud>(cloud);
    // Dragged for a few frames (each frame another scale): nothing is written.
    for (const double f : {1.5, 2.2, 3.0}) {
        Lattice& l = registry.patch<Lattice>(lattice);
        for (std::size_t i = 0; i < l.current.size(); ++i) l.current[i] = f * l.rest[i];
        lod::streaming_system(registry, {});
        EXPECT_EQ(registry.version<GaussianCloud>(cloud), stamp);
    }
    // Still: the deformed shape's cut, once its pieces are in.
    const auto& sc = registry.get<lod::StreamedCloud>(cloud);
    ASSERT_TRUE(sc.stream->wait_complete());
    lod::streaming_system(registry, {});
    EXPECT_GT(registry.version<GaussianCloud>(cloud), stamp);
    EXPECT_GT(registry.get<GaussianCloud>(cloud).size(), at_rest);
}

// The drawn cut deforms as any cloud: moving one corner control point of a B-spline lattice re-deforms only
// the pages (runs of the cut's nodes) its support reaches, and the cut is kept while it moves.
TEST(LodStream, ControlPointEditRedeformsOnlyTheCutPagesItReaches) {
    const fs::path meta = potree_fixture("pages", 700000);  // about 11 pages of 65,536
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    lod::StreamSettings settings;
    settings.options = everything();
    settings.wait = true;
    lod::enable_streaming(registry, settings);
    ASSERT_TRUE(load_scene(registry, meta.string()));
    ecs::Entity cloud = ecs::null_entity;
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud&) { cloud = e; });
    ASSERT_NE(cloud, ecs::null_entity);
    registry.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    const ecs::Entity lattice = registry.create();
    registry.emplace<Lattice>(
        lattice,
        make_lattice(glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                     glm::ivec3(6), LatticeBasis::bspline));
    registry.emplace<Deformers>(cloud, Deformers{{lattice}});
    lod::streaming_system(registry, {});  // the full-detail cut, waited for
    registry.resource<lod::StreamSettings>().wait = false;
    ffd_system(registry, {});
    const std::size_t drawn = registry.get<SplatCloud>(cloud).size();
    const std::uint64_t stamp = registry.version<SplatCloud>(cloud);
    ASSERT_GT(registry.resource<FfdStats>().last_pages.total, 8u);
    // One corner control point pulled out: the cut stays, and a few of its pages are deformed again.
    ffd::stretch(registry.patch<Lattice>(lattice),
                 ffd::select_range(registry.get<Lattice>(lattice), glm::ivec3(0), glm::ivec3(0)),
                 glm::dvec3(-0.3, -0.3, -0.3));
    lod::streaming_system(registry, {});
    EXPECT_EQ(registry.version<SplatCloud>(cloud), stamp);
    ffd_system(registry, {});
    const FfdStats::LastPages p = registry.resource<FfdStats>().last_pages;
    EXPECT_GT(p.redone, 0u);
    EXPECT_LT(p.redone, p.total / 2) << p.redone << " of " << p.total;
    EXPECT_EQ(registry.get<SplatCloud>(cloud).size(), drawn);
}
