// Cut selection (systems/lod/cut.h): on a hand-made octree of known sizes and on a streamed SOG built by
// lod_build.h, the cut covers the hierarchy exactly once, stays within the budget, refines exactly the
// nodes above τ that fit, grows as the camera comes closer, leaves what is behind the camera coarse, and
// reaches every finest node when τ is tiny and the budget large.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <functional>
#include <set>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/operations.h"
#include "systems/lod/cut.h"
#include "systems/lod/lattice_bounds.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

// An octree over [-8, 8]^3, `depth` levels below the root; a node of side a shows detail a / 8 and costs
// 64 splats (a fixed number of Gaussians per node: finer nodes are denser).
lod::CutTree octree(int depth) {
    lod::CutTree t;
    const std::function<std::uint32_t(glm::dvec3, double, int)> make = [&](glm::dvec3 lo, double a,
                                                                           int level) -> std::uint32_t {
        const std::uint32_t self = std::uint32_t(t.nodes.size());
        t.nodes.emplace_back();
        t.nodes[self].lo = lo, t.nodes[self].hi = lo + glm::dvec3(a);
        t.nodes[self].size = a / 8.0, t.nodes[self].splats = 64;
        if (level < depth)
            for (int c = 0; c < 8; ++c) {
                const glm::dvec3 off((c >> 2) & 1, (c >> 1) & 1, c & 1);
                const std::uint32_t ch = make(lo + off * (a / 2), a / 2, level + 1);
                t.nodes[self].children.push_back(ch);
            }
        return self;
    };
    make(glm::dvec3(-8.0), 16.0, 0);
    return t;
}

std::vector<std::int32_t> parents(const lod::CutTree& t) {
    std::vector<std::int32_t> p(t.nodes.size(), -1);
    for (std::size_t i = 0; i < t.nodes.size(); ++i)
        for (const std::uint32_t c : t.nodes[i].children) p[c] = std::int32_t(i);
    return p;
}

// Every finest node has exactly one ancestor-or-self in the cut; the cut's cost is its nodes' sum.
void expect_covers_once(const lod::CutTree& t, const lod::Cut& cut) {
    const std::set<std::uint32_t> in(cut.nodes.begin(), cut.nodes.end());
    ASSERT_EQ(in.size(), cut.nodes.size());
    const auto p = parents(t);
    std::uint64_t cost = 0;
    for (const std::uint32_t n : cut.nodes) cost += t.nodes[n].splats;
    EXPECT_EQ(cost, cut.splats);
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {
        if (!t.nodes[i].children.empty()) continue;
        int hits = 0;
        for (std::int32_t a = std::int32_t(i); a >= 0; a = p[std::size_t(a)])
            hits += in.count(std::uint32_t(a));
        ASSERT_EQ(hits, 1) << "finest node " << i;
    }
}

lod::CutView view_from(glm::dvec3 eye) {
    lod::CutView v;
    v.camera.eye = eye;
    v.camera.target = glm::dvec3(0.0);
    v.camera.fov_y_degrees = 50.0f;
    v.camera.near_plane = 0.05f;
    v.camera.far_plane = 1000.0f;
    v.viewport = {640, 480};
    return v;
}

TEST(LodCut, RefinesExactlyTheNodesAboveTauThatFit) {
    const lod::CutTree t = octree(4);
    for (const double distance : {200.0, 60.0, 20.0, 12.0})
        for (const std::uint64_t budget :
             {std::uint64_t(1000), std::uint64_t(30000), std::uint64_t(1) << 40}) {
            const lod::CutView v = view_from(glm::dvec3(0.3, 0.2, 1.0) * distance);
            lod::CutOptions o;
            o.tau_pixels = 4.0, o.budget = budget;
            const lod::Cut cut = lod::select_cut(t, v, o);
            expect_covers_once(t, cut);
            EXPECT_LE(cut.splats, std::max<std::uint64_t>(budget, t.nodes[0].splats));
            // A node in the cut above τ with children is there only because its children did not fit.
            for (const std::uint32_t n : cut.nodes) {
                const auto& node = t.nodes[n];
                if (node.children.empty() || lod::projected_size(node, v) <= o.tau_pixels) continue;
                std::uint64_t children = 0;
                for (const std::uint32_t c : node.children) children += t.nodes[c].splats;
                EXPECT_GT(cut.splats - node.splats + children, budget) << n;
                EXPECT_TRUE(cut.budget_limited);
            }
            // Every parent of a node in the cut was above τ (nothing refines needlessly).
            const auto p = parents(t);
            for (const std::uint32_t n : cut.nodes) {
                if (p[n] < 0) continue;
                EXPECT_GT(lod::projected_size(t.nodes[std::size_t(p[n])], v), o.tau_pixels);
            }
        }
}

