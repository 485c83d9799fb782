// The resources the editor's window systems keep between frames, named so the engine's schedule can
// declare them (systems/engine/engine.cpp: editor.requests, editor.ui). Only the names are public: each
// is defined, and only ever touched, in the file that owns it.
//
//   ViewSession     view_app.cpp     run_view's options, ctrl+s target, screenshot count, drag log
//   FileDialog      file_dialog.cpp  the open / save dialog's folder, listing and typed name
//   LayoutState     panels.cpp       this frame's panel layout and the rectangles the panels got
//   PanelEntries    panels.cpp       values typed into the tool and lattice panels, not yet applied
//   FrameTimeShown  panels.cpp       the frame-time panel's numbers as of its last refresh
//   UiCacheState    ui_cache.cpp     the UI panel cache's texture and cached panels (sffd::editor)
#pragma once

namespace sffd::editor {

struct UiCacheState;

namespace detail {
struct ViewSession;
struct FileDialog;
struct LayoutState;
struct PanelEntries;
struct FrameTimeShown;
}  // namespace detail

}  // namespace sffd::editor
