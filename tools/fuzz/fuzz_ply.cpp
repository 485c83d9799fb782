// libFuzzer target: the streaming PLY reader (header parsing, every element in small chunks) and the
// PLY importer (validation, faces, colours) on arbitrary bytes. Nothing may crash, hang or leak; bad
// input must come back as an error naming the file.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const std::string path = "/dev/shm/sffd_fuzz_ply_" + std::to_string(getpid()) + ".ply";
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) return 0;
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    std::size_t header_bytes = 0;
    (void)ply::parse_header(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz",
                            header_bytes);
    if (auto r = ply::Reader::open(path)) {
        ply::Chunk chunk;
        while (r->current_element() < r->header().elements.size()) {
            auto n = r->read_rows(7, chunk);
            if (!n) {
                if (n.message().find(path) == std::string::npos)
                    __builtin_trap();  // errors must name the file
                break;
            }
        }
    } else if (r.message().find(path) == std::string::npos) {
        __builtin_trap();
    }
    auto g = assets::read_ply_geometry(path);
    if (!g && g.message().find(path) == std::string::npos) __builtin_trap();
    return 0;
}
