// libFuzzer target: the PlayCanvas compressed PLY reader (gaussian::read_compressed_ply through
// read_gaussians, so the 3DGS PLY dispatch too) on arbitrary bytes. Nothing may crash, hang or leak;
// bad input must come back as an error naming the file, and an accepted cloud must pass validate().
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "systems/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const std::string path = "/dev/shm/sffd_fuzz_cply_" + std::to_string(getpid()) + ".ply";
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) return 0;
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    auto g = gaussian::read_gaussians(path);
    if (!g) {
        if (g.message().find(path) == std::string::npos) __builtin_trap();  // errors must name the file
    } else if (!gaussian::validate(*g, path)) {
        __builtin_trap();  // what the reader accepts, the rest of the engine must accept
    }
    return 0;
}
