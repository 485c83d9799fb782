// Lattice overlay (phase `rendering`, after the splat render system): draws every lattice's cell edges
// and control points into the render system's output framebuffer, so the window and screenshots show
// it. Selected points are orange and larger; pinned outer-layer points (local edits) blue-grey; points
// inside the object's bounding box white; the rest cyan. Without x-ray, hidden parts are drawn faintly
// and visible parts (depth-tested against the splats) fully; with x-ray everything is drawn fully. While
// the view previews (moving) with EditorState::light_overlay_while_moving, the faint pass shows the hidden
// control points only, not the hidden cell edges (overlay_draws()).
//   reads   Lattice, Transform, picking::LatticeSelection, EditorState (resource), Camera, SplatCloud
//           (bounds), render output framebuffer (systems/splat_render)
//   writes  the colour attachment of that framebuffer; LatticeOverlayState (resource: program, buffers,
//           the cache of the untested edges that did not move: OverlayOptions, OverlayCacheStats)
// Needs a current GL 4.5 context; does nothing without EditorState or before the first rendered frame.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/app/frame_loop.h"
#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "systems/editor/editor_state.h"

namespace sffd::editor {

// CPU part (testable without GL): one vertex per control point / line end.
struct OverlayVertex {
    glm::vec3 position;  // relative to the anchor
    glm::vec4 color;
    float size;
};
struct OverlayGeometry {
    glm::dvec3 anchor{0.0};
    std::vector<OverlayVertex> points;
    std::vector<OverlayVertex> lines;  // pairs
};
// Colours of the overlay, exposed for tests.
inline constexpr glm::vec4 overlay_selected{1.0f, 0.45f, 0.02f, 1.0f};
inline constexpr glm::vec4 overlay_pinned{0.35f, 0.42f, 0.62f, 1.0f};
inline constexpr glm::vec4 overlay_inside{0.95f, 0.95f, 0.95f, 1.0f};
inline constexpr glm::vec4 overlay_outside{0.25f, 0.8f, 0.9f, 1.0f};
inline constexpr glm::vec4 overlay_proportional{1.0f, 1.0f, 1.0f, 1.0f};  // the proportional radius

// The proportional radius's circle: `segments` points on the circle of `radius` about `centre` in the
// plane facing the camera (the lattice overlay draws it, as lines, while a proportional drag runs).
std::vector<glm::dvec3> proportional_circle(const Camera& camera, const glm::dvec3& centre, double radius,
                                            int segments = 64);

OverlayGeometry build_lattice_overlay(const ecs::Registry& registry, const EditorState& state,
                                      ecs::Entity lattice);

// One draw of a lattice's overlay, in order: its cell edges or its control points, depth-tested against
// the splats or not, at `strength` times their opacity.
struct OverlayDraw {
    bool lines = false;
    bool depth_test = false;
    float strength = 1.0f;
};
// This frame's draws: x-ray, everything at full strength untested; otherwise a faint untested pass (the
// part behind the surface shows through), then the visible part at full strength. On a CPU rasteriser
// every edge pixel costs about the same whether it is drawn or depth-rejected, so the faint pass's
// edges are nearly half of the overlay (2-core machine, sphere drag frame, x-ray off: the overlay took
// 8.0-8.5 ms with them, 4.3-4.9 ms without). While the view previews with light_overlay_while_moving,
// the faint pass draws the control points only.
std::vector<OverlayDraw> overlay_draws(const EditorState& state);

// Registry resource (optional): the line cache of x-ray edges (lattice_overlay.cpp, OverlayLineCache) is
// used unless line_cache is false (`splatffd view --no-overlay-cache`, for comparisons).
struct OverlayOptions {
    bool line_cache = true;
};
// Frames whose untested edges of a single lattice went through the cache: rebuilt (the cache drawn
// again, then used), reused as it was, or drawn directly (the view or the edges' layout changed).
struct OverlayCacheStats {
    std::uint64_t rebuilt = 0, reused = 0, direct = 0;
    std::uint64_t cached_edges = 0, live_edges = 0;  // summed over the frames that used the cache
};
OverlayCacheStats overlay_cache_stats(const ecs::Registry& registry);

Status init_lattice_overlay(ecs::Registry& registry);
void lattice_overlay_system(ecs::Registry& registry, const FrameContext& frame);
void release_lattice_overlay(ecs::Registry& registry);

}  // namespace sffd::editor
