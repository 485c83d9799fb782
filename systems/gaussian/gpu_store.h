// GpuGaussianStore: registry resource holding every Gaussian cloud on the GPU. The Gaussian kind of the
// shared residency (runtime/gfx/residency.h: rest / deformed_gpu / deformed_cpu, written once each):
//   - residency_system (phase `residency`) uploads the authored GaussianCloud into `rest` (GpuGaussian
//     layout, shaders/gaussian/gaussian_layout.h) and `sh` with upload_rest() when its change stamp moves;
//   - gaussian_deform_system's GPU pass reads `rest`/`sh` and writes `deformed` (centres, rotations,
//     scales; opacity carried) and the SH data its ShMode needs (state deformed_gpu); its CPU path
//     uploads its output with upload_cpu_deformed() (state deformed_cpu);
//   - the renderer and picking read draw_buffer(), sh_buffer() and, when has_frames(), `frames`.
// What differs from surface splats is only the data: SH coefficients, and how the deformation carried
// them (sh_source).
// Owned by the registry (a resource), so GL names live exactly as long as the context's registry.
#pragma once

#include <cstdint>
#include <unordered_map>

#include "runtime/ecs/entity.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/residency.h"

namespace sffd::gaussian {

// How the deformed cloud's colour is evaluated (meaningful only while deformed).
enum class ShSource : std::uint8_t {
    authored,  // the authored `sh` (degree 0, or no rotation asked for)
    rotated,   // `deformed_sh`: coefficients rotated by the deformation (ShMode::rotate_coefficients)
    frames,    // the authored `sh` evaluated in `frames` (vec4[3] per Gaussian, ShMode::rotate_view)
};

struct GpuGaussians : gfx::ResidentCloud {
    gfx::Buffer sh;           // float[count * K * 3], GaussianCloud::sh layout, authored
    gfx::Buffer deformed_sh;  // float[count * K * 3], read when sh_source == rotated
    gfx::Buffer frames;       // vec4[3 * count], read when sh_source == frames
    int sh_degree = 0;
    // Degree of `deformed_sh` in state preview_cpu: a moving preview carries only the DC term (0), so the
    // subset's colour costs no SH rotation, upload or evaluation; the still frame draws `sh_degree`.
    int preview_sh_degree = 0;
    ShSource sh_source = ShSource::authored;

    bool has_frames() const { return is_deformed() && sh_source == ShSource::frames; }
    // The SH degree of what sh_buffer() holds now.
    int drawn_sh_degree() const {
        return state == gfx::Residency::preview_cpu ? preview_sh_degree : sh_degree;
    }
    GLuint sh_buffer() const {
        return is_deformed() && sh_source == ShSource::rotated ? deformed_sh.id() : sh.id();
    }
};

struct GpuGaussianStore {
    std::unordered_map<ecs::Entity, GpuGaussians> clouds;
};

}  // namespace sffd::gaussian
