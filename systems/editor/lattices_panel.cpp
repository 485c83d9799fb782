// The "lattices" section at the top of the Lattice panel (lattice_manage.h): the clouds and the lattices
// each follows, in order (click one to make it active); add / remove / refit with the fit settings (shape,
// padding, divisions, basis); order; export / import JSON. Every button calls the same function as its
// key, posted to the input phase (pending_edits.h), so each action is one undo step. (A section, not a window
// of its own: the right column (panel_layout.h) holds Tools and Lattice.)
#include <cstdio>
#include <string>

#include <imgui.h>

#include "runtime/scene/components.h"
#include "systems/editor/lattice_manage.h"
#include "systems/editor/panels.h"
#include "systems/editor/pending_edits.h"

namespace sffd::editor {

namespace {

std::string name_of(const ecs::Registry& r, ecs::Entity e, const char* fallback) {
    const Name* n = r.try_get<Name>(e);
    return n && !n->value.empty() ? n->value : std::string(fallback);
}

}  // namespace

void lattice_manager_section(ecs::Registry& registry, EditorState& state) {
    const bool none = !registry.valid(state.active_lattice) || !registry.has<Lattice>(state.active_lattice);
    ImGui::SetNextItemOpen(true, none ? ImGuiCond_Always : ImGuiCond_Once);
    if (ImGui::CollapsingHeader("lattices: add, remove, order, JSON")) {
        LatticeFitSettings& settings = lattice_fit_settings(registry);
        // Clouds and their ordered lattices; clicking a lattice makes it active.
        std::vector<ecs::Entity> clouds;
        registry.each_entity([&](ecs::Entity e) {
            if (registry.has<SplatCloud>(e)) clouds.push_back(e);
        });
        for (ecs::Entity c : clouds) {
            ImGui::TextUnformatted(name_of(registry, c, "cloud").c_str());
            const auto list = lattices_of(registry, c);
            if (list.empty()) ImGui::TextDisabled("  no lattice: add one (shift+a)");
            for (std::size_t i = 0; i < list.size(); ++i) {
                char prefix[32];
                std::snprintf(prefix, sizeof prefix, "  %zu. ", i + 1);
                ImGui::TextUnformatted(prefix);
                ImGui::SameLine();
                const std::string label =
                    name_of(registry, list[i], "lattice") + "##" + std::to_string(list[i].index);
                if (ImGui::Selectable(label.c_str(), list[i] == state.active_lattice))
                    state.active_lattice = list[i];
            }
        }
        ImGui::Separator();
        // Fit settings for add and refit.
        int shape = int(settings.fit.shape), basis = int(settings.fit.basis);
        ImGui::Combo("box", &shape, "axis-aligned\0oriented (PCA)\0");
        ImGui::Combo("basis##fit", &basis, "Bernstein\0cubic B-spline\0");
        settings.fit.shape = ffd::FitShape(shape), settings.fit.basis = LatticeBasis(basis);
        ImGui::InputInt3("divisions##fit", &settings.fit.divisions.x);
        settings.fit.divisions = glm::clamp(settings.fit.divisions, glm::ivec3(1), glm::ivec3(64));
        float pad = float(settings.fit.padding);
        if (ImGui::SliderFloat("padding", &pad, 0.0f, 0.5f, "%.3f")) settings.fit.padding = double(pad);
        if (ImGui::Button("add (shift+a)"))
            post_edit(registry, "add lattice", [](ecs::Registry& r, EditorState& s) { add_lattice(r, s); });
        same_line_if_fits("refit (shift+f)");
        if (ImGui::Button("refit (shift+f)"))
            post_edit(registry, "refit lattice",
                      [](ecs::Registry& r, EditorState& s) { refit_lattice(r, s); });
        if (ImGui::Button("remove (del)"))
            post_edit(registry, "remove lattice",
                      [](ecs::Registry& r, EditorState& s) { remove_lattice(r, s); });
        same_line_if_fits("up (pgup)");
        if (ImGui::Button("up (pgup)"))
            post_edit(registry, "lattice order",
                      [](ecs::Registry& r, EditorState& s) { move_lattice_in_order(r, s, -1); });
        same_line_if_fits("down (pgdn)");
        if (ImGui::Button("down (pgdn)"))
            post_edit(registry, "lattice order",
                      [](ecs::Registry& r, EditorState& s) { move_lattice_in_order(r, s, +1); });
        ImGui::Separator();
        if (settings.json_folder.empty()) {
            char path[512];
            std::snprintf(path, sizeof path, "%s", settings.json_path.c_str());
            if (ImGui::InputText("json", path, sizeof path)) settings.json_path = path;
        } else {  // named after the active lattice (lattice_json_path)
            ImGui::TextWrapped("json: %s", lattice_json_path(registry, state).c_str());
        }
        if (ImGui::Button("export (ctrl+e)"))
            post_edit(registry, "export lattice", [](ecs::Registry& r, EditorState& s) {
                export_lattice_json(r, s, lattice_json_path(r, s));
            });
        same_line_if_fits("import (ctrl+i)");
        if (ImGui::Button("import (ctrl+i)"))
            post_edit(registry, "import lattice", [](ecs::Registry& r, EditorState& s) {
                import_lattice_json(r, s, lattice_json_path(r, s));
            });
        ImGui::Separator();
    }
}

}  // namespace sffd::editor
