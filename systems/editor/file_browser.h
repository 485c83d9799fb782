// The editor's file browser (open / save dialogs; no package in Debian 12 provides one for ImGui 1.86):
// a folder listing with ".." to go up, sub-folders first, files filtered by extension. The listing and
// the remembered last folder are plain functions (tested on CPU); the ImGui dialog is in panels.cpp.
// The last folder is kept in $XDG_CONFIG_HOME/splatffd/editor.ini (`last_folder=PATH`, the folder of
// view_app's user_config_file) so saves, screenshots and the next dialog start there.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::editor {

struct FolderEntry {
    std::string name;  // ".." for the parent
    bool folder = false;
};

// `folder`'s entries: ".." (unless at the root), sub-folders, then files whose extension (lower case,
// with the dot) is in `extensions` (all files when empty), each group sorted by name; hidden entries
// (leading '.') are left out. Error "folder: problem" when it cannot be listed.
Result<std::vector<FolderEntry>> list_folder(const std::filesystem::path& folder,
                                             const std::vector<std::string>& extensions);

// Extensions the editor opens (scenes and point clouds) and saves (scenes).
const std::vector<std::string>& openable_extensions();
const std::vector<std::string>& saveable_extensions();

// The remembered folder ("" when none, or when it no longer exists) and remembering one (best effort:
// a warning, not an error, when the config folder cannot be written). `config_file` is the ini's path.
std::string load_last_folder(const std::string& config_file);
void save_last_folder(const std::string& config_file, const std::string& folder);

}  // namespace sffd::editor
