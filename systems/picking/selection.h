// Selection operations on a lattice's control points, for the editor (systems/editor records each result
// on its undo stack). Pure functions over LatticeSelection and plain inputs; the two registry helpers at
// the end only gather those inputs (world positions, visibility, the rest position under a surface hit).
//
//   sel = select(sel, {hit.index}, select_mode(shift, ctrl));                  // click / shift / ctrl
//   sel = select(sel, control_points_in_rect(points, view, rect), mode);      // box select
//   sel = select(sel, brush_select(lattice, local_point, {.top_k = 4}), mode); // surface brush
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/screen_view.h"

namespace sffd::picking {

enum class SelectMode : std::uint8_t { replace, add, remove };

// Click modifiers: plain click replaces, shift adds, ctrl removes (ctrl wins when both are held).
SelectMode select_mode(bool shift, bool ctrl);

// The selection after applying `picked` with `mode`. Replace with nothing picked clears the selection
// (a click into empty space); add/remove with nothing picked leave it unchanged. Result sorted, unique.
LatticeSelection select(const LatticeSelection& current, std::span<const std::uint32_t> picked,
                        SelectMode mode);

bool is_selected(const LatticeSelection& selection, std::uint32_t index);

// --- box select -----------------------------------------------------------------------------------
// A screen rectangle in pixels (y down); corners in any order (a drag from any direction).
struct ScreenRect {
    glm::dvec2 a{0.0}, b{0.0};
};

// Indices of the points whose projection lies inside the rectangle (borders included) and in front of
// the camera, and for which `visible` (when given) returns true.
std::vector<std::uint32_t> control_points_in_rect(std::span<const glm::dvec3> world_points,
                                                  const ScreenView& view, ScreenRect rect,
                                                  const std::function<bool(const glm::dvec3&)>& visible = {});

// Registry form: the lattice entity's control points; with `visible_only`, points hidden behind a
// surface (from the eye) are left out — pass visible_only = !xray.
std::vector<std::uint32_t> control_points_in_rect(ecs::Registry& registry, PickingState& state,
                                                  ecs::Entity lattice, const ScreenView& view,
                                                  ScreenRect rect, bool visible_only);

// --- surface brush --------------------------------------------------------------------------------
// Lattice-local coordinates (s, t, u) = M⁻¹ (X − X0), M = [S T U] (notes/ffd-math.md). nullopt when the
// lattice axes are degenerate.
std::optional<glm::dvec3> lattice_local_coordinates(const Lattice& lattice, const glm::dvec3& point);

// Basis weight of every control point at a point X in the lattice's space (same flat indexing as
// Lattice::current): B(l,i,s) B(m,j,t) B(n,k,u) for Bernstein lattices, N(l s − i) N(m t − j) N(n u − k)
// for cubic B-spline lattices. All zeros when X is outside the lattice (any coordinate outside [0, 1]).
std::vector<double> control_point_weights(const Lattice& lattice, const glm::dvec3& point);

struct BrushOptions {
    std::size_t top_k = 0;      // keep at most this many (0: no limit)
    double min_fraction = 0.5;  // keep weights >= min_fraction * the largest weight
};

// The control points with the most influence at X, by decreasing weight (ties: lower index first).
// Empty when X is outside the lattice.
std::vector<std::uint32_t> brush_select(const Lattice& lattice, const glm::dvec3& point,
                                        const BrushOptions& options);

// Where a surface hit lies in the lattice's (undeformed) space: the authored rest position of the hit
// point (splat centre + splat_coords along the authored axes), moved from its cloud's space into the
// lattice entity's space through both Transforms. For a
// cloud with several deformers this is exact for the first lattice only (later lattices see the output of
// earlier ones, which picking does not keep). A Gaussian hit gives its authored centre. nullopt when the
// hit is not a surface or a Gaussian, or the entity is gone.
std::optional<glm::dvec3> surface_hit_in_lattice_space(const ecs::Registry& registry, ecs::Entity lattice,
                                                       const PickHit& hit);

}  // namespace sffd::picking
