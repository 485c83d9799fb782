// libFuzzer target: the streamed SOG reader (lod::open_streamed_sog on a lod-meta.json, then every level
// read and the hierarchy's cut selected). A small real hierarchy (3,000 procedural Gaussians, 2 levels,
// several units) is built once in a scratch folder, so the units, their meta.json and images exist; the
// first byte picks what the input replaces: even, lod-meta.json alone (the tree, levels, counts, runs,
// filenames: confinement, run tiling, the budgets); odd, lod-meta.json and, after a "@@@@", the first unit's
// meta.json (its count, image names, the texel-per-byte ratio; read_sog on what passes). Nothing may crash,
// hang or leak; a refusal must name a file of the folder; an accepted hierarchy's levels must hold its
// counts, and a selected cut must stay within its budget.
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/core/log.h"
#include "systems/lod/cut.h"

namespace {

namespace fs = std::filesystem;

bool write(const fs::path& path, const char* data, std::size_t size) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const fs::path base = fs::path("/dev/shm") / ("sffd_fuzz_lod_" + std::to_string(getpid()));
    static const std::string unit_meta = [] {
        log::set_sink([](log::Level, std::string_view) {});
        std::error_code ec;
        fs::remove_all(base, ec);
        lod::LodBuildOptions o;
        o.levels = 2, o.chunk_count = 1024;
        if (!lod::build_streamed_sog(lod::synthetic_gaussian_source(3000), base / "lod-meta.json", o))
            __builtin_trap();
        std::FILE* f = std::fopen((base / "0_0" / "meta.json").c_str(), "rb");
        std::string text;
        char buf[4096];
        for (std::size_t n; f && (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
        if (f) std::fclose(f);
        return text;
    }();
    if (size < 1) return 0;
    const std::string in(reinterpret_cast<const char*>(data) + 1, size - 1);
    const fs::path meta = base / "lod-meta.json", unit = base / "0_0" / "meta.json";
    const bool with_unit = (data[0] & 1) != 0;
    const std::size_t cut = with_unit ? std::min(in.find("@@@@"), in.size()) : in.size();
    if (!write(meta, in.data(), cut)) return 0;
    if (with_unit) {
        const std::size_t at = std::min(cut + 4, in.size());
        if (!write(unit, in.data() + at, in.size() - at)) return 0;
    }
    auto s = lod::open_streamed_sog(meta);
    if (!s && s.message().find(base.string()) == std::string::npos) __builtin_trap();  // errors name a file
    if (s) {
        for (int l = 0; l < s->levels; ++l) {
            auto g = lod::read_level(*s, l);
            if (g && g->size() != s->counts[std::size_t(l)]) __builtin_trap();
            if (!g && g.message().find(base.string()) == std::string::npos) __builtin_trap();
        }
        (void)lod::describe(*s);
        const lod::CutTree t = lod::cut_tree(*s);
        lod::CutView v;
        v.camera.eye = glm::dvec3(0.0, 0.0, 30.0);
        const lod::Cut c = lod::select_cut(t, v, {1.0, 5000, true});
        if (!t.nodes.empty() && c.splats > std::max<std::uint64_t>(5000, t.nodes[t.root].splats))
            __builtin_trap();
    }
    if (with_unit && !write(unit, unit_meta.data(), unit_meta.size())) return 0;  // the next input's unit
    return 0;
}
