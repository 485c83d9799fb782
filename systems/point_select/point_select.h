// Point selection for surface splats (SplatCloud) and 3D Gaussians (GaussianCloud): the tools the editor
// offers (click, rectangle, lasso, polygon, brush, sphere, by colour), the modes that combine a tool's
// candidates with the current selection, and the commands (all, none, invert, grow, shrink). Pure
// functions over the registry; no UI, no GL of its own.
//
// The selection is the kPointSelected bit of the cloud's PointFlags (runtime/scene/point_columns.h), by
// point index, so it survives deformation and animation. Hidden and deleted points (point_gone()) are
// never selected: no tool nominates them, and the operations that rewrite the selection through a mode
// or a command (commit, all, none, invert) also clear a bit a gone point still carries.
//
// What the user sees is what is selected: positions are those picking sees (systems/picking's
// splat_source / gaussian_source: the deformed CPU output when current, a GPU-only output read back, a
// CPU deformation when neither is readable, else the authored cloud), placed in the world by the cloud's
// model matrix model_matrix(Transform, origin) (runtime/scene/camera.h, the one the renderer and picking
// use), projected through the ScreenView's camera (picking's screen convention: pixels, y down).
//
// Every operation that writes returns what it changed as a SelectionDelta: the changed points by page
// (point_pages.h), at most 2 bytes a changed point plus a constant a page. The bits are toggled, so the
// same delta applied again undoes it (apply_delta is its own inverse):
//
//   point_select::PointSelectState state;                       // caches; one per editor
//   SelectionDelta d = select_region(registry, state, cloud, view, rect_region(a, b), {.mode = Mode::add});
//   undo.push(d);  ...  apply_delta(registry, cloud, undo.top());  // undo (and again: redo)
//
// Visible only: a screen tool's candidates are the points on the visible surface, decided by a CPU depth
// buffer built from the same shown positions (not Embree), over the tool's screen box only: every
// non-gone point writes its footprint (a splat's disc, or a flat Gaussian's disc across its shortest
// axis, as a plane in 3D: the depth where each pixel's ray meets it; a round Gaussian: a screen disc of
// its projected radius at its centre's depth; clipped to kMaxFootprintPx), and a point is visible when
// its depth is within `depth_tolerance` footprint radii of the buffer at its centre pixel. Why not Embree:
// picking's scene is rebuilt after every deformation (0.7 s for 1M Gaussians) and answers one ray at a
// time, where a box asks about up to every point; the buffer costs one pass over the points the box can
// see. X-ray (visible_only = false): every point in the region. Screen tools take only points in front
// of the eye whose centre lies inside the viewport.
//
// Footprint radius r of a point (world units, through the Transform's largest scale): surface splats the
// longer splat axis (the disc picking trims to the ellipse); Gaussians kFootprintSigmas standard
// deviations of their largest axis (deformed scales; picking's own deformation: scaled by the
// Jacobian's largest column).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/picking/screen_view.h"

namespace sffd::point_select {

inline constexpr double kFootprintSigmas = 2.0;  // a Gaussian's footprint radius, in standard deviations
inline constexpr double kMaxFootprintPx = 8.0;   // cap of a footprint disc written into the depth buffer

// ---- Selection deltas ---------------------------------------------------------------------------------

// The points one operation changed, for undo: per changed page (ascending), the changed offsets within
// the page as sorted uint16 (2 bytes a point), or, when that would be larger (more than 4,096 changed
// points), a 65,536-bit mask (8 KiB). bytes() <= 2 * changed() + kPageOverhead * pages.size() + sizeof.
struct SelectionDelta {
    struct Page {
        std::uint32_t page = 0;
        std::uint32_t count = 0;             // changed points in this page
        std::vector<std::uint16_t> offsets;  // sorted, unique (empty when `mask` is used)
        std::vector<std::uint64_t> mask;     // 1,024 words, bit o = offset o changed (or empty)
    };
    static constexpr std::size_t kPageOverhead = sizeof(Page);
    static constexpr std::size_t kMaskWords = 1024;

    std::size_t points = 0;   // the size of the cloud it was made for (apply refuses another size)
    std::vector<Page> pages;  // ascending page number, each with count > 0

