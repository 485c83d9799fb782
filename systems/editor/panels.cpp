#include "systems/editor/panels.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <imgui.h>

#include "runtime/app/app.h"
#include "runtime/assets/scene.h"
#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/file_browser.h"
#include "systems/editor/lattice_manage.h"
#include "systems/editor/material_edit.h"
#include "systems/editor/panel_layout.h"
#include "systems/editor/pending_edits.h"
#include "systems/editor/selection_edit.h"
#include "systems/editor/session_state.h"
#include "systems/editor/tool_widgets.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/world_space.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/profiling/overlay.h"
#include "systems/splat_render/splat_render.h"

namespace sffd::editor {

// The layout of this frame (from the window size and last frame's collapsed flags) and the rectangles the
// panels really got (what panel_rects() reports): a registry resource, so it lives and dies with the
// editor's registry.
struct detail::LayoutState {
    std::array<bool, panel_count> collapsed{};
    std::array<PanelRect, panel_count> rects{};
    float menu_height = 0.0f;
    std::vector<NamedPanelRect> drawn;
    std::vector<PanelRect> backgrounds;  // panel_backgrounds()
};
using detail::LayoutState;

namespace {
LayoutState& layout_state(ecs::Registry& registry) {
    if (LayoutState* s = registry.try_resource<LayoutState>()) return *s;
    return registry.set_resource<LayoutState>();
}

void record_current_window(ecs::Registry& registry, const char* name) {
    const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
    layout_state(registry).drawn.push_back({name, PanelRect{pos.x, pos.y, size.x, size.y}});
}

}  // namespace

// Values typed into the tool and lattice panels that stay between frames until applied: a registry
// resource, created on first use, so they live and die with the editor's registry.
struct detail::PanelEntries {
    glm::dvec3 move_by{0.0, 0.1, 0.0};
    double twist_by = 45.0;
    glm::ivec3 divisions{0};  // pending resolution of `divisions_of` (0: take the lattice's)
    ecs::Entity divisions_of = ecs::null_entity;
};
using detail::PanelEntries;

namespace {
PanelEntries& panel_entries(ecs::Registry& registry) {
    if (PanelEntries* e = registry.try_resource<PanelEntries>()) return *e;
    return registry.set_resource<PanelEntries>();
}

// Begin of a laid-out panel: placed and sized every frame (the user collapses panels, the layout moves
// the others), not movable or resizable by hand (a moved panel would cover another).
bool begin_panel(ecs::Registry& registry, Panel p) {
    LayoutState& ls = layout_state(registry);
    const PanelRect& r = ls.rects[std::size_t(p)];
    ImGui::SetNextWindowPos(ImVec2(r.x, r.y), ImGuiCond_Always);
    ImGui::SetNextWindowSize(ImVec2(r.w, r.h), ImGuiCond_Always);
    const ImVec2 window = ImGui::GetMainViewport()->Size;
    if (panels_start_collapsed(window.x, window.y))
        ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
    const bool open =
        ImGui::Begin(panel_title(p), nullptr,
                     ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoBackground);
    ls.collapsed[std::size_t(p)] = ImGui::IsWindowCollapsed();
    record_current_window(registry, panel_title(p));
    if (!ls.collapsed[std::size_t(p)]) ls.backgrounds.push_back(ls.drawn.back().rect);
    return open;
}

// One inspector edit = one undo step, and no panel writes a component (pending_edits.h): each widget edits
// a copy of the component and posts it while it changes; the value the component had when the widget
// became active is kept in PendingEdits (so a half-done edit dies with the editor's registry) and posted
// with the last value on release, where the input phase records it as one step.
template <class C>
void post_widget(ecs::Registry& registry, ecs::Entity e, const C& shown, const C& value, bool changed,
                 const char* label) {
    post_widget_gesture<C>(registry, e, shown, value, ImGui::IsItemActivated(), changed,
                           ImGui::IsItemDeactivatedAfterEdit(), label);
}

// Posts an operation of editor_system.h / lattice_manage.h (each records its own undo step).
template <class Fn>
void post(ecs::Registry& registry, const char* label, Fn&& fn) {
    post_edit(registry, label, std::forward<Fn>(fn));
}

bool input_dvec3(const char* label, glm::dvec3& v, const char* format = "%.4f") {
    return ImGui::InputScalarN(label, ImGuiDataType_Double, &v.x, 3, nullptr, nullptr, format);
}
bool drag_dvec3(const char* label, glm::dvec3& v, float speed = 0.01f) {
    return ImGui::DragScalarN(label, ImGuiDataType_Double, &v.x, 3, speed, nullptr, nullptr, "%.4f");
}

std::string entity_label(const ecs::Registry& registry, ecs::Entity e) {
    std::string name = "entity " + std::to_string(e.index);
    if (const Name* n = registry.try_get<Name>(e); n && !n->value.empty()) name = n->value;
    const std::string kind = entity_kind(registry, e);
    return kind.empty() ? name : name + "  [" + kind + "]";
}

void menu_bar(ecs::Registry& registry, EditorState& state) {
    bool open_popup = false, save_popup = false;
    if (ImGui::BeginMainMenuBar()) {
        layout_state(registry).menu_height = ImGui::GetWindowSize().y;
        record_current_window(registry, "##menu");
        if (ImGui::BeginMenu("File")) {
            if (ImGui::MenuItem("Open scene...", "Ctrl+O")) open_popup = true;
            if (ImGui::MenuItem("Save scene", "Ctrl+S")) state.request_save = true;
            if (ImGui::MenuItem("Save scene as...")) save_popup = true;
            if (ImGui::MenuItem("Screenshot", "F12")) state.request_screenshot = true;
            ImGui::Separator();
            if (ImGui::MenuItem("Quit", "Ctrl+Q")) state.request_quit = true;
            ImGui::EndMenu();
        }
        if (ImGui::BeginMenu("Edit")) {
            if (ImGui::MenuItem("Undo", "Ctrl+Z", false, state.undo.can_undo()))
                post(registry, "undo", [](ecs::Registry& r, EditorState& s) { undo(r, s); });
            if (ImGui::MenuItem("Redo", "Ctrl+Shift+Z", false, state.undo.can_redo()))
                post(registry, "redo", [](ecs::Registry& r, EditorState& s) { redo(r, s); });
            ImGui::Separator();
            if (ImGui::MenuItem("Select all", "A"))
                post(registry, "select all", [](ecs::Registry& r, EditorState& s) { select_all(r, s); });
            if (ImGui::MenuItem("Deselect", "Esc"))
                post(registry, "deselect", [](ecs::Registry& r, EditorState& s) { clear_selection(r, s); });
            if (ImGui::MenuItem("Reset lattice", "Home"))
                post(registry, "reset lattice",
                     [](ecs::Registry& r, EditorState& s) { reset_lattice(r, s); });
            ImGui::EndMenu();
        }
        if (ImGui::BeginMenu("View")) {
            ImGui::MenuItem("X-ray", "T", &state.xray);
            ImGui::MenuItem("Lattice", nullptr, &state.show_lattice);
            ImGui::MenuItem("Weights", nullptr, &state.show_weights);
            ImGui::MenuItem("Lattice cage only", "Shift+T", &state.lattice_cage_only);
            ImGui::MenuItem("Preview while moving", nullptr, &state.preview_while_moving);
            ImGui::MenuItem("Half-resolution preview", nullptr, &state.half_resolution_preview,
                            state.preview_while_moving);
            ImGui::MenuItem("Light overlay while moving", nullptr, &state.light_overlay_while_moving,
                            state.preview_while_moving);
            ImGui::MenuItem("Auto-key", "N", &state.auto_key);
            if (ImGui::MenuItem("Frame selection", "F"))
                post(registry, "frame selection",
                     [](ecs::Registry& r, EditorState& s) { frame_selection(r, s); });
            ImGui::EndMenu();
        }
        ImGui::EndMainMenuBar();
    }
    if (state.request_open_dialog) open_popup = true, state.request_open_dialog = false;
    if (open_popup || save_popup) open_file_dialog(registry, state, save_popup);
    file_dialog_window(registry, state);
}

void outliner(ecs::Registry& registry, EditorState& state) {
    if (begin_panel(registry, Panel::outliner)) {
        registry.each_entity([&](ecs::Entity e) {
            const std::string label = entity_label(registry, e) + "##" + std::to_string(e.index);
            if (ImGui::Selectable(label.c_str(), state.selected_entity == e)) {
                state.selected_entity = e;
                if (registry.has<Lattice>(e)) state.active_lattice = e;
            }
        });
    }
    ImGui::End();
}

void inspector(ecs::Registry& registry, EditorState& state) {
    if (!begin_panel(registry, Panel::inspector)) {
        ImGui::End();
        return;
    }
    const ecs::Registry& cr = registry;  // the panel reads components; its edits are posted
    const ecs::Entity e = state.selected_entity;
    if (!cr.valid(e)) {
        ImGui::TextDisabled("select an entity in the outliner");
        ImGui::End();
        return;
    }
    if (const Name* n = cr.try_get<Name>(e);
        n && ImGui::CollapsingHeader("Name", ImGuiTreeNodeFlags_DefaultOpen)) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%s", n->value.c_str());
        Name value = *n;
        const bool changed = ImGui::InputText("name", buf, sizeof buf);
        if (changed) value.value = buf;
        post_widget<Name>(registry, e, *n, value, changed, "rename");
    }
    if (const Transform* t = cr.try_get<Transform>(e);
        t && ImGui::CollapsingHeader("Transform", ImGuiTreeNodeFlags_DefaultOpen)) {
        Transform value = *t;
        bool changed = drag_dvec3("translation", value.translation);
        post_widget<Transform>(registry, e, *t, value, changed, "move entity");
        glm::dvec3 euler = glm::degrees(glm::eulerAngles(t->rotation));
        changed = drag_dvec3("rotation (deg)", euler, 0.5f);
        if (changed) value.rotation = glm::dquat(glm::radians(euler));
        post_widget<Transform>(registry, e, *t, value, changed, "rotate entity");
        changed = drag_dvec3("scale", value.scale);
        post_widget<Transform>(registry, e, *t, value, changed, "scale entity");
    }
    if (const SplatCloud* c = cr.try_get<SplatCloud>(e);
        c && ImGui::CollapsingHeader("SplatCloud", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Text("%zu splats%s%s", c->size(), c->colors.empty() ? "" : ", colours",
                    c->texture.path.empty() ? "" : ", textured");
        ImGui::Text("origin %.3f %.3f %.3f", c->origin.x, c->origin.y, c->origin.z);
    }
    if (const SplatMaterial* m = cr.try_get<SplatMaterial>(e);
        m && ImGui::CollapsingHeader("Material", ImGuiTreeNodeFlags_DefaultOpen)) {
        // Its own component (material_edit.h): a drag re-renders only, and its undo step holds two
        // materials. Replays set the same fields through set_material_value().
        SplatMaterial value = *m;
        bool ch = ImGui::ColorEdit4("base colour", &value.base_color.x);
        post_widget<SplatMaterial>(registry, e, *m, value, ch, "material colour");
        for (MaterialField f : {MaterialField::specular, MaterialField::shininess}) {
            const MaterialFieldInfo& info = material_field_info(f);
            ch = ImGui::SliderFloat(info.widget, &material_value(value, f), info.min, info.max);
            post_widget<SplatMaterial>(registry, e, *m, value, ch, info.label);
        }
    }
    if (const Camera* cam = cr.try_get<Camera>(e);
        cam && ImGui::CollapsingHeader("Camera", ImGuiTreeNodeFlags_DefaultOpen)) {
        Camera value = *cam;
        bool ch = drag_dvec3("eye", value.eye);
        post_widget<Camera>(registry, e, *cam, value, ch, "camera eye");
        ch = drag_dvec3("target", value.target);
        post_widget<Camera>(registry, e, *cam, value, ch, "camera target");
        ch = ImGui::SliderFloat("fov y", &value.fov_y_degrees, 5.0f, 120.0f);
        post_widget<Camera>(registry, e, *cam, value, ch, "camera fov");
    }
    if (const DirectionalLight* l = cr.try_get<DirectionalLight>(e);
        l && ImGui::CollapsingHeader("DirectionalLight", ImGuiTreeNodeFlags_DefaultOpen)) {
        DirectionalLight value = *l;
        bool ch = ImGui::DragFloat3("direction", &value.direction.x, 0.01f);
        post_widget<DirectionalLight>(registry, e, *l, value, ch, "light direction");
        ch = ImGui::ColorEdit3("colour", &value.color.x);
        post_widget<DirectionalLight>(registry, e, *l, value, ch, "light colour");
        ch = ImGui::SliderFloat("intensity", &value.intensity, 0.0f, 10.0f);
        post_widget<DirectionalLight>(registry, e, *l, value, ch, "light intensity");
    }
    if (const AmbientLight* a = cr.try_get<AmbientLight>(e);
        a && ImGui::CollapsingHeader("AmbientLight", ImGuiTreeNodeFlags_DefaultOpen)) {
        AmbientLight value = *a;
        bool ch = ImGui::ColorEdit3("ambient colour", &value.color.x);
        post_widget<AmbientLight>(registry, e, *a, value, ch, "ambient colour");
        ch = ImGui::SliderFloat("ambient intensity", &value.intensity, 0.0f, 2.0f);
        post_widget<AmbientLight>(registry, e, *a, value, ch, "ambient intensity");
    }
    if (const Lattice* l = cr.try_get<Lattice>(e);
        l && ImGui::CollapsingHeader("Lattice", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Text("divisions %d x %d x %d (%zu points), %s", l->divisions.x, l->divisions.y, l->divisions.z,
                    l->size(), l->basis == LatticeBasis::bernstein ? "Bernstein" : "B-spline");
        ImGui::Text("origin %.3f %.3f %.3f", l->origin.x, l->origin.y, l->origin.z);
        if (const auto* sel = cr.try_get<picking::LatticeSelection>(e))
            ImGui::Text("%zu selected", sel->indices.size());
        ImGui::TextDisabled("edit shape and resolution in the Lattice panel");
    }
    if (const Deformers* d = cr.try_get<Deformers>(e); d && ImGui::CollapsingHeader("Deformers")) {
        for (ecs::Entity l : d->lattices) ImGui::BulletText("%s", entity_label(registry, l).c_str());
    }
    if (const AnimationClip* clip = cr.try_get<AnimationClip>(e);
        clip && ImGui::CollapsingHeader("AnimationClip")) {
        AnimationClip value = *clip;
        double duration = clip->duration;
        const bool ch = ImGui::InputDouble("duration (s)", &duration, 0.1, 1.0, "%.3f");
        if (ch && duration > 0.0) value.duration = duration;
        post_widget<AnimationClip>(registry, e, *clip, value, ch && duration > 0.0, "clip duration");
        int mode = int(clip->mode);
        const bool mch = ImGui::Combo("mode", &mode, "loop\0once\0ping-pong\0");
        if (mch) value.mode = PlayMode(mode);
        post_widget<AnimationClip>(registry, e, *clip, value, mch, "clip mode");
        ImGui::Text("%zu tracks", clip->tracks.size());
    }
    ImGui::End();
}

void tools_panel(ecs::Registry& registry, EditorState& state) {
    const bool open = begin_panel(registry, Panel::tools);
    if (open) edit_mode_widgets(registry, state);
    if (open && state.mode == EditMode::points) point_tools_widgets(registry, state);  // tool_widgets.cpp
    if (open && state.mode != EditMode::points) {
        int tool = int(state.tool);
        ImGui::RadioButton("select (Q)", &tool, int(Tool::select));
        ImGui::SameLine();
        ImGui::RadioButton("move (G)", &tool, int(Tool::move));
        ImGui::RadioButton("twist (R)", &tool, int(Tool::twist));
        ImGui::SameLine();
        ImGui::RadioButton("brush (B)", &tool, int(Tool::brush));
        ImGui::RadioButton("scale (S)", &tool, int(Tool::scale));
        state.tool = Tool(tool);
        int move_axis = int(state.move_axis);
        ImGui::Combo("move axis", &move_axis, "view plane\0x\0y\0z\0view\0custom\0");
        state.move_axis = AxisMode(move_axis);
        int twist_axis = int(state.twist_axis) - 1;
        ImGui::Combo("twist axis", &twist_axis, "x\0y\0z\0view\0custom\0");
        state.twist_axis = AxisMode(twist_axis + 1);
        input_dvec3("custom axis", state.custom_axis, "%.3f");
        int pivot = int(state.pivot_mode);
        ImGui::Combo("pivot", &pivot, "selection centroid\0picked point (alt+click)\0");
        state.pivot_mode = PivotMode(pivot);
        int scope = int(state.scope);
        ImGui::RadioButton("local (selection)", &scope, int(ToolScope::local));
        ImGui::SameLine();
        ImGui::RadioButton("global", &scope, int(ToolScope::global));
        state.scope = ToolScope(scope);
        ImGui::Checkbox("pin outer layer (P)", &state.pin_outer_layer);
        ImGui::SameLine();
        ImGui::Checkbox("x-ray (T)", &state.xray);
        proportional_widgets(state);
        ImGui::Separator();
        glm::dvec3& move_by = panel_entries(registry).move_by;
        double& twist_by = panel_entries(registry).twist_by;
        input_dvec3("##move", move_by, "%.3f");
        ImGui::SameLine();
        if (ImGui::Button("stretch"))
            post(registry, "stretch",
                 [by = move_by](ecs::Registry& r, EditorState& s) { apply_stretch(r, s, by); });
        ImGui::InputDouble("##twist", &twist_by, 5.0, 45.0, "%.1f deg");
        ImGui::SameLine();
        if (ImGui::Button("twist"))
            post(registry, "twist",
                 [by = twist_by](ecs::Registry& r, EditorState& s) { apply_twist(r, s, by); });
        if (ImGui::Button("reset lattice"))
            post(registry, "reset lattice", [](ecs::Registry& r, EditorState& s) { reset_lattice(r, s); });
        ImGui::SameLine();
        if (ImGui::Button("frame (F)"))
            post(registry, "frame selection",
                 [](ecs::Registry& r, EditorState& s) { frame_selection(r, s); });
        ImGui::Text("editable: %zu points", editable_selection(registry, state).size());
    }
    ImGui::End();
}

void lattice_panel(ecs::Registry& registry, EditorState& state) {
    if (begin_panel(registry, Panel::lattice)) {
        lattice_manager_section(registry, state);  // add / remove / order / JSON (lattice_manage.h)
        const Lattice* l = registry.valid(state.active_lattice)
                               ? std::as_const(registry).try_get<Lattice>(state.active_lattice)
                               : nullptr;
        if (!l) {
            ImGui::TextDisabled("no lattice: shift+a adds one");
        } else {
            ImGui::Text("%s", entity_label(registry, state.active_lattice).c_str());
            ImGui::Text("%d x %d x %d divisions, %s", l->divisions.x, l->divisions.y, l->divisions.z,
                        l->basis == LatticeBasis::bernstein ? "Bernstein" : "B-spline");
            const std::size_t inside = control_points_inside_object(registry, *l);
            const auto outer = outer_layer_mask(*l);
            ImGui::TextWrapped("%zu inside the object's box (white), %zu outer (pinned: %s)", inside,
                               std::size_t(std::count(outer.begin(), outer.end(), std::uint8_t(1))),
                               state.pin_outer_layer ? "yes" : "no");
            if (ImGui::Button(state.pin_outer_layer ? "unpin outer layer" : "pin outer layer"))
                state.pin_outer_layer = !state.pin_outer_layer;
            ImGui::SameLine();
            if (ImGui::Button("reset"))
                post(registry, "reset lattice",
                     [](ecs::Registry& r, EditorState& s) { reset_lattice(r, s); });
            ImGui::Separator();
            // Resolution: edits a pending value; "resample" applies it keeping the current shape.
            glm::ivec3& divisions = panel_entries(registry).divisions;
            ecs::Entity& divisions_of = panel_entries(registry).divisions_of;
            if (divisions_of != state.active_lattice || divisions == glm::ivec3(0)) {
                divisions = l->divisions;
                divisions_of = state.active_lattice;
            }
            ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.5f);
            ImGui::InputInt3("divisions", &divisions.x);
            divisions = glm::clamp(divisions, glm::ivec3(1), glm::ivec3(64));
            same_line_if_fits("resample");
            if (ImGui::Button("resample")) {
                post(registry, "resample",
                     [d = divisions](ecs::Registry& r, EditorState& s) { resample_lattice(r, s, d); });
                divisions = glm::ivec3(0);
            }
            int basis = int(l->basis);
            if (ImGui::Combo("basis", &basis, "Bernstein\0cubic B-spline\0"))
                post(registry, "basis", [b = LatticeBasis(basis)](ecs::Registry& r, EditorState& s) {
                    set_lattice_basis(r, s, b);
                });
            if (ImGui::Button("fit to object"))
                post(registry, "fit to object",
                     [](ecs::Registry& r, EditorState& s) { fit_lattice_to(r, s, false); });
            same_line_if_fits("fit to selection");
            if (ImGui::Button("fit to selection"))
                post(registry, "fit to selection",
                     [](ecs::Registry& r, EditorState& s) { fit_lattice_to(r, s, true); });
            same_line_if_fits("apply as rest");
            if (ImGui::Button("apply as rest"))
                post(registry, "apply as rest",
                     [](ecs::Registry& r, EditorState& s) { apply_lattice_as_rest(r, s); });
        }
    }
    ImGui::End();
}

void timeline_panel(ecs::Registry& registry, EditorState& state) {
    if (begin_panel(registry, Panel::timeline)) {
        const ecs::Entity e = state.active_lattice;
        const ecs::Registry& cr = registry;
        const AnimationClip* clip = cr.valid(e) ? cr.try_get<AnimationClip>(e) : nullptr;
        const AnimationState* anim = cr.valid(e) ? cr.try_get<AnimationState>(e) : nullptr;
        if (ImGui::Button(anim && anim->playing ? "pause" : "play"))
            post(registry, "play", [](ecs::Registry& r, EditorState& s) { toggle_play(r, s); });
        ImGui::SameLine();
        if (ImGui::Button("set key (K)"))
            post(registry, "set key", [](ecs::Registry& r, EditorState& s) { key_last_edit(r, s); });
        ImGui::SameLine();
        if (ImGui::Button("delete key"))
            post(registry, "delete key", [](ecs::Registry& r, EditorState& s) { delete_keys_at_time(r, s); });
        ImGui::SameLine();
        ImGui::Checkbox("auto-key (N)", &state.auto_key);
        if (clip && anim) {
            ImGui::SameLine();
            float t = float(anim->time);
            ImGui::SetNextItemWidth(-1);
            if (ImGui::SliderFloat("##time", &t, 0.0f, float(clip->duration), "%.3f s"))
                post(registry, "scrub", [t](ecs::Registry& r, EditorState& s) { scrub_to(r, s, t); });
            // Key markers under the slider.
            const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
            ImDrawList* dl = ImGui::GetWindowDrawList();
            for (const KeyRef& k : list_keys(*clip)) {
                const float x = lo.x + (hi.x - lo.x) * float(k.time / clip->duration);
                dl->AddTriangleFilled(ImVec2(x, hi.y - 6), ImVec2(x - 4, hi.y + 2), ImVec2(x + 4, hi.y + 2),
                                      IM_COL32(255, 190, 40, 255));
            }
        } else {
            ImGui::TextDisabled("no clip on this lattice: stretch or twist, then set key");
        }
    }
    ImGui::End();
}

}  // namespace

// What the frame-time panel shows: the profile overlay's numbers as they were at the last refresh. Five
// times a second, as frame-rate readouts usually refresh: numbers that change every frame cannot be read,
// and between refreshes the panel draws the same triangles, which the UI's panel cache then copies
// instead of drawing (ui_cache.h).
struct detail::FrameTimeShown {
    std::chrono::steady_clock::time_point at{};
    bool valid = false;
    float last_ms = 0.0f, avg_ms = 0.0f;
    std::vector<float> graph;  // oldest first
    float scale = 0.0f;
    struct Bar {
        std::string name;
        float avg_ms = 0.0f;
    };
    std::vector<Bar> bars;
};
using detail::FrameTimeShown;

namespace {
constexpr std::chrono::milliseconds kFrameTimeRefresh{200};

void profiler_panel(ecs::Registry& registry, EditorState&) {
    if (begin_panel(registry, Panel::frame_time)) {
        FrameTimeShown* shown = registry.try_resource<FrameTimeShown>();
        if (!shown) shown = &registry.set_resource<FrameTimeShown>();
        const auto now = std::chrono::steady_clock::now();
        if (const auto* o = registry.try_resource<profiling::ProfileOverlay>();
            o && o->count > 0 && (!shown->valid || now - shown->at >= kFrameTimeRefresh)) {
            shown->at = now, shown->valid = true;
            shown->last_ms = o->frame_last_ms, shown->avg_ms = o->frame_avg_ms;
            shown->graph.resize(o->count);
            for (std::size_t k = 0; k < o->count; ++k)
                shown->graph[k] = o->frame_ms[(o->oldest() + k) % profiling::ProfileOverlay::history];
            // Scaled to the typical frame, not the ring's maximum: the first frame (shader compilation,
            // uploads: seconds) made every later frame a flat line at the bottom of the graph.
            shown->scale = graph_scale(std::span<const float>(o->frame_ms.data(), o->count));
            shown->bars.clear();
            for (const auto& e : o->systems) shown->bars.push_back({e.name, e.avg_ms});
        }
        if (shown->valid) {
            ImGui::Text("%.1f ms (avg %.1f, %.1f FPS)", double(shown->last_ms), double(shown->avg_ms),
                        shown->avg_ms > 0 ? 1000.0 / double(shown->avg_ms) : 0.0);
            char overlay[48];
            std::snprintf(overlay, sizeof overlay, "0..%.0f ms, %zu frames", double(shown->scale),
                          shown->graph.size());
            ImGui::PlotLines("##frame", shown->graph.data(), int(shown->graph.size()), 0, overlay, 0.0f,
                             shown->scale,
                             ImVec2(ImGui::GetContentRegionAvail().x,
                                    50));  // PlotLines (1.86) takes no -1 width: it drew a 1-px line
            const float total = std::max(shown->avg_ms, 1e-3f);
            for (const auto& b : shown->bars) {
                char text[128];
                std::snprintf(text, sizeof text, "%s %.2f ms", b.name.c_str(), double(b.avg_ms));
                ImGui::ProgressBar(std::clamp(b.avg_ms / total, 0.0f, 1.0f), ImVec2(-1, 0), text);
            }
        } else {
            ImGui::TextDisabled("no profile yet");
        }
    }
    ImGui::End();
}

// One text line with the window padding, and never below ImGui's minimum window height (which a
// 24 px bar used to exceed, reaching 8 px below the window).
float status_bar_height() {
    const ImGuiStyle& style = ImGui::GetStyle();
    return std::max(style.WindowMinSize.y, ImGui::GetTextLineHeight() + 2.0f * style.WindowPadding.y);
}

void status_bar(ecs::Registry& registry, EditorState& state) {
    const ImGuiViewport* vp = ImGui::GetMainViewport();
    const float h = status_bar_height();
    ImGui::SetNextWindowPos(ImVec2(vp->Pos.x, vp->Pos.y + vp->Size.y - h));
    ImGui::SetNextWindowSize(ImVec2(vp->Size.x, h));
    ImGui::Begin("##status", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs |
                     ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing);
    record_current_window(registry, "##status");
    std::size_t selected = 0;
    if (registry.valid(state.active_lattice))
        if (const auto* s = std::as_const(registry).try_get<picking::LatticeSelection>(state.active_lattice))
            selected = s->indices.size();
    const char* render = state.previewing                                      ? "preview while moving"
                         : state.rest_quality == int(render::Quality::preview) ? "preview"
                                                                               : "HQ";
    const std::string proportional =
        state.proportional.enabled
            ? log::str(" | proportional ", falloff_name(state.proportional.falloff), " r ",
                       state.drag.proportional.enabled ? state.drag.proportional.radius
                                                       : state.proportional.radius)
            : std::string();
    if (state.mode == EditMode::points) {
        ImGui::Text("%s | render %s | undo %zu/%zu | %s", point_status_text(registry, state).c_str(), render,
                    state.undo.position(), state.undo.size(), state.status.c_str());
        return ImGui::End();
    }
    ImGui::Text(
        "LATTICE | tool %s | axis %s | %s%s%s%s | %zu selected | auto-key %s%s | render %s | undo %zu/%zu | "
        "%s",
        tool_name(state.tool), axis_mode_name(state.tool == Tool::twist ? state.twist_axis : state.move_axis),
        state.scope == ToolScope::local ? "local" : "global", state.pin_outer_layer ? " pinned" : "",
        state.xray ? " x-ray" : "", proportional.c_str(), selected, state.auto_key ? "ON" : "off",
        registry.valid(state.unkeyed) && registry.has<AnimationClip>(state.unkeyed) ? " (un-keyed edit)" : "",
        render, state.undo.position(), state.undo.size(), state.status.c_str());
    ImGui::End();
}

void gizmo(ecs::Registry& registry, EditorState& state) {
    point_gizmo(registry, state);  // point mode's box, lasso, polygon, brush and sphere
    if (state.mode == EditMode::points) return;
    ImDrawList* dl = ImGui::GetForegroundDrawList();
    const Drag& d = state.drag;
    if (d.kind == Drag::Kind::box) {
        // Translucent fill under a 2-px outline with a dark 1-px edge outside it, visible on light and dark
        // surfaces alike (a faint 1-px line was lost over the model).
        const ImVec2 a(std::min(float(d.start.x), float(state.cursor.x)),
                       std::min(float(d.start.y), float(state.cursor.y)));
        const ImVec2 b(std::max(float(d.start.x), float(state.cursor.x)),
                       std::max(float(d.start.y), float(state.cursor.y)));
        dl->AddRectFilled(a, b, IM_COL32(255, 200, 60, 48));
        dl->AddRect(ImVec2(a.x - 1.5f, a.y - 1.5f), ImVec2(b.x + 1.5f, b.y + 1.5f), IM_COL32(0, 0, 0, 200),
                    0.0f, 0, 1.0f);
        dl->AddRect(a, b, IM_COL32(255, 200, 60, 255), 0.0f, 0, 2.0f);
    }
    if (state.tool != Tool::move && state.tool != Tool::twist && state.tool != Tool::scale) return;
    if (!registry.valid(state.camera) || !registry.has<Camera>(state.camera)) return;
    const ecs::Registry& cr = registry;
    const Camera& cam = cr.get<Camera>(state.camera);
    const std::vector<std::uint32_t> pts = editable_selection(registry, state);
    if (pts.empty() && d.kind == Drag::Kind::none) return;
    glm::dvec3 pivot = d.kind != Drag::Kind::none ? d.pivot_world : glm::dvec3(0.0);
    if (d.kind == Drag::Kind::none) {
        if (state.pivot_mode == PivotMode::picked_point && state.has_picked_pivot) {
            pivot = state.picked_pivot;
        } else if (const Lattice* l = cr.try_get<Lattice>(state.active_lattice)) {
            pivot = glm::dvec3(model_matrix(cr.try_get<Transform>(state.active_lattice)) *
                               glm::dvec4(centroid(*l, pts), 1.0));
        }
    }
    const glm::dvec3 c = project_to_pixel(cam, state.viewport, pivot);
    if (c.z > 1.0) return;
    const ImVec2 centre(float(c.x), float(c.y));
    const AxisMode mode = state.tool == Tool::twist ? state.twist_axis : state.move_axis;
    if (mode == AxisMode::view_plane) {
        dl->AddCircle(centre, 14.0f, IM_COL32(255, 255, 255, 220), 24, 2.0f);
    } else {
        const glm::dvec3 axis = axis_direction(mode, cam, state.custom_axis);
        const double size = 0.25 * glm::length(cam.eye - cam.target);
        const glm::dvec3 a = project_to_pixel(cam, state.viewport, pivot - axis * size);
        const glm::dvec3 b = project_to_pixel(cam, state.viewport, pivot + axis * size);
        const ImU32 col = mode == AxisMode::x   ? IM_COL32(240, 70, 70, 255)
                          : mode == AxisMode::y ? IM_COL32(90, 220, 90, 255)
                          : mode == AxisMode::z ? IM_COL32(80, 130, 255, 255)
                                                : IM_COL32(230, 230, 230, 255);
        if (a.z <= 1.0 && b.z <= 1.0)
            dl->AddLine(ImVec2(float(a.x), float(a.y)), ImVec2(float(b.x), float(b.y)), col, 2.0f);
        if (state.tool == Tool::twist) dl->AddCircle(centre, 40.0f, col, 48, 2.0f);
    }
    dl->AddCircleFilled(centre, 4.0f, IM_COL32(255, 255, 255, 255));
    if (d.kind == Drag::Kind::twist) {
        char text[64];
        std::snprintf(text, sizeof text, "%.1f deg", glm::degrees(d.angle));
        dl->AddText(ImVec2(centre.x + 44, centre.y - 8), IM_COL32(255, 255, 255, 255), text);
    }
}

}  // namespace

void same_line_if_fits(const char* next_label) {
    const ImGuiStyle& style = ImGui::GetStyle();
    const float w = ImGui::CalcTextSize(next_label, nullptr, true).x + 2.0f * style.FramePadding.x;
    const float right = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
    if (ImGui::GetItemRectMax().x + style.ItemSpacing.x + w <= right) ImGui::SameLine();
}

std::vector<PanelRect> panel_backgrounds(const ecs::Registry& registry) {
    const LayoutState* ls = registry.try_resource<LayoutState>();
    return ls ? ls->backgrounds : std::vector<PanelRect>{};
}

std::vector<NamedPanelRect> panel_rects(const ecs::Registry& registry) {
    const LayoutState* ls = registry.try_resource<LayoutState>();
    return ls ? ls->drawn : std::vector<NamedPanelRect>{};
}

void draw_panels(ecs::Registry& registry, const FrameContext&) {
    EditorState* state = registry.try_resource<EditorState>();
    if (!state) return;
    LayoutState& ls = layout_state(registry);
    ls.drawn.clear();
    ls.backgrounds.clear();
    const ImGuiViewport* vp = ImGui::GetMainViewport();
    LayoutInput in;
    in.width = vp->Size.x, in.height = vp->Size.y;
    in.top = ls.menu_height > 0.0f ? ls.menu_height : ImGui::GetFrameHeight();
    in.bottom = status_bar_height();
    in.title = ImGui::GetFrameHeight();
    in.collapsed = ls.collapsed;
    ls.rects = layout_panels(in);
    const PanelRect view = view_rect(ls.rects, in);
    registry.set_resource<EditorViewRect>(EditorViewRect{view, in.width, in.height});
    registry.set_resource<render::DisplayViewport>(
        render::DisplayViewport{view.x, view.y, view.w, view.h, in.width, in.height});
    menu_bar(registry, *state);
    outliner(registry, *state);
    inspector(registry, *state);
    tools_panel(registry, *state);
    lattice_panel(registry, *state);
    timeline_panel(registry, *state);
    profiler_panel(registry, *state);
    status_bar(registry, *state);
    gizmo(registry, *state);
}

}  // namespace sffd::editor
