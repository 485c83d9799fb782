// libFuzzer target: the FFD engineer's lattice JSON reader (systems/ffd/lattice_io.h) on arbitrary text.
// Accepted lattices must be internally consistent (control point arrays of the declared size, finite
// coordinates of at most 1e30).
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "systems/ffd/lattice_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    auto lattice = ffd::parse_lattice_json(text, "fuzz.json");
    if (lattice) {
        if (lattice->rest.size() != lattice->size() || lattice->current.size() != lattice->size())
            __builtin_trap();
        // Accepted control points are finite and at most 1e30 in magnitude (1e308 once deformed to inf).
        for (const auto* grid : {&lattice->rest, &lattice->current})
            for (const auto& p : *grid)
                for (int a = 0; a < 3; ++a)
                    if (!(std::abs(p[a]) <= 1e30)) __builtin_trap();
    } else if (lattice.message().find("fuzz.json") == std::string::npos) {
        __builtin_trap();
    }
    return 0;
}
