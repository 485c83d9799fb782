#include "systems/editor/point_settings.h"

#include <algorithm>

#include "systems/editor/input_record.h"

namespace sffd::editor {

const char* edit_mode_name(EditMode mode) { return mode == EditMode::points ? "points" : "lattice"; }

const char* point_tool_name(PointTool tool) {
    switch (tool) {
        case PointTool::select: return "select";
        case PointTool::lasso: return "lasso";
        case PointTool::polygon: return "polygon";
        case PointTool::brush: return "brush";
        case PointTool::sphere: return "sphere";
        case PointTool::colour: return "colour";
    }
    return "?";
}

const char* point_mode_name(PointMode mode) {
    switch (mode) {
        case PointMode::set: return "set";
        case PointMode::add: return "add";
        case PointMode::remove: return "remove";
        case PointMode::intersect: return "intersect";
    }
    return "?";
}

std::optional<PointMode> point_mode_from_name(std::string_view name) {
    for (PointMode m : {PointMode::set, PointMode::add, PointMode::remove, PointMode::intersect})
        if (name == point_mode_name(m)) return m;
    return std::nullopt;
}

PointMode point_mode_for(std::uint8_t modifiers, PointMode plain) {
    const bool shift = modifiers & mods::shift, ctrl = modifiers & mods::ctrl;
    if (shift && ctrl) return PointMode::intersect;
    if (ctrl) return PointMode::remove;
    if (shift) return PointMode::add;
    return plain;
}

namespace {

constexpr std::string_view fields[] = {
    "point.mode",          "point.brush_radius", "point.sphere_radius", "point.colour_tolerance",
    "point.grow_distance", "weight.radius",      "weight.falloff",      "view.lattice",
    "view.weights"};

double positive(double v) { return std::clamp(v, 1e-6, 1e6); }

}  // namespace

bool is_point_field(std::string_view field) {
    return std::find(std::begin(fields), std::end(fields), field) != std::end(fields);
}

std::optional<double> parse_point_field_value(std::string_view field, std::string_view word) {
    if (field == "point.mode") {
        if (const auto m = point_mode_from_name(word)) return double(int(*m));
        return std::nullopt;
    }
    if (field == "weight.falloff") {
        if (const auto f = falloff_from_name(word)) return double(int(*f));
        return std::nullopt;
    }
    return std::nullopt;  // a number: the parser reads it
}

std::string_view point_field_word(std::string_view field, double value) {
    if (field == "point.mode") return point_mode_name(PointMode(std::clamp(int(value), 0, 3)));
    if (field == "weight.falloff") return falloff_name(Falloff(std::clamp(int(value), 0, falloff_count - 1)));
    return {};
}

void set_point_field(PointToolSettings& s, std::string_view field, double value) {
    if (field == "point.mode") s.mode = PointMode(std::clamp(int(value), 0, 3));
    else if (field == "point.brush_radius") s.brush_radius_px = positive(value);
    else if (field == "point.sphere_radius") s.sphere_radius = positive(value);
    else if (field == "point.colour_tolerance") s.colour_tolerance = std::clamp(value, 0.0, 2.0);
    else if (field == "point.grow_distance") s.grow_distance = positive(value);
    else if (field == "weight.radius") s.weight_radius = positive(value);
    else if (field == "weight.falloff")
        s.weight_falloff = Falloff(std::clamp(int(value), 0, falloff_count - 1));
}

}  // namespace sffd::editor
