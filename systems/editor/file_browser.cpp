#include "systems/editor/file_browser.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"

namespace sffd::editor {

namespace fs = std::filesystem;

Result<std::vector<FolderEntry>> list_folder(const fs::path& folder,
                                             const std::vector<std::string>& extensions) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return make_error(folder.string() + ": not a folder");
    std::vector<FolderEntry> dirs, files;
    fs::directory_iterator it(folder, fs::directory_options::skip_permission_denied, ec);
    if (ec) return make_error(folder.string() + ": " + ec.message());
    for (const fs::directory_entry& e : it) {
        const std::string name = e.path().filename().string();
        if (name.empty() || name[0] == '.') continue;
        std::error_code ec2;
        if (e.is_directory(ec2)) {
            dirs.push_back({name, true});
            continue;
        }
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        if (extensions.empty() || std::find(extensions.begin(), extensions.end(), ext) != extensions.end())
            files.push_back({name, false});
    }
    const auto by_name = [](const FolderEntry& a, const FolderEntry& b) { return a.name < b.name; };
    std::sort(dirs.begin(), dirs.end(), by_name);
    std::sort(files.begin(), files.end(), by_name);
    std::vector<FolderEntry> out;
    const fs::path abs = fs::absolute(folder, ec);
    if (abs.has_relative_path()) out.push_back({"..", true});
    out.insert(out.end(), dirs.begin(), dirs.end());
    out.insert(out.end(), files.begin(), files.end());
    return out;
}

const std::vector<std::string>& openable_extensions() {
    static const std::vector<std::string> e = {".glb", ".gltf", ".ply", ".obj", ".off"};
    return e;
}

const std::vector<std::string>& saveable_extensions() {
    static const std::vector<std::string> e = {".glb", ".gltf"};
    return e;
}

std::string load_last_folder(const std::string& config_file) {
    if (config_file.empty()) return {};
    std::ifstream f(config_file);
    for (std::string line; std::getline(f, line);) {
        if (line.rfind("last_folder=", 0) != 0) continue;
        std::string folder = line.substr(12);
        std::error_code ec;
        return fs::is_directory(folder, ec) ? folder : std::string();
    }
    return {};
}

void save_last_folder(const std::string& config_file, const std::string& folder) {
    if (config_file.empty() || folder.empty()) return;
    if (Status st = write_file_atomic(config_file, "last_folder=" + folder + "\n"); !st)
        log::warn("editor: the last folder is not remembered: ", st.message());
}

}  // namespace sffd::editor