    bool empty() const { return pages.empty(); }
    std::size_t changed() const;                 // points toggled
    std::size_t bytes() const;                   // heap and inline bytes held (the memory bound above)
    std::vector<std::uint32_t> indices() const;  // the changed points, ascending
};

// The delta that turns `before` into `after` in the kPointSelected bit (other bits ignored). Equal sizes.
SelectionDelta delta_between(std::span<const std::uint8_t> before, std::span<const std::uint8_t> after);
// The delta toggling exactly `indices` (sorted, unique, < points).
SelectionDelta delta_from_indices(std::span<const std::uint32_t> indices, std::size_t points);
// Toggles kPointSelected of every point in `delta` in `bits` (bits.size() == delta.points); its own inverse.
void toggle(std::span<std::uint8_t> bits, const SelectionDelta& delta);
// One delta with the effect of `first` then `then` (per point: XOR).
SelectionDelta compose(const SelectionDelta& first, const SelectionDelta& then);

// Toggles the delta's points in e's PointFlags (created, all clear, when absent) and marks the changed
// pages (mark_points_changed, the selection column). Returns false, changing nothing, when e has no
// cloud or its size is not delta.points. Apply the same delta again to undo.
bool apply_delta(ecs::Registry& registry, ecs::Entity e, const SelectionDelta& delta);

// ---- Modes --------------------------------------------------------------------------------------------

// How a tool's candidates C combine with the current selection S (gone points: never selected):
//   set: C; add: S ∪ C; remove: S \ C; intersect: S ∩ C.
enum class Mode : std::uint8_t { set, add, remove, intersect };
// Modifiers as the lattice selection reads them: plain set, shift add, ctrl remove (ctrl wins over
// shift). Intersect has no modifier of its own here (the editor offers it as a button or a key).
Mode select_mode(bool shift, bool ctrl);

// The delta that makes e's selection the result of `mode` with `candidates` (sorted, unique indices),
// applied to e (apply_delta). Candidates that are gone are ignored.
SelectionDelta commit(ecs::Registry& registry, ecs::Entity e, std::span<const std::uint32_t> candidates,
                      Mode mode);

// ---- Reading ------------------------------------------------------------------------------------------

std::size_t point_count(const ecs::Registry& registry, ecs::Entity e);  // 0 without a cloud
std::vector<std::uint32_t> selected_points(const ecs::Registry& registry, ecs::Entity e);
std::size_t selected_count(const ecs::Registry& registry, ecs::Entity e);

// ---- State --------------------------------------------------------------------------------------------

// What the tools cache between calls, per cloud: picking's source cache (read-backs and CPU
// deformations, systems/picking/pick_cache.h) and the bounds and footprint radii of blocks of 2,048
// points in the cloud's frame (for culling: a block whose projected box misses the tool's screen box is
// skipped), keyed by the shown data's version. Move-only; one per editor (or test).
class PointSelectState {
public:
    PointSelectState();
    ~PointSelectState();
    PointSelectState(PointSelectState&&) noexcept;
    PointSelectState& operator=(PointSelectState&&) noexcept;
    PointSelectState(const PointSelectState&) = delete;
    PointSelectState& operator=(const PointSelectState&) = delete;

    struct Stats {
        std::uint64_t block_rebuilds = 0;  // clouds whose block bounds were recomputed
        std::uint64_t blocks_tested = 0;   // blocks whose points were projected (last screen query)
        std::uint64_t blocks_culled = 0;   // blocks skipped by their projected bounds (last screen query)
    };
    const Stats& stats() const;

