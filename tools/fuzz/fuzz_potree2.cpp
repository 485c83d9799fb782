// libFuzzer target: the Potree 2 reader (assets::open_potree2, then read_potree2 and a level cut). The
// input is split at each "@@@@" into the folder's metadata.json, hierarchy.bin and octree.bin, so
// mutations reach the JSON checks, the chunk walk of the hierarchy (proxies, masks, byte ranges) and the
// point decoding without one file's damage hiding the others. Nothing may crash, hang or leak; an error
// must name a file of the folder; an accepted octree's full detail must hold "points" finite splats.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/core/log.h"

namespace {

bool write(const std::string& path, const char* data, std::size_t size) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const bool once = [] {
        log::set_sink([](log::Level, std::string_view) {});
        return true;
    }();
    (void)once;
    const std::string in(reinterpret_cast<const char*>(data), size);
    static const std::string base = "/dev/shm/sffd_fuzz_potree2_" + std::to_string(getpid());
    std::error_code ec;
    std::filesystem::remove_all(base, ec);
    std::filesystem::create_directories(base, ec);
    std::size_t at = 0;
    for (const char* name : {"metadata.json", "hierarchy.bin", "octree.bin"}) {
        const std::size_t end = std::min(in.find("@@@@", at), in.size());
        if (!write(base + "/" + name, in.data() + at, end - at)) return 0;
        at = std::min(end + 4, in.size());
    }
    auto o = assets::open_potree2(base + "/metadata.json");
    if (!o) {
        if (o.message().rfind(base, 0) != 0) __builtin_trap();  // errors name the file
        return 0;
    }
    auto full = assets::read_potree2(*o);
    if (!full) {
        if (full.message().rfind(base, 0) != 0) __builtin_trap();
        return 0;
    }
    if (full->size() != o->points) __builtin_trap();
    for (std::size_t i = 0; i < full->size(); ++i)
        if (!std::isfinite(full->axis_u[i].x + full->axis_v[i].y + full->normals[i].z)) __builtin_trap();
    auto cut = assets::read_potree2_nodes(*o, assets::potree2_level_cut(*o, 1));
    if (cut && cut->size() > full->size()) __builtin_trap();
    return 0;
}
