// libFuzzer target: the scene reader (glTF JSON or GLB through tinygltf, our accessor checks, the
// SFFD_scene extension) on arbitrary bytes. The first byte picks .gltf or .glb so both paths are fuzzed.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "runtime/assets/scene.h"
#include "runtime/core/log.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace sffd;
    static const bool quiet = [] {
        log::set_sink([](log::Level, std::string_view) {});
        return true;
    }();
    (void)quiet;
    if (size < 1) return 0;
    const bool glb = (data[0] & 1) != 0;
    const std::string path =
        "/dev/shm/sffd_fuzz_scene_" + std::to_string(getpid()) + (glb ? ".glb" : ".gltf");
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) return 0;
        std::fwrite(data + 1, 1, size - 1, f);
        std::fclose(f);
    }
    ecs::Registry registry;
    registry.set_resource<SceneHooks>();  // assets' own formats only
    if (auto s = load_scene(registry, path); !s && s.message().find(path) == std::string::npos)
        __builtin_trap();
    return 0;
}
