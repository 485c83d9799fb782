// The editor's open / save-as dialog (File > Open scene, Save scene as, ctrl+o), drawn by draw_panels.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <imgui.h>

#include "runtime/assets/scene.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/file_browser.h"
#include "systems/editor/panels.h"
#include "systems/editor/pending_edits.h"
#include "systems/editor/session_state.h"

namespace sffd::editor {

// The open / save dialog (named in session_state.h): a folder listing (file_browser.h) with ".." and
// sub-folders, files filtered by extension, a name field (built-in scene names such as "sphere" can be
// typed), Escape or Cancel closes.
struct detail::FileDialog {
    enum class Mode { open, save } mode = Mode::open;
    std::filesystem::path folder;
    std::vector<FolderEntry> entries;
    std::string error;
    char name[512] = "";
};
using detail::FileDialog;

namespace {
// A registry resource, so the dialog's folder and listing live and die with the editor's registry.
FileDialog& file_dialog(ecs::Registry& registry) {
    if (FileDialog* d = registry.try_resource<FileDialog>()) return *d;
    return registry.set_resource<FileDialog>();
}

void browse(FileDialog& d, const std::filesystem::path& folder) {
    auto listed =
        list_folder(folder, d.mode == FileDialog::Mode::open ? openable_extensions() : saveable_extensions());
    if (!listed) {
        d.error = listed.message();
        return;
    }
    std::error_code ec;
    d.folder = std::filesystem::weakly_canonical(folder, ec);
    if (ec) d.folder = folder;
    d.entries = std::move(*listed);
    d.error.clear();
}

void remember_folder(EditorState& state, const std::filesystem::path& folder) {
    state.last_folder = folder.string();
    save_last_folder(state.settings_file, state.last_folder);
}

void open_scene_file(ecs::Registry& registry, EditorState& state, const std::string& path) {
    // Replace the scene: destroy every entity, load, re-run the editor set-up. The undo history refers
    // to the old entities, so it is cleared.
    ecs::Registry probe;
    SceneHooks::copy_to(registry, probe);  // the probe opens what the scene's registry opens
    if (Status st = load_scene(probe, path); !st) {
        state.status = st.message();
        return;
    }
    std::vector<ecs::Entity> all;
    registry.each_entity([&](ecs::Entity e) { all.push_back(e); });
    for (ecs::Entity e : all) registry.destroy(e);
    if (Status st2 = load_scene(registry, path); !st2) state.status = st2.message();
    state.undo.clear();
    state.camera = state.active_lattice = state.selected_entity = ecs::null_entity;
    state.last_edit = {};
    state.unkeyed = ecs::null_entity;
    // Point mode's gesture and caches name the old clouds; its settings stay.
    state.points.path.clear(), state.points.stroke.clear(), state.points.has_centre = false;
    state.points.select = point_select::PointSelectState{};
    setup_editor(registry, state.viewport);
    state.status = "opened " + path;
}

}  // namespace

void file_dialog_window(ecs::Registry& registry, EditorState& state) {
    FileDialog& d = file_dialog(registry);
    const char* title = d.mode == FileDialog::Mode::open ? "Open scene" : "Save scene as";
    const ImGuiViewport* vp = ImGui::GetMainViewport();
    ImGui::SetNextWindowPos(ImVec2(vp->Size.x * 0.5f, vp->Size.y * 0.5f), ImGuiCond_Appearing,
                            ImVec2(0.5f, 0.5f));
    ImGui::SetNextWindowSize(
        ImVec2(std::min(640.0f, vp->Size.x - 40.0f), std::min(460.0f, vp->Size.y - 80.0f)),
        ImGuiCond_Appearing);
    if (!ImGui::BeginPopupModal(title, nullptr)) return;
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) {
        ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
        return;
    }
    ImGui::TextUnformatted(d.folder.string().c_str());
    if (!d.error.empty()) ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", d.error.c_str());
    const float list_h = ImGui::GetContentRegionAvail().y - 2.0f * ImGui::GetFrameHeightWithSpacing() - 4.0f;
    std::string chosen;  // a file double-clicked: open/save it at once
    if (ImGui::BeginChild("##files", ImVec2(0, std::max(list_h, 60.0f)), true)) {
        std::filesystem::path enter;
        for (const FolderEntry& e : d.entries) {
            const std::string label = e.folder ? "[" + e.name + "]" : e.name;
            if (ImGui::Selectable(label.c_str(), !e.folder && e.name == d.name,
                                  ImGuiSelectableFlags_AllowDoubleClick)) {
                if (e.folder) enter = e.name == ".." ? d.folder.parent_path() : d.folder / e.name;
                else {
                    std::snprintf(d.name, sizeof d.name, "%s", e.name.c_str());
                    if (ImGui::IsMouseDoubleClicked(0)) chosen = (d.folder / e.name).string();
                }
            }
        }
        if (!enter.empty()) browse(d, enter);
    }
    ImGui::EndChild();
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.7f);
    const bool entered =
        ImGui::InputText(d.mode == FileDialog::Mode::open ? "file or built-in name" : "file name", d.name,
                         sizeof d.name, ImGuiInputTextFlags_EnterReturnsTrue);
    if (ImGui::Button(d.mode == FileDialog::Mode::open ? "Open" : "Save") || entered) {
        const std::string name = d.name;
        if (!name.empty()) {
            const std::filesystem::path p(name);
            // A bare built-in name ("sphere") is not a file in the folder; anything else is relative to it.
            const bool builtin = d.mode == FileDialog::Mode::open && !p.has_extension() &&
                                 !p.has_parent_path() && !std::filesystem::exists(d.folder / p);
            chosen = builtin ? name : (p.is_absolute() ? p : d.folder / p).string();
        }
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) ImGui::CloseCurrentPopup();
    if (!chosen.empty()) {
        const std::filesystem::path p(chosen);
        if (p.has_parent_path()) remember_folder(state, p.parent_path());
        if (d.mode == FileDialog::Mode::open)  // replaces the scene: in the next input phase
            post_edit(registry, "open scene",
                      [chosen](ecs::Registry& r, EditorState& s) { open_scene_file(r, s, chosen); });
        else state.save_as = chosen, state.request_save = true;
        ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
}

void open_file_dialog(ecs::Registry& registry, EditorState& state, bool save) {
    FileDialog& d = file_dialog(registry);
    d.mode = save ? FileDialog::Mode::save : FileDialog::Mode::open;
    d.name[0] = '\0';
    std::error_code ec;
    browse(d, state.last_folder.empty() ? std::filesystem::current_path(ec)
                                        : std::filesystem::path(state.last_folder));
    if (!d.error.empty()) browse(d, std::filesystem::current_path(ec));  // the remembered folder is gone
    ImGui::OpenPopup(save ? "Save scene as" : "Open scene");
}

bool file_dialog_open() { return ImGui::IsPopupOpen("Open scene") || ImGui::IsPopupOpen("Save scene as"); }

}  // namespace sffd::editor
