// Cut selection in a Gaussian level-of-detail hierarchy: which nodes to draw for one camera, under a splat
// budget, by projected screen-space error (as hierarchical 3DGS, Kerbl et al. 2024, sec. 5, selects its cut).
//
// A CutTree is any hierarchy whose children together show their parent's region at finer detail. A node
// has bounds (the box of what it draws, in the cloud's frame), a world-space size (the detail it shows:
// how far apart its Gaussians are, the error a viewer sees when the cut stops there) and the splats it
// costs. The cut is a set of nodes that covers the root exactly once (every finest node has exactly one
// ancestor-or-self in it). Selection starts from {root} and refines greedily, largest projected size first:
//
//   projected(n) = size(n) · s · f / max(d, near)   pixels
//
// with s the largest axis scale of the model matrix, f = (height / 2) / tan(fov_y / 2) the focal length in
// pixels and d the distance from the eye to the node's box in the world (0 inside it; the nearest point
// of the box, so no part of the node is seen larger). A node refines (is replaced by its children) while
// its projected size exceeds τ pixels and the cut with its children instead still fits the budget; a
// refinement that does not fit leaves the node in the cut (`budget_limited`) and smaller ones go on. Boxes
// wholly outside the view frustum (with `cull`) have projected size 0 and are never refined: they stay at
// the coarsest detail that covers them.
//
// cut_tree() turns a streamed SOG (runtime/assets/formats/lod/streamed_sog.h) into a CutTree: its spatial
// nodes, and below each leaf one node per level it lists, coarsest first (level l's only child is level
// l − 1). The spatial nodes hold no Gaussians of their own, so each costs what its leaves cost at their
// coarsest level, and its size is the largest of its children's (its box contains theirs, so it refines
// whenever one of them would). A leaf's level l has the leaf's box and size diag(box) / sqrt(n_l), the
// spacing of n_l Gaussians over a surface patch of that extent: the metadata holds no Gaussian sizes, and
// captured scenes are surfaces.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"

namespace sffd::lod {

struct StreamedSog;

struct CutNode {
    glm::dvec3 lo{0.0}, hi{0.0};  // bounds, in the cloud's frame
    double size = 0.0;            // world-space size of its detail (the cloud's frame's units)
    std::uint64_t splats = 0;     // what drawing it costs
    std::vector<std::uint32_t> children;
    // Streamed SOG trees (cut_tree): the spatial node and the level this node draws (-1: a spatial node
    // above the leaves, drawn as its leaves' coarsest levels).
    std::uint32_t source = 0;
    int level = -1;
};

struct CutTree {
    std::vector<CutNode> nodes;  // parents before their children
    std::uint32_t root = 0;
};

struct CutView {
    Camera camera;
    Viewport viewport;
    glm::dmat4 model{1.0};  // the cloud's frame to the world (model_matrix of its Transform)
};

struct CutOptions {
    double tau_pixels = 1.0;           // refine while the projected size exceeds this
    std::uint64_t budget = 3'000'000;  // splats the cut may cost
    bool cull = true;                  // nodes outside the frustum are not refined
};

struct Cut {
    std::vector<std::uint32_t> nodes;  // ascending
    std::uint64_t splats = 0;
    std::size_t refinements = 0;
    bool budget_limited = false;  // a node above τ stayed because its children did not fit
};

// Pixels, as above (0 for a culled node when `cull`).
double projected_size(const CutNode& node, const CutView& view, bool cull = true);
// The box lies wholly outside the view frustum (one of its six planes has all eight corners beyond it).
bool outside_frustum(const glm::dvec3& lo, const glm::dvec3& hi, const CutView& view);

Cut select_cut(const CutTree& tree, const CutView& view, const CutOptions& options = {});

// A streamed SOG as a CutTree (above).
CutTree cut_tree(const StreamedSog& sog);

}  // namespace sffd::lod
