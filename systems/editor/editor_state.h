// EditorState: the editor's singleton resource (set by `splatffd view` and by tests). Plain data plus
// the undo stack. The window (or the replayer) appends this frame's InputEvents to `events`; the
// editor's input system (editor_system.h) consumes them in the input phase and turns them into camera
// moves, selections and lattice edits (recorded on `undo`). Requests the input system cannot carry out
// itself (save, screenshot, quit: they need the scene path, the GL context or the window) are flags the
// view loop handles after the frame.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"
#include "systems/animation/components.h"
#include "systems/editor/camera_controller.h"
#include "systems/editor/gizmo.h"
#include "systems/editor/input_record.h"
#include "systems/editor/lattice_tools.h"
#include "systems/editor/point_mode.h"
#include "systems/editor/proportional.h"
#include "systems/editor/undo_stack.h"
#include "systems/ffd/components.h"
#include "systems/picking/screen_view.h"
#include "systems/picking/selection.h"

namespace sffd::editor {

enum class Tool : std::uint8_t { select, move, twist, brush, scale };
const char* tool_name(Tool tool);

enum class PivotMode : std::uint8_t { centroid, picked_point };

// A gesture that needs picking: the input phase posts the pick (picking::post_pick) and this action; the
// picking phase answers it; editor_pick_system, right after picking, applies the action to the answer.
// A box select needs no ray: it is applied in the same step, with picking's visibility test.
struct PendingPick {
    // point_*: point mode's gestures (point_tools.cpp). point_click, point_colour and point_sphere wait for a
    // pick (the cloud in front, the eyedropper's point, the sphere's centre); point_region (box, lasso,
    // polygon) and point_brush (a dab) need none: they run after this frame's deformation, as box_select.
    enum class Action : std::uint8_t {
        click_select,
        brush,
        pivot,
        box_select,
        point_click,
        point_colour,
        point_sphere,
        point_region,
        point_brush
    };
    Action action = Action::click_select;
    std::uint64_t id = 0;                                     // picking::PickRequest::id (not box_select)
    std::uint8_t modifiers = 0;                               // click_select, box_select: the modifiers
    picking::SelectMode mode = picking::SelectMode::replace;  // brush: how the dab changes the selection
    // box_select: the rectangle's corners (pixels), the view it was drawn in, and whether only the control
    // points visible from the eye count (not in x-ray).
    glm::dvec2 from{0.0}, to{0.0};
    picking::ScreenView view{};
    bool visible_only = true;
    // Point gestures: the region (point_region, point_brush), the mode, the cursor (point_click: `from`).
    point_select::ScreenRegion region{};
    PointMode point_mode = PointMode::set;
};

// A stretch or twist as the user last applied it (in lattice space), so "set key" can key it.
struct LastEdit {
    enum class Kind : std::uint8_t { none, stretch, twist } kind = Kind::none;
    ecs::Entity lattice = ecs::null_entity;
    std::vector<std::uint32_t> points;
    glm::dvec3 displacement{0.0};
    double angle = 0.0;  // radians
    glm::dvec3 axis{0.0, 0.0, 1.0};
    glm::dvec3 pivot{0.0};
    // Why the last edit cannot be keyed (a scale; a proportional edit that moved neighbours by their
    // falloff: a track keys one stretch or twist of one point set); empty when it can.
    std::string not_keyable;
};

// What a held mouse button is doing.
struct Drag {
    enum class Kind : std::uint8_t {
        none,
        pending_click,
        box,
        orbit,
        pan,
        move,
        twist,
        brush,
        scale,
        // Point mode (point_tools.cpp): a press not yet a drag (click, or a box once it moves), a box, a
        // lasso path, a brush stroke, a sphere's radius.
        point_click,
        point_box,
        point_lasso,
        point_brush,
        point_sphere
    } kind = Kind::none;
    MouseButton button = MouseButton::left;
    std::uint8_t modifiers = 0;
    glm::dvec2 start{0.0};  // cursor at press
    glm::dvec2 last{0.0};   // cursor at the previous event
    Camera camera;          // the camera when the tool drag began (tools drag in its view)
    ecs::Entity lattice = ecs::null_entity;
    std::vector<glm::dvec3> start_points;  // the pose shown at press (tools apply from it: no drift)
    std::optional<Lattice> before;         // undo snapshot
    // The lattice plays a clip (animated_lattice()): the animation owns Lattice::current, so the drag
    // writes its pose as the clip's UnkeyedEdit at the clip time instead; the edit's state at press.
    bool animated = false;
    double clip_time = 0.0;
    std::optional<UnkeyedEdit> before_unkeyed;
    std::vector<std::uint32_t> points;  // edited control points
    glm::dvec3 pivot_world{0.0};
    glm::dvec3 axis_world{0.0, 0.0, 1.0};
    double angle = 0.0;  // accumulated twist (unbounded)
    glm::dvec3 displacement_world{0.0};
    glm::dmat3 scale_world{1.0};  // scale: the linear map about the pivot, world axes
    // Proportional editing (proportional.h): the settings of this drag (the wheel and PageUp/PageDown
    // change its radius), each control point's world distance to the nearest edited point at press, and
    // the pinned points no falloff moves (empty: none).
    ProportionalSettings proportional;
    std::vector<double> distance;
    std::vector<std::uint8_t> excluded;
};

// Typed values after g / r (Blender habit: `g z 0.2 Enter`, `r x 45 Enter`). Pressing g/w/r starts an
// entry; while it is active the number keys (0-9, minus, period, comma, space) go to `text` (space does
// not play/pause), backspace edits, x/y/z set the axis as always, Enter applies (move: one value along
// the x/y/z axis or three values dx dy dz; twist: degrees), Escape cancels. Any other key or a mouse
// press ends the entry unapplied and then does what it always does (ctrl+q still quits).
struct TypedEntry {
    bool active = false;
    Tool tool = Tool::move;
    std::string text;
    bool axis_typed = false;  // an axis key was pressed in this entry
};

struct EditorState {
    // --- edit mode (ctrl+tab): the lattice's control points, or the points of the clouds (point_mode.h) ---
    EditMode mode = EditMode::lattice;
    PointEditing points;

