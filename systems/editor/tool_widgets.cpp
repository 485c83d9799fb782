#include "systems/editor/tool_widgets.h"

#include <imgui.h>

#include "runtime/core/log.h"
#include "runtime/scene/camera.h"
#include "systems/editor/pending_edits.h"
#include "systems/editor/point_mode.h"
#include "systems/editor/point_weights.h"

namespace sffd::editor {

void proportional_widgets(EditorState& state) {
    ProportionalSettings& p = state.proportional;
    ImGui::Checkbox("proportional (O)", &p.enabled);
    int falloff = int(p.falloff);
    if (ImGui::Combo("falloff (shift+O)", &falloff, "smooth\0sphere\0linear\0sharp\0constant\0"))
        p.falloff = Falloff(falloff);
    double radius = p.radius;
    if (ImGui::InputDouble("radius (wheel)", &radius, 0.05, 0.5, "%.4f"))
        p.radius = clamp_proportional_radius(radius);
}

void edit_mode_widgets(ecs::Registry& registry, EditorState& state) {
    int mode = int(state.mode);
    ImGui::TextUnformatted("edit (ctrl+tab):");
    ImGui::SameLine();
    bool changed = ImGui::RadioButton("lattice", &mode, int(EditMode::lattice));
    ImGui::SameLine();
    changed |= ImGui::RadioButton("points", &mode, int(EditMode::points));
    if (changed && mode != int(state.mode))
        post_edit(registry, "edit mode",
                  [mode](ecs::Registry& r, EditorState& s) { set_edit_mode(r, s, EditMode(mode)); });
    ImGui::Separator();
}

namespace {

template <class Fn>
void button(ecs::Registry& registry, const char* label, Fn fn, bool same_line = true) {
    if (same_line) ImGui::SameLine();
    if (ImGui::Button(label)) post_edit(registry, label, fn);
}

}  // namespace

void point_tools_widgets(ecs::Registry& registry, EditorState& state) {
    PointToolSettings& s = state.points.settings;
    int tool = int(s.tool);
    static const char* const labels[point_tool_count] = {
        "select (Q)", "lasso (L)", "polygon (shift+L)", "brush (B)", "sphere (shift+B)", "colour (E)"};
    for (int t = 0; t < point_tool_count; ++t) {
        if (t % 2) ImGui::SameLine();
        ImGui::RadioButton(labels[t], &tool, t);
    }
    if (tool != int(s.tool)) s.tool = PointTool(tool), state.points.path.clear();
    int mode = int(s.mode);
    if (ImGui::Combo("mode", &mode, "set\0add\0remove\0intersect\0")) s.mode = PointMode(mode);
    ImGui::Checkbox("x-ray (T): not only the visible", &state.xray);
    ImGui::InputDouble("brush px", &s.brush_radius_px, 1.0, 8.0, "%.0f");
    ImGui::InputDouble("sphere r", &s.sphere_radius, 0.01, 0.1, "%.3f");
    ImGui::InputDouble("colour tol", &s.colour_tolerance, 0.01, 0.05, "%.3f");
    ImGui::InputDouble("grow by", &s.grow_distance, 0.005, 0.05, "%.3f");
    s.brush_radius_px = std::clamp(s.brush_radius_px, 1.0, 4096.0);
    s.sphere_radius = std::clamp(s.sphere_radius, 1e-6, 1e6);
    s.colour_tolerance = std::clamp(s.colour_tolerance, 0.0, 2.0);
    s.grow_distance = std::clamp(s.grow_distance, 1e-6, 1e6);
    const double grow = s.grow_distance;
    button(
        registry, "all (A)", [](ecs::Registry& r, EditorState& e) { points_select_all(r, e); }, false);
    button(registry, "none (alt+A)", [](ecs::Registry& r, EditorState& e) { points_select_none(r, e); });
    button(registry, "invert (ctrl+I)", [](ecs::Registry& r, EditorState& e) { points_invert(r, e); });
    button(
        registry, "grow (ctrl+=)", [grow](ecs::Registry& r, EditorState& e) { points_grow(r, e, grow); },
        false);
    button(registry, "shrink (ctrl+-)",
           [grow](ecs::Registry& r, EditorState& e) { points_shrink(r, e, grow); });
    button(
        registry, "hide (H)", [](ecs::Registry& r, EditorState& e) { points_hide(r, e); }, false);
    button(registry, "unhide (alt+H)", [](ecs::Registry& r, EditorState& e) { points_unhide(r, e); });
    button(registry, "delete (X)", [](ecs::Registry& r, EditorState& e) { points_delete(r, e); });
    button(
        registry, "duplicate (shift+D)", [](ecs::Registry& r, EditorState& e) { points_duplicate(r, e); },
        false);
    button(registry, "separate (P)", [](ecs::Registry& r, EditorState& e) { points_separate(r, e); });
    ImGui::Separator();
    ImGui::InputDouble("weight r", &s.weight_radius, 0.01, 0.1, "%.3f");
    s.weight_radius = std::clamp(s.weight_radius, 1e-6, 1e6);
    int falloff = int(s.weight_falloff);
    if (ImGui::Combo("curve", &falloff, "smooth\0sphere\0linear\0sharp\0constant\0"))
        s.weight_falloff = Falloff(falloff);
    const double radius = s.weight_radius;
    const Falloff curve = s.weight_falloff;
    button(
        registry, "weights from selection (shift+W)",
        [radius, curve](ecs::Registry& r, EditorState& e) { weights_from_selection(r, e, radius, curve); },
        false);
    button(registry, "clear (alt+W)", [](ecs::Registry& r, EditorState& e) { clear_weights(r, e); });
    const point_edit::PointCounts t = point_totals(registry);
    ImGui::Text("%zu selected, %zu hidden, %zu deleted of %zu", t.selected, t.hidden, t.deleted, t.points);
}

std::string point_status_text(const ecs::Registry& registry, const EditorState& state) {
    const PointToolSettings& s = state.points.settings;
    const point_edit::PointCounts t = point_totals(registry);
    return log::str("POINTS | tool ", point_tool_name(s.tool), " | mode ", point_mode_name(s.mode),
                    state.xray ? " | x-ray" : " | visible only", " | ", t.selected, " of ", t.points,
                    " selected, ", t.hidden, " hidden, ", t.deleted, " deleted");
}

void point_gizmo(const ecs::Registry& registry, const EditorState& state) {
    ImDrawList* dl = ImGui::GetForegroundDrawList();
    const ImU32 line = IM_COL32(255, 200, 60, 255), dark = IM_COL32(0, 0, 0, 200);
    const Drag& d = state.drag;
    const auto at = [](glm::dvec2 p) { return ImVec2(float(p.x), float(p.y)); };
    const std::vector<glm::dvec2>& path = state.points.path;
    if (d.kind == Drag::Kind::point_box) {
        const ImVec2 a(std::min(float(d.start.x), float(state.cursor.x)),
                       std::min(float(d.start.y), float(state.cursor.y)));
        const ImVec2 b(std::max(float(d.start.x), float(state.cursor.x)),
                       std::max(float(d.start.y), float(state.cursor.y)));
        dl->AddRectFilled(a, b, IM_COL32(255, 200, 60, 48));
        dl->AddRect(a, b, line, 0.0f, 0, 2.0f);
    }
    if (path.size() >= 2 || (!path.empty() && state.points.settings.tool == PointTool::polygon)) {
        std::vector<ImVec2> pts;
        for (const glm::dvec2& p : path) pts.push_back(at(p));
        if (state.points.settings.tool == PointTool::polygon) pts.push_back(at(state.cursor));
        dl->AddPolyline(pts.data(), int(pts.size()), dark, ImDrawFlags_Closed, 3.5f);
        dl->AddPolyline(pts.data(), int(pts.size()), line, ImDrawFlags_Closed, 2.0f);
    }
    if (state.mode == EditMode::points && state.points.settings.tool == PointTool::brush)
        dl->AddCircle(at(state.cursor), float(state.points.settings.brush_radius_px), line, 48, 1.5f);
    if (d.kind == Drag::Kind::point_sphere && state.points.has_centre && registry.valid(state.camera))
        if (const Camera* cam = registry.try_get<Camera>(state.camera)) {
            const glm::dvec3 c = project_to_pixel(*cam, state.viewport, state.points.centre);
            const glm::dvec3 right = glm::normalize(glm::cross(cam->target - cam->eye, cam->up));
            const double r = state.points.dragged_radius > 0 ? state.points.dragged_radius
                                                             : state.points.settings.sphere_radius;
            const glm::dvec3 e = project_to_pixel(*cam, state.viewport, state.points.centre + right * r);
            if (c.z <= 1.0)
                dl->AddCircle(ImVec2(float(c.x), float(c.y)), float(glm::length(glm::dvec2(e - c))), line, 48,
                              2.0f);
        }
}

}  // namespace sffd::editor
