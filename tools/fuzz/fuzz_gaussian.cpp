// libFuzzer targets for the Gaussian readers, one executable per format (SFFD_FUZZ_FORMAT picks it, so
// each target has its own corpus and dictionary): 3DGS PLY, .splat, .spz, KHR_gaussian_splatting glTF
// (the first byte picks .gltf or .glb), the Gaussian scene reader (load_scene on a glTF whose
// SFFD_scene extension holds Gaussian entries, plus the file loader on every format), the PlayCanvas
// compressed PLY (a .ply like the first, with its own seeds) and .ksplat. Nothing may crash,
// hang or leak; an error must name the file; an accepted cloud must pass validate().
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "runtime/assets/scene.h"
#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/gaussian_scene.h"

#ifndef SFFD_FUZZ_FORMAT
#error "SFFD_FUZZ_FORMAT (1 ply, 2 splat, 3 spz, 4 gltf, 5 scene, 6 compressed ply, 7 ksplat) must be defined"
#endif

namespace {

std::string write_input(const std::uint8_t* data, std::size_t size, const char* ext) {
    const std::string path = "/dev/shm/sffd_fuzz_gauss_" + std::to_string(getpid()) + ext;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return {};
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
    return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const bool once = [] {
        log::set_sink([](log::Level, std::string_view) {});
        return true;
    }();
    (void)once;
    const int format = SFFD_FUZZ_FORMAT;
    const char* ext = format == 1 || format == 6 ? ".ply"
                      : format == 2              ? ".splat"
                      : format == 3              ? ".spz"
                      : format == 7              ? ".ksplat"
                                                 : ".gltf";
    if (format == 4 || format == 5) {
        if (size < 1) return 0;
        ext = (data[0] & 1) ? ".glb" : ".gltf";
        ++data, --size;
    }
    std::string packed;
    if (format == 3) {
        // SPZ is one gzip stream: mutations of compressed bytes rarely get past inflate. The first byte
        // picks raw bytes (even: the gzip layer, CRC and length checks) or the rest gzipped here (odd:
        // the decoded header, budgets and attribute decoding).
        if (size < 1) return 0;
        const bool wrap = (data[0] & 1) != 0;
        ++data, --size;
        if (wrap) {
            z_stream z{};
            if (deflateInit2(&z, 1, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK) return 0;
            packed.resize(deflateBound(&z, uLong(size)) + 32);
            z.next_in = const_cast<Bytef*>(data);
            z.avail_in = uInt(size);
            z.next_out = reinterpret_cast<Bytef*>(packed.data());
            z.avail_out = uInt(packed.size());
            const int rc = deflate(&z, Z_FINISH);
            packed.resize(z.total_out);
            deflateEnd(&z);
            if (rc != Z_STREAM_END) return 0;
            data = reinterpret_cast<const std::uint8_t*>(packed.data());
            size = packed.size();
        }
    }
    const std::string path = write_input(data, size, ext);
    if (path.empty()) return 0;
    if (format != 5) {
        auto g = gaussian::read_gaussians(path);
        if (!g && g.message().find(path) == std::string::npos) __builtin_trap();  // errors name the file
        if (g && !gaussian::validate(*g, path)) __builtin_trap();                 // accepted clouds are sane
    } else {
        ecs::Registry registry;
        gaussian::register_gaussian_scene_hooks(SceneHooks::in(registry));
        if (auto s = load_scene(registry, path); !s && s.message().find(path) == std::string::npos)
            __builtin_trap();
    }
    return 0;
}
