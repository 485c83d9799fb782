// libFuzzer target: the SOG reader (gaussian::read_gaussians on a `.sog` or a folder's meta.json). The
// first byte picks what the input is: even, a `.sog` archive's raw bytes (the ZIP reader: end record,
// central directory, local headers, inflate, CRC-32); odd, a SOG folder, the rest split at each "@@@@"
// into meta.json and the images means_l, means_u, quats, scales, sh0, shN_centroids, shN_labels (.webp),
// so mutations reach meta.json, the image budgets, libwebp and the decoding without a ZIP's CRC in the
// way. Nothing may crash, hang or leak; an error must name the file; an accepted cloud must pass
// validate().
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"

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
    if (size < 1) return 0;
    const bool folder = (data[0] & 1) != 0;
    const std::string in(reinterpret_cast<const char*>(data) + 1, size - 1);
    static const std::string base = "/dev/shm/sffd_fuzz_sog_" + std::to_string(getpid());
    std::string path;
    if (!folder) {
        path = base + ".sog";
        if (!write(path, in.data(), in.size())) return 0;
    } else {
        static const char* const names[] = {"meta.json",          "means_l.webp",   "means_u.webp",
                                            "quats.webp",         "scales.webp",    "sh0.webp",
                                            "shN_centroids.webp", "shN_labels.webp"};
        std::error_code ec;
        std::filesystem::remove_all(base, ec);
        std::filesystem::create_directories(base, ec);
        std::size_t at = 0;
        for (const char* name : names) {
            const std::size_t end = std::min(in.find("@@@@", at), in.size());
            if (!write(base + "/" + name, in.data() + at, end - at)) return 0;
            at = std::min(end + 4, in.size());
        }
        path = base + "/meta.json";
    }
    auto g = gaussian::read_gaussians(path);
    if (!g && g.message().find(path) == std::string::npos) __builtin_trap();  // errors name the file
    if (g && !gaussian::validate(*g, path)) __builtin_trap();                 // accepted clouds are sane
    return 0;
}
