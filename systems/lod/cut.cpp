#include "systems/lod/cut.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <utility>

#include "runtime/assets/formats/lod/streamed_sog.h"

namespace sffd::lod {

namespace {

std::array<glm::dvec3, 8> world_corners(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dmat4& m) {
    std::array<glm::dvec3, 8> c;
    for (int i = 0; i < 8; ++i) {
        const glm::dvec3 p((i & 4) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 1) ? hi.z : lo.z);
        c[std::size_t(i)] = glm::dvec3(m * glm::dvec4(p, 1.0));
    }
    return c;
}

double largest_scale(const glm::dmat4& m) {
    return std::max(
        {glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
}

}  // namespace

bool outside_frustum(const glm::dvec3& lo, const glm::dvec3& hi, const CutView& view) {
    const glm::dmat4 clip =
        projection_matrix(view.camera, view.viewport) * view_matrix(view.camera) * view.model;
    std::array<glm::dvec4, 8> c;
    for (int i = 0; i < 8; ++i)
        c[std::size_t(i)] =
            clip * glm::dvec4((i & 4) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 1) ? hi.z : lo.z, 1.0);
    // Plane a: -w <= x_a <= w (a = x, y, z); every corner beyond the same plane puts the box outside.
    for (int a = 0; a < 3; ++a) {
        bool below = true, above = true;
        for (const glm::dvec4& p : c) {
            below = below && p[a] < -p.w;
            above = above && p[a] > p.w;
        }
        if (below || above) return true;
    }
    return false;
}

double projected_size(const CutNode& node, const CutView& view, bool cull) {
    if (cull && outside_frustum(node.lo, node.hi, view)) return 0.0;
    const auto corners = world_corners(node.lo, node.hi, view.model);
    glm::dvec3 lo = corners[0], hi = corners[0];
    for (const glm::dvec3& p : corners) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::dvec3 e = view.camera.eye;
    const double d = glm::length(glm::max(glm::max(lo - e, e - hi), glm::dvec3(0.0)));
    const double fov = glm::radians(double(view.camera.fov_y_degrees));
    const double focal = 0.5 * double(view.viewport.height) / std::tan(0.5 * fov);
    const double near = std::max(double(view.camera.near_plane), 1e-9);
    return node.size * largest_scale(view.model) * focal / std::max(d, near);
}

Cut select_cut(const CutTree& tree, const CutView& view, const CutOptions& o) {
    Cut cut;
    if (tree.nodes.empty()) return cut;
    // The frontier: nodes in the cut that may still refine, largest projected size first.
    using Entry = std::pair<double, std::uint32_t>;
    std::priority_queue<Entry> open;
    std::vector<std::uint32_t> done;
    cut.splats = tree.nodes[tree.root].splats;
    open.push({projected_size(tree.nodes[tree.root], view, o.cull), tree.root});
    while (!open.empty()) {
        const auto [size, n] = open.top();
        const CutNode& node = tree.nodes[n];
        if (!(size > o.tau_pixels)) break;  // every node left is at or below τ
        open.pop();
        if (node.children.empty()) {
            done.push_back(n);
            continue;
        }
        std::uint64_t children = 0;
        for (const std::uint32_t c : node.children) children += tree.nodes[c].splats;
        const std::uint64_t after = cut.splats - node.splats + children;
        if (after > o.budget && children > node.splats) {
            cut.budget_limited = true;
            done.push_back(n);
            continue;
        }
        cut.splats = after;
        ++cut.refinements;
        for (const std::uint32_t c : node.children)
            open.push({projected_size(tree.nodes[c], view, o.cull), c});
    }
    for (; !open.empty(); open.pop()) done.push_back(open.top().second);
    std::sort(done.begin(), done.end());
    cut.nodes = std::move(done);
    return cut;
}

CutTree cut_tree(const StreamedSog& sog) {
    CutTree t;
    if (sog.nodes.empty()) return t;
    // Spatial node i keeps index i; each leaf's levels follow, coarsest first.
    t.nodes.resize(sog.nodes.size());
    for (std::size_t i = 0; i < sog.nodes.size(); ++i) {
        CutNode& c = t.nodes[i];
        c.lo = sog.nodes[i].lo, c.hi = sog.nodes[i].hi, c.source = std::uint32_t(i);
    }
    for (std::size_t i = 0; i < sog.nodes.size(); ++i) {
        const LodNode& n = sog.nodes[i];
        if (!n.children.empty()) continue;
        const double diag = glm::length(n.hi - n.lo);
        std::uint32_t above = std::uint32_t(i);  // the node the next level hangs below
        bool first = true;
        for (int l = sog.levels - 1; l >= 0; --l) {
            const auto& run = n.lods[std::size_t(l)];
            if (!run) continue;
            CutNode c;
            c.lo = n.lo, c.hi = n.hi, c.source = std::uint32_t(i), c.level = l, c.splats = run->count;
            c.size = run->count > 0 ? diag / std::sqrt(double(run->count)) : 0.0;
            if (first) {
                // The leaf's spatial node draws its coarsest level itself.
                t.nodes[i].level = l, t.nodes[i].splats = c.splats, t.nodes[i].size = c.size;
                first = false;
                continue;
            }
            const std::uint32_t at = std::uint32_t(t.nodes.size());
            t.nodes[above].children.push_back(at);
            t.nodes.push_back(std::move(c));
            above = at;
        }
    }
    // Spatial nodes above the leaves: their leaves' coarsest cost, their children's largest size (children
    // come after their parent, so a backward pass sees every child first).
    for (std::size_t i = sog.nodes.size(); i-- > 0;) {
        const LodNode& n = sog.nodes[i];
        if (n.children.empty()) continue;
        CutNode& c = t.nodes[i];
        c.splats = 0, c.size = 0.0;
        for (const std::uint32_t ch : n.children) {
            c.children.push_back(ch);
            c.splats += t.nodes[ch].splats;
            c.size = std::max(c.size, t.nodes[ch].size);
        }
    }
    t.root = 0;
    return t;
}

}  // namespace sffd::lod
