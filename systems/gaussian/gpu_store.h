// GpuGaussianStore: registry resource holding every Gaussian cloud on the GPU, the Gaussian twin of
// gfx::GpuSplatStore (runtime/gfx/splat_store.h). Skinning-style data flow, as for surface splats:
//   - whoever first needs a cloud on the GPU (the render system, or the GPU deformation) uploads the
//     authored GaussianCloud into `rest` (GpuGaussian layout, shaders/gaussian/gaussian_layout.h) and
//     `sh` when the cloud's change stamp moves (`rest_version`);
//   - the GPU Gaussian deformation reads `rest`/`sh` and writes `deformed` (centres, rotations, scales;
//     opacity carried) and, in ShMode::rotate_view, `frames` (vec4[3] per Gaussian: the polar rotation of
//     J), once per change of the cloud or its lattices, and bumps `deformed_version`;
//   - the renderer reads draw_buffer() (and `frames` when has_frames): the CPU deformation's output
//     (DeformedGaussians) is uploaded into `deformed` by the render system when the GPU did not write it.
// Owned by the registry (a resource), so GL names live exactly as long as the context's registry.
#pragma once

#include <cstdint>
#include <unordered_map>

#include "runtime/ecs/entity.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::gaussian {

struct GpuGaussians {
    gfx::Buffer rest;                    // GpuGaussian[count], authored data
    gfx::Buffer sh;                      // float[count * K * 3], GaussianCloud::sh layout, authored
    gfx::Buffer deformed;                // GpuGaussian[count], deformed (GPU pass or uploaded CPU output)
    gfx::Buffer deformed_sh;             // float[count * K * 3] when the deformation rotated the coefficients
    gfx::Buffer frames;                  // vec4[3 * count]: SH frames (rotate_view), when has_frames
    std::uint32_t count = 0;
    int sh_degree = 0;
    std::uint64_t rest_version = 0;      // GaussianCloud change stamp that `rest`/`sh` hold
    std::uint64_t deformed_version = 0;  // bumped whenever `deformed` is rewritten
    bool has_deformed = false;           // `deformed` is valid and should be drawn
    bool has_deformed_sh = false;        // `deformed_sh` is valid and should be read instead of `sh`
    bool has_frames = false;             // `frames` is valid and the SH are evaluated in these frames
    bool deformed_on_gpu = false;        // the GPU pass wrote `deformed` (no CPU copy exists)

    GLuint draw_buffer() const { return has_deformed ? deformed.id() : rest.id(); }
    GLuint sh_buffer() const { return has_deformed_sh ? deformed_sh.id() : sh.id(); }
};

struct GpuGaussianStore {
    std::unordered_map<ecs::Entity, GpuGaussians> clouds;
};

}  // namespace sffd::gaussian
