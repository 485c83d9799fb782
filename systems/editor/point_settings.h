// Point editing's view state (systems/editor/README.md, "Point mode"): which edit mode the editor is in,
// the point tool and its settings, and the replay `set` fields that change them. Plain data, no registry:
// the parser of recordings (input_record.cpp) checks the fields through is_point_field().
//
// The edit mode: `ctrl+tab` switches between lattice editing (the control points: today's tools) and
// point editing (the splats and Gaussians themselves: selection through systems/point_select, hide,
// delete, duplicate, separate through systems/point_edit, weights). Blender toggles its edit mode with
// Tab, which this editor gives to the active lattice's cycling, so the toggle has ctrl.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "systems/editor/proportional.h"

namespace sffd::editor {

enum class EditMode : std::uint8_t { lattice, points };
const char* edit_mode_name(EditMode mode);  // "lattice", "points"

// The point tools: select (click, or drag a box), lasso (freehand drag), polygon (clicks, Enter closes),
// brush (a screen circle per dab), sphere (3D: a centre on the surface, a world radius), colour (the
// eyedropper: the clicked point's colour, within a tolerance).
enum class PointTool : std::uint8_t { select, lasso, polygon, brush, sphere, colour };
inline constexpr int point_tool_count = 6;
const char* point_tool_name(PointTool tool);

// How a gesture combines with the selection when no modifier says otherwise (shift add, ctrl remove,
// ctrl+shift intersect); the same order as point_select::Mode.
enum class PointMode : std::uint8_t { set, add, remove, intersect };
const char* point_mode_name(PointMode mode);
std::optional<PointMode> point_mode_from_name(std::string_view name);
// The gesture's mode from its modifiers (mods bits of input_record.h) and the default.
PointMode point_mode_for(std::uint8_t modifiers, PointMode plain);

struct PointToolSettings {
    PointTool tool = PointTool::select;
    PointMode mode = PointMode::set;
    double brush_radius_px = 24.0;   // brush: screen radius of a dab
    double sphere_radius = 0.25;     // sphere: world radius of a click without a drag
    double colour_tolerance = 0.08;  // colour: RGB distance in [0, 1] (sRGB, as stored)
    double grow_distance = 0.05;     // grow / shrink: world distance
    // Weights from the selection (point_weights.h): 1 on the selected points, falling off to 0 at
    // `weight_radius` (world) from the nearest of them by `weight_falloff` (proportional.h's curves).
    double weight_radius = 0.25;
    Falloff weight_falloff = Falloff::smooth;
};

// Replay `set` fields: point.mode (set|add|remove|intersect), point.brush_radius (pixels),
// point.sphere_radius, point.colour_tolerance, point.grow_distance, weight.radius (world units),
// weight.falloff (smooth|sphere|linear|sharp|constant), view.lattice (0/1: the lattice overlay),
// view.weights (0/1: the renderer's weight colours).
// The enum fields carry their index in the event's value; parse_point_field_value() reads the file's word.
bool is_point_field(std::string_view field);
std::optional<double> parse_point_field_value(std::string_view field, std::string_view word);
// The file's word for an event's value (format_input_recording).
std::string_view point_field_word(std::string_view field, double value);
// Applies a field to the settings (view.lattice and view.weights are the caller's: no point settings). Radii
// and distances are clamped to (0, 1e6], the tolerance to [0, 2].
void set_point_field(PointToolSettings& settings, std::string_view field, double value);

}  // namespace sffd::editor