    // --- tool settings (panels and shortcuts change them) ---
    Tool tool = Tool::select;
    AxisMode move_axis = AxisMode::view_plane;
    AxisMode twist_axis = AxisMode::view;
    glm::dvec3 custom_axis{0.0, 0.0, 1.0};
    PivotMode pivot_mode = PivotMode::centroid;
    glm::dvec3 picked_pivot{0.0};  // world; set by alt+click on the surface
    bool has_picked_pivot = false;
    ToolScope scope = ToolScope::local;
    bool pin_outer_layer = true;
    bool xray = false;
    bool show_lattice = true;
    bool show_weights = false;  // the renderer's weight colours (RenderSettings::show_weights; View menu)
    bool lattice_cage_only = false;
    ProportionalSettings proportional;  // `o` toggles, shift+o cycles the falloff (proportional.h)
    // Preview while moving: while the camera or the lattice moves (orbit/pan/wheel, tool drags, brush,
    // playback) the renderer draws in preview quality; after `refine_after` still frames it refines to
    // the quality the view started with (RenderSettings::quality; `--quality preview` stays preview).
    bool preview_while_moving = true;
    int refine_after = 8;
    // Those preview frames at half the window's resolution (RenderSettings::preview_divider 2): a quarter of
    // the fill. The view turns it on where the GL is a CPU rasteriser, whose frame time is mostly fill;
    // View > "Half-resolution preview" toggles it.
    bool half_resolution_preview = false;
    // While those frames preview, the lattice overlay's faint pass (the part behind the surface) shows
    // the hidden control points but not the hidden cell edges: on a CPU rasteriser those edges are
    // nearly half of the overlay's cost (overlay_draws()). Set with half_resolution_preview; View >
    // "Light overlay while moving" toggles it.
    bool light_overlay_while_moving = false;
    int still_frames = 1 << 20;  // frames since the last movement
    int rest_quality = -1;       // render::Quality the view started with (-1: not read yet)
    bool previewing = false;     // this frame renders in preview because of movement (status bar)
    Camera last_camera;  // camera at the end of the previous frame (movement by any means)  // shift+t: the
                         // overlay draws only the box's 12 edges (+ selected points)
    // Auto-key (n toggles; status bar and Timeline show it): every stretch/twist is also keyed at the clip
    // time. Off: a stretch/twist of a lattice with a clip is "un-keyed" until k keys it; playing would
    // replace it with the clip's pose, so the first play only warns and the second plays.
    bool auto_key = false;
    ecs::Entity unkeyed = ecs::null_entity;  // lattice with a stretch/twist since its last key
    bool play_warned = false;
    double click_tolerance_px = 8.0;

    // --- what is being edited ---
    ecs::Entity camera = ecs::null_entity;           // entity with the Camera the view uses
    ecs::Entity active_lattice = ecs::null_entity;   // lattice the tools work on
    ecs::Entity selected_entity = ecs::null_entity;  // outliner / inspector selection
    Viewport viewport;

    UndoStack undo;

    // --- input of this frame (filled by the window or the replayer, consumed by the input system) ---
    std::vector<InputEvent> events;
    std::optional<InputReplayer> replay;  // --replay: events for each frame come from the recording
    bool record = false;                  // --record: keep every consumed event (frame-stamped) in `recorded`
    std::vector<InputEvent> recorded;
    glm::dvec2 cursor{0.0};
    Drag drag;
    // Picks posted this frame, applied after the picking phase (editor_pick_system), and the events that
    // came after a pick-dependent one: handled in the next frame's input phase, after the pick was
    // applied, so every event sees what the events before it did.
    std::vector<PendingPick> pending_picks;
    std::vector<InputEvent> deferred;
    LastEdit last_edit;
    TypedEntry typed;

    // --- requests for the view loop ---
    bool request_save = false;
    bool request_screenshot = false;
    bool request_quit = false;
    bool request_frame_selection = false;
    bool request_open_dialog = false;  // ctrl+o: the panels open File > Open scene
    std::string save_as;               // non-empty: save there (File > Save as); it becomes the ctrl+s path

    // --- files (file_browser.h) ---
    std::string last_folder;    // where the dialogs open and saves/screenshots go by default ("" = current)
    std::string settings_file;  // editor.ini that remembers last_folder ("" = nothing remembered: tests)

    std::string status;  // last message for the status bar (also logged)
};

}  // namespace sffd::editor
