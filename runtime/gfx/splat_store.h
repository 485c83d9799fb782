// GpuSplatStore: registry resource holding every point cloud's splats on the GPU, in the GpuSplat layout
// (shaders/common/bindings.h). Skinning-style data flow:
//   - the render system (or whoever first needs it) uploads the authored SplatCloud into `rest` when the
//     cloud's change stamp moves;
//   - the FFD system's compute pass reads `rest` and writes `deformed` once per change of the cloud or
//     its lattices, and stamps `deformed_version`;
//   - every render pass reads draw_buffer(): `deformed` when the cloud has deformers, `rest` otherwise.
// Owned by the registry (a resource), so GL names live exactly as long as the context's registry.
#pragma once

#include <cstdint>
#include <unordered_map>

#include "runtime/ecs/entity.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::gfx {

struct GpuSplats {
    Buffer rest;                       // GpuSplat[count], authored data
    Buffer deformed;                   // GpuSplat[count], written by the FFD compute pass
    std::uint32_t count = 0;
    std::uint64_t rest_version = 0;    // SplatCloud change stamp that `rest` holds
    std::uint64_t deformed_version = 0;  // bumped whenever `deformed` is rewritten
    bool has_deformed = false;         // `deformed` is valid and should be drawn

    GLuint draw_buffer() const { return has_deformed ? deformed.id() : rest.id(); }
};

struct GpuSplatStore {
    std::unordered_map<ecs::Entity, GpuSplats> clouds;
};

}  // namespace sffd::gfx