    struct Impl;
    Impl& impl();

private:
    std::unique_ptr<Impl> m_impl;
};

// ---- Screen tools -------------------------------------------------------------------------------------

// A screen region in pixels (picking's convention: y down, continuous, borders included).
//   rect: the box with corners a and b (any order: a drag from any direction);
//   circle: centre and radius (the brush; apply one per stamp of a stroke);
//   polygon: a closed polygon (last vertex joins the first), even-odd rule: the lasso's freehand path
//            and the polygon tool's clicked vertices alike. Fewer than 3 vertices: empty.
struct ScreenRegion {
    enum class Shape : std::uint8_t { rect, circle, polygon };
    Shape shape = Shape::rect;
    glm::dvec2 a{0.0}, b{0.0};
    glm::dvec2 centre{0.0};
    double radius = 0.0;
    std::vector<glm::dvec2> vertices;
};
ScreenRegion rect_region(glm::dvec2 a, glm::dvec2 b);
ScreenRegion circle_region(glm::dvec2 centre, double radius);
ScreenRegion polygon_region(std::vector<glm::dvec2> vertices);
// Whether a screen point lies in the region (the exact test every tool uses for centres).
bool region_contains(const ScreenRegion& region, glm::dvec2 point);

// Which part of a point must meet the region:
//   centre: its projected centre lies in the region;
//   whole:  its projected footprint disc (radius r projected at its depth, at least half a pixel) lies
//           entirely inside the region (SuperSplat's "whole splat" toggle; a polygon: centre inside and
//           the disc crosses no edge).
enum class Footprint : std::uint8_t { centre, whole };

struct ScreenOptions {
    Mode mode = Mode::set;
    bool visible_only = true;  // false: x-ray, every point in the region
    Footprint footprint = Footprint::centre;
    double depth_tolerance = 1.0;  // visible when depth <= buffer + depth_tolerance * r (+1e-6 relative)
};

// The points of cloud e (SplatCloud or GaussianCloud) in front of the camera that meet the region, per
// the options (mode ignored); sorted. Gone points are never returned.
std::vector<std::uint32_t> points_in_region(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                            const picking::ScreenView& view, const ScreenRegion& region,
                                            const ScreenOptions& options);
// points_in_region, then commit with options.mode.
SelectionDelta select_region(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                             const picking::ScreenView& view, const ScreenRegion& region,
                             const ScreenOptions& options);

// ---- Click --------------------------------------------------------------------------------------------

struct ClickOptions {
    bool visible_only = true;   // false: x-ray
    double tolerance_px = 6.0;  // picking's screen tolerance, used when no footprint covers the cursor
};

// The point under the cursor, picking's surface rule on the shown points: among the points whose
// projected footprint disc covers the cursor, the nearest to the eye (x-ray: the one whose centre is
// nearest the cursor); when none covers it, the visible (x-ray: any) point whose centre is nearest the
// cursor within tolerance_px. Gone points are skipped. nullopt: nothing there.
std::optional<std::uint32_t> point_under_cursor(ecs::Registry& registry, PointSelectState& state,
                                                ecs::Entity e, const picking::ScreenView& view,
                                                glm::dvec2 cursor, const ClickOptions& options = {});
// The click: commit {point_under_cursor} with `mode` (set with nothing under the cursor clears, as a
// click into empty space does for control points).
SelectionDelta select_click(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                            const picking::ScreenView& view, glm::dvec2 cursor, Mode mode,
                            const ClickOptions& options = {});

// ---- World tools --------------------------------------------------------------------------------------

// The points whose shown world position lies within `radius` of `centre` (inclusive); sorted, no gone.
std::vector<std::uint32_t> points_in_sphere(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                            const glm::dvec3& centre, double radius);
SelectionDelta select_sphere(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                             const glm::dvec3& centre, double radius, Mode mode);

// ---- By colour ----------------------------------------------------------------------------------------

// A point's colour as RGB in [0, 1] (sRGB-encoded, as stored): surface splats their `colors`, else the
// texture's nearest texel at its uv, else the material's base colour (SplatMaterial, encoded to sRGB);
// Gaussians their SH DC colour clamp(0.5 + C0 * dc, 0, 1) (unchanged by a deformation). nullopt when e
// has no cloud or the index is out of range.
std::optional<glm::vec3> point_colour(const ecs::Registry& registry, ecs::Entity e, std::uint32_t index);
// The points whose colour lies within `tolerance` (Euclidean RGB distance, [0, 1] units) of `colour`;
// every point of the cloud (not only those on screen); sorted, no gone.
std::vector<std::uint32_t> points_by_colour(const ecs::Registry& registry, ecs::Entity e, glm::vec3 colour,
                                            double tolerance);
SelectionDelta select_by_colour(ecs::Registry& registry, ecs::Entity e, glm::vec3 colour, double tolerance,
                                Mode mode);

// ---- Commands -----------------------------------------------------------------------------------------

SelectionDelta select_all(ecs::Registry& registry, ecs::Entity e);  // every point not gone
SelectionDelta select_none(ecs::Registry& registry, ecs::Entity e);
SelectionDelta invert_selection(ecs::Registry& registry, ecs::Entity e);  // gone points stay unselected
// Adds every unselected point (not gone) within `distance` (world, shown positions, inclusive) of a
// selected one; one step (not repeated until nothing changes). A uniform grid of cell `distance` over
// the selected points answers the neighbour queries.
SelectionDelta grow_selection(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                              double distance);
// Removes every selected point within `distance` of an unselected point that is not gone (gone points
// are not part of the surface the user sees, so they do not erode the selection).
SelectionDelta shrink_selection(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                double distance);

}  // namespace sffd::point_select
