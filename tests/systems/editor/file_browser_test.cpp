// The editor's file browser: the folder listing (".." first, folders, files filtered by extension, hidden
// entries left out, a clear error for a missing folder), the remembered last folder, and the dialog in a
// headless ImGui context: it opens in the last folder and Escape closes it.
#include "systems/editor/file_browser.h"

#include <fstream>

#include <gtest/gtest.h>
#include <imgui.h>

#include "runtime/scene/components.h"
#include "systems/editor/editor_state.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/panels.h"

using namespace sffd;
using namespace sffd::editor;
namespace fs = std::filesystem;

namespace {

struct TempDir {
    fs::path path = fs::temp_directory_path() / ("sffd_file_browser_" + std::to_string(::getpid()));
    TempDir() { fs::create_directories(path); }
    ~TempDir() { fs::remove_all(path); }
    void touch(const std::string& name) { std::ofstream(path / name) << "x"; }
};

std::vector<std::string> names(const std::vector<FolderEntry>& entries) {
    std::vector<std::string> out;
    for (const FolderEntry& e : entries) out.push_back((e.folder ? "/" : "") + e.name);
    return out;
}

}  // namespace

TEST(FileBrowser, ListsParentFoldersThenFilteredFiles) {
    TempDir dir;
    fs::create_directories(dir.path / "zeta");
    fs::create_directories(dir.path / "alpha");
    fs::create_directories(dir.path / ".hidden");
    for (const char* f : {"b.glb", "a.PLY", "notes.txt", "c.gltf", ".secret.glb"}) dir.touch(f);
    auto all = list_folder(dir.path, {});
    ASSERT_TRUE(all) << all.message();
    EXPECT_EQ(names(*all),
              (std::vector<std::string>{"/..", "/alpha", "/zeta", "a.PLY", "b.glb", "c.gltf", "notes.txt"}));
    auto open = list_folder(dir.path, openable_extensions());
    ASSERT_TRUE(open);
    EXPECT_EQ(names(*open), (std::vector<std::string>{"/..", "/alpha", "/zeta", "a.PLY", "b.glb", "c.gltf"}));
    auto save = list_folder(dir.path, saveable_extensions());
    ASSERT_TRUE(save);
    EXPECT_EQ(names(*save), (std::vector<std::string>{"/..", "/alpha", "/zeta", "b.glb", "c.gltf"}));
    auto root = list_folder("/", {});
    ASSERT_TRUE(root);
    ASSERT_FALSE(root->empty());
    EXPECT_NE(root->front().name, "..") << "no parent above the root";
    auto missing = list_folder(dir.path / "nope", {});
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.message(), (dir.path / "nope").string() + ": not a folder");
}

TEST(FileBrowser, LastFolderIsRemembered) {
    TempDir dir;
    const std::string ini = (dir.path / "editor.ini").string();
    EXPECT_EQ(load_last_folder(ini), "");
    fs::create_directories(dir.path / "scans");
    save_last_folder(ini, (dir.path / "scans").string());
    EXPECT_EQ(load_last_folder(ini), (dir.path / "scans").string());
    fs::remove_all(dir.path / "scans");
    EXPECT_EQ(load_last_folder(ini), "") << "a folder that is gone is forgotten";
    save_last_folder("", "/tmp");  // no config file: nothing happens
}

TEST(FileBrowser, DialogOpensAndEscapeClosesIt) {
    ImGuiContext* ctx = ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    unsigned char* px = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&px, &w, &h);
    io.DisplaySize = ImVec2(1280, 720);
    io.DeltaTime = 1.0f / 60.0f;
    io.KeyMap[ImGuiKey_Escape] = 256;  // what a backend maps (imgui 1.86 legacy key array)
    ecs::Registry reg;
    EditorState& state = reg.set_resource<EditorState>();
    state.viewport = {1280, 720};
    const auto frame = [&](bool escape) {
        io.KeysDown[256] = escape;
        ImGui::NewFrame();
        draw_panels(reg, FrameContext{});
        const bool open = file_dialog_open();
        ImGui::Render();
        return open;
    };
    frame(false);
    ImGui::NewFrame();
    open_file_dialog(reg, state, false);
    draw_panels(reg, FrameContext{});
    ImGui::Render();
    EXPECT_TRUE(frame(false));
    EXPECT_TRUE(frame(false));
    EXPECT_FALSE(frame(true)) << "Escape closes the dialog";
    EXPECT_FALSE(frame(false));
    // ctrl+o (through the input system) opens it again.
    InputEvent ctrl_o;
    ctrl_o.kind = InputKind::key;
    ctrl_o.key = "o";
    ctrl_o.modifiers = mods::ctrl;
    reg.emplace<Camera>(reg.create());
    setup_editor(reg, state.viewport);
    state.events = {ctrl_o};
    editor_input_system(reg, FrameContext{});
    EXPECT_TRUE(state.request_open_dialog);
    frame(false);
    EXPECT_TRUE(frame(false));
    EXPECT_FALSE(state.request_open_dialog);
    ImGui::DestroyContext(ctx);
}
