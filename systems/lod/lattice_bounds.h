// Conservative bounds of a hierarchy node under a lattice: a box that holds the FFD image of every point
// of the node's box (../shared/notes/ffd-math.md; systems/ffd/README.md). Cut selection and culling of a
// deformed hierarchy read these instead of deforming the node's Gaussians.
//
// Per lattice, with (s, t, u) the box's local-coordinate range (the box of its eight corners' local
// coordinates, so oblique lattices are covered) clipped to [0, 1]:
//   - the part of the box outside the lattice stays where it is (points outside are not moved), so a box
//     that reaches outside keeps itself in the result;
//   - the displacement D = Σ ΔP_c w_c (ΔP = current − rest) has weights w_c ≥ 0 that sum to 1 (Bernstein;
//     a B-spline window whose four neighbours per axis all exist) or at most 1 (a B-spline window cut by
//     the grid's edge, where 0 joins the hull), and only the control points whose basis is non-zero over
//     the range count: a B-spline's window floor(l s) − 1 .. floor(l s) + 2 per axis; for Bernstein every
//     basis is non-zero inside, so its control net is first restricted to the range (de Casteljau per
//     axis: the Bézier volume over the sub-box has its own control points, whose hull holds it, and
//     shrinks with the range). The box ⊕ hull(D's points) holds the result;
//   - when the rest grid is the uniform one (rest_is_uniform), X' = Σ P_c w_c itself lies in the hull of
//     the same control points (current positions; restricted for Bernstein), which is tighter under
//     rotations (a twist moves control points far, but keeps them around the lattice); the result is the
//     intersection of the two.
// Per-point weights (PointWeights: X + w D, w in [0, 1]) move a point part of the way: `weighted` adds 0 to
// the displacement hull and the box to the control-point hull. A chain of lattices is bounded one after
// the other. Every box is padded by kInsideSlack times the lattice's edges (points that far outside a
// face deform as if on it). deformed_cut_tree() applies it to every node of a cut tree (cut.h).
//
// Covered: the FFD of every point of the box, so every Gaussian centre in it. A deformed Gaussian's extent
// is its covariance through the Jacobian at its centre (J Σ Jᵀ), a linearisation: its 1σ ellipsoid can
// leave the FFD image of the undeformed ellipsoid by a second-order amount where the lattice bends within
// it.
#pragma once

#include <span>

#include "systems/ffd/lattice.h"
#include "systems/lod/cut.h"

namespace sffd::lod {

// The bounds of the FFD image of `box` under `lattice` (in the lattice's frame; `box` in the same frame).
ffd::Box lattice_node_bounds(const Lattice& lattice, const ffd::Box& box, bool weighted = false);
// Through each lattice in order (a chain of Deformers, each already in the cloud's frame).
ffd::Box lattice_node_bounds(std::span<const Lattice* const> lattices, const ffd::Box& box,
                             bool weighted = false);

// A CutTree as its lattices deform it: every node's box replaced by its bounds under the chain, and its
// size grown by as much as its box's diagonal grew (a stretched region shows its Gaussians stretched;
// never shrunk, so a squeeze refines no less than at rest). Cut selection on the result sees the
// deformed hierarchy where it is drawn.
CutTree deformed_cut_tree(const CutTree& tree, std::span<const Lattice* const> lattices,
                          bool weighted = false);

}  // namespace sffd::lod
