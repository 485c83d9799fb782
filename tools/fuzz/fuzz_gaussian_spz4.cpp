// libFuzzer target: the SPZ version 4 reader (gaussian::read_gaussians on a `.spz`). The first byte picks
// what the input is: even, the file's raw bytes (header, extension records, table of contents, zstd
// frames and their checksums); odd, a 32-byte header followed by the decoded arrays, which the harness
// splits by the header's count and degree, compresses one zstd frame each and lists in a correct table,
// so mutations reach the attribute decoding and validation behind the container. Nothing may crash,
// hang or leak; an error must name the file; an accepted cloud must pass validate().
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>

#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"

namespace {

void put64(std::string& s, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}

// Header + arrays -> a version-4 container with a table that matches what is there.
std::string wrap(const std::uint8_t* data, std::size_t size) {
    if (size < 32) return std::string(reinterpret_cast<const char*>(data), size);
    std::string out(reinterpret_cast<const char*>(data), 32);
    out[4] = 4, out[5] = out[6] = out[7] = 0;
    out[16] = 32, out[17] = out[18] = out[19] = 0;
    const std::uint64_t n = std::uint64_t(data[8]) | std::uint64_t(data[9]) << 8;  // small counts only
    out[8] = char(n & 0xff), out[9] = char(n >> 8), out[10] = out[11] = 0;
    const int degree = data[12] % 5;
    out[12] = char(degree);
    const std::uint64_t rest = std::uint64_t((degree + 1) * (degree + 1) - 1) * 3;
    const std::uint64_t sizes[6] = {n * 9, n, n * 3, n * 3, n * 4, n * rest};
    std::string table, frames;
    std::size_t at = 32;
    int streams = 0;
    for (std::uint64_t want : sizes) {
        if (want == 0) continue;
        std::string raw(reinterpret_cast<const char*>(data) + std::min(at, size),
                        std::min<std::size_t>(std::size_t(want), size - std::min(at, size)));
        at += std::size_t(want);
        raw.resize(std::size_t(want), '\0');  // short inputs are padded, so the count always holds
        std::string z(ZSTD_compressBound(raw.size()), '\0');
        z.resize(ZSTD_compress(z.data(), z.size(), raw.data(), raw.size(), 1));
        put64(table, z.size()), put64(table, raw.size());
        frames += z;
        ++streams;
    }
    out[15] = char(streams);
    return out + table + frames;
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
    const bool wrapped = (data[0] & 1) != 0;
    ++data, --size;
    const std::string bytes =
        wrapped ? wrap(data, size) : std::string(reinterpret_cast<const char*>(data), size);
    static const std::string path = "/dev/shm/sffd_fuzz_spz4_" + std::to_string(getpid()) + ".spz";
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) return 0;
        std::fwrite(bytes.data(), 1, bytes.size(), f);
        std::fclose(f);
    }
    auto g = gaussian::read_gaussians(path);
    if (!g && g.message().find(path) == std::string::npos) __builtin_trap();  // errors name the file
    if (g && !gaussian::validate(*g, path)) __builtin_trap();                 // accepted clouds are sane
    return 0;
}