TEST(LodCut, GrowsAsTheCameraComesCloser) {
    const lod::CutTree t = octree(4);
    std::uint64_t before = 0;
    for (const double distance : {1000.0, 300.0, 100.0, 40.0, 20.0, 10.0}) {
        // Without culling: close up, parts of the cube leave the view and would stay coarse.
        const lod::Cut cut =
            lod::select_cut(t, view_from(glm::dvec3(0, 0, distance)), {2.0, 1u << 30, false});
        EXPECT_GE(cut.splats, before) << distance;
        before = cut.splats;
    }
    EXPECT_EQ(lod::select_cut(t, view_from(glm::dvec3(0, 0, 1e6)), {2.0, 1u << 30, true}).nodes,
              std::vector<std::uint32_t>{0});
    // Tiny τ, no budget limit: every finest node.
    const lod::Cut all = lod::select_cut(t, view_from(glm::dvec3(0, 0, 30)), {1e-9, 1u << 30, false});
    std::size_t finest = 0;
    for (const auto& n : t.nodes) finest += n.children.empty();
    EXPECT_EQ(all.nodes.size(), finest);
}

TEST(LodCut, LeavesWhatIsOutOfViewCoarse) {
    const lod::CutTree t = octree(3);
    // Inside the cube at x = 7, looking towards +x: the half at x < 0 is behind the camera.
    lod::CutView v = view_from(glm::dvec3(6.0, 0.0, 0.0));
    v.camera.target = glm::dvec3(20.0, 0.0, 0.0);
    const lod::Cut cut = lod::select_cut(t, v, {1.0, 1u << 30, true});
    expect_covers_once(t, cut);
    bool behind_refined = false, ahead_refined = false;
    for (const std::uint32_t n : cut.nodes) {
        const auto& node = t.nodes[n];
        const double side = node.hi.x - node.lo.x;
        if (node.hi.x <= 0.0 && side < 8.0) behind_refined = true;
        if (node.lo.x >= 4.0 && side <= 2.0) ahead_refined = true;
    }
    EXPECT_FALSE(behind_refined);
    EXPECT_TRUE(ahead_refined);
    EXPECT_TRUE(lod::outside_frustum(glm::dvec3(-8.0), glm::dvec3(0.0, 8.0, 8.0), v));
    EXPECT_FALSE(lod::outside_frustum(glm::dvec3(4.0, -1.0, -1.0), glm::dvec3(8.0, 1.0, 1.0), v));
}

TEST(LodCut, StreamedSogTree) {
    const fs::path d = fs::temp_directory_path() / ("sffd_lod_cut_" + std::to_string(::getpid()));
    fs::remove_all(d);
    lod::LodBuildOptions o;
    o.levels = 4, o.chunk_count = 1024;
    ASSERT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(20000), d / "lod-meta.json", o));
    auto s = lod::open_streamed_sog(d / "lod-meta.json");
    ASSERT_TRUE(s) << s.message();
    const lod::CutTree t = lod::cut_tree(*s);
    // The root costs every leaf's coarsest level; all finest nodes together are level 0.
    EXPECT_EQ(t.nodes[t.root].splats, s->counts[3]);
    std::uint64_t finest = 0;
    for (const auto& n : t.nodes) {
        if (n.children.empty()) {
            EXPECT_EQ(n.level, 0);
            finest += n.splats;
        }
    }
    EXPECT_EQ(finest, s->counts[0]);
    // From afar: the coarsest cut; close up with a big budget: the finest; in between, within the budget.
    const lod::Cut far = lod::select_cut(t, view_from(glm::dvec3(0, 0, 5000)), {1.0, 1u << 30, true});
    EXPECT_EQ(far.splats, s->counts[3]);
    const lod::Cut near = lod::select_cut(t, view_from(glm::dvec3(0, 0, 25)), {0.01, 1u << 30, false});
    EXPECT_EQ(near.splats, s->counts[0]);
    expect_covers_once(t, near);
    const std::uint64_t budget = (s->counts[0] + s->counts[1]) / 2;
    const lod::Cut mid = lod::select_cut(t, view_from(glm::dvec3(0, 0, 25)), {0.01, budget, true});
    expect_covers_once(t, mid);
    EXPECT_LE(mid.splats, budget);
    EXPECT_GT(mid.splats, s->counts[1] / 2);
    EXPECT_TRUE(mid.budget_limited);
    fs::remove_all(d);
}

