#include "systems/ffd/lattice_io.h"

#include <nlohmann/json.hpp>

#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/scene/lattice_json.h"

namespace sffd::ffd {

using nlohmann::json;

Result<Lattice> parse_lattice_json(std::string_view text, const std::string& name) {
    if (Status s = check_json_depth(text, name); !s) return s.error();
    json j;
    try {
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {  // parse errors, number overflow (1e999)
        return make_error(name + ": malformed JSON (" + std::string(e.what()) + ")");
    }
    return lattice_from_json(j, name);
}

Result<Lattice> load_lattice(const std::filesystem::path& path) {
    // Regular files only (--lattice /dev/zero or a FIFO would read forever), within the JSON budget.
    auto text = read_file(path, kMaxJsonFileBytes);
    if (!text) return text.error();
    return parse_lattice_json(*text, path.string());
}

Status save_lattice(const std::filesystem::path& path, const Lattice& l) {
    if (Status s = validate_lattice(l, path.string()); !s) return s;
    return write_file_atomic(path, lattice_to_json(l).dump(1) + "\n");
}

}  // namespace sffd::ffd