// A real hierarchy under lattices: every node of the deformed cut tree holds its own Gaussians' centres
// deformed by the reference FFD, at every level, under a twisted B-spline lattice and a stretched
// Bernstein one (in a chain too); the cut of the deformed tree still covers it once within the budget.
TEST(LodCut, DeformedTreeBoundsHoldTheDeformedGaussians) {
    const fs::path d = fs::temp_directory_path() / ("sffd_lod_cut_deformed_" + std::to_string(::getpid()));
    fs::remove_all(d);
    lod::LodBuildOptions o;
    o.levels = 3, o.chunk_count = 1024;
    ASSERT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(12000), d / "lod-meta.json", o));
    auto s = lod::open_streamed_sog(d / "lod-meta.json");
    ASSERT_TRUE(s) << s.message();
    const lod::CutTree tree = lod::cut_tree(*s);
    Lattice twisted =
        make_lattice(glm::dvec3(-12.0), {glm::dvec3(24, 0, 0), glm::dvec3(0, 24, 0), glm::dvec3(0, 0, 24)},
                     glm::ivec3(6), LatticeBasis::bspline);
    ffd::twist_graded(twisted, ffd::all_control_points(twisted), glm::dvec3(0, 1, 0), 0.2);
    Lattice stretched =
        make_lattice(glm::dvec3(-4.0, -11.0, -11.0),
                     {glm::dvec3(15, 0, 0), glm::dvec3(0, 22, 0), glm::dvec3(0, 0, 22)}, glm::ivec3(3));
    ffd::stretch(stretched, ffd::select_range(stretched, glm::ivec3(2, 0, 0), glm::ivec3(3)),
                 glm::dvec3(30, 5, 0));
    std::map<std::uint32_t, GaussianCloud> units;
    const auto unit = [&](std::uint32_t u) -> const GaussianCloud& {
        auto it = units.find(u);
        if (it == units.end()) {
            auto g = lod::read_unit(*s, u);
            EXPECT_TRUE(g) << g.message();
            it = units.emplace(u, g ? std::move(*g) : GaussianCloud{}).first;
        }
        return it->second;
    };
    const std::vector<std::vector<const Lattice*>> chains = {
        {&twisted}, {&stretched}, {&twisted, &stretched}};
    for (const auto& chain : chains) {
        const lod::CutTree deformed = lod::deformed_cut_tree(tree, chain);
        std::size_t checked = 0, outside = 0;
        for (const lod::CutNode& n : deformed.nodes) {
            if (n.level < 0) continue;
            const auto& run = s->nodes[n.source].lods[std::size_t(n.level)];
            ASSERT_TRUE(run);
            const GaussianCloud part = lod::slice(unit(run->file), *run);
            std::vector<glm::vec3> p = part.positions;
            for (const Lattice* l : chain)
                ASSERT_TRUE(
                    ffd::deform(*l, ffd::PointsIn{p.data(), nullptr, nullptr, nullptr, p.size(), part.origin},
                                ffd::PointsOut{p.data()}, ffd::Backend::reference));
            for (const glm::vec3& q : p) {
                const glm::dvec3 x = part.origin + glm::dvec3(q);
                ++checked;
                for (int a = 0; a < 3; ++a) outside += x[a] < n.lo[a] - 1e-4 || x[a] > n.hi[a] + 1e-4;
            }
        }
        EXPECT_EQ(checked, s->total());
        EXPECT_EQ(outside, 0u) << chain.size() << " lattice(s)";
        const lod::Cut cut = lod::select_cut(deformed, view_from(glm::dvec3(5, 3, 30)), {1.0, 8000, true});
        expect_covers_once(deformed, cut);
        EXPECT_LE(cut.splats, 8000u);
    }
    fs::remove_all(d);
}

}  // namespace
