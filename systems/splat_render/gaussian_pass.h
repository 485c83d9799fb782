// The render system's 3D Gaussian pass: every entity with a GaussianCloud is drawn in the same
// frame and output target as the surface splats, after them.
//
//   reads   GaussianCloud (+ Transform), GpuGaussianStore (systems/gaussian/gpu_store.h: draw_buffer(),
//           sh_buffer(), frames; kept by residency_system and the deformation), the render system's
//           camera and targets (its depth: surface splats hide the Gaussians behind them)
//   writes  GaussianPassState (resource: programs, targets, per-cloud bounds)
//
// Per cloud: the gaussian GL renderer (systems/splat_render/gaussian_draw.h: projection, front-to-back order,
// instanced quads, or its tile renderer for a cloud covering too much of the image) into an RGBA32F
// accumulation target (premultiplied colour, coverage) whose quads are depth-tested against the surface
// splats' depth buffer (each quad at its centre's depth; no depth writes); then one full-screen pass
// composites it over the surface colour: C = G + (1 − A) S (the output target keeps straight colour and
// coverage, so the stored colour is C / coverage). Clouds are drawn nearest first (front-to-back blending
// across clouds is exact when they do not overlap in depth).
#pragma once

#include <cstdint>
#include <functional>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/gl.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/gaussian/components.h"
#include "systems/splat_render/gaussian_draw.h"
#include "systems/splat_render/splat_pack.h"

namespace sffd::render {

// The render system's frame, as the Gaussian pass sees it.
struct GaussianPassFrame {
    Camera camera;
    glm::dmat4 view{1.0}, projection{1.0};
    GLuint output_fbo = 0;  // colour attachment 0 (linear RGBA16F, straight colour + coverage), 1 (aux)
    GLuint color = 0, aux = 0, depth = 0;
    int width = 1, height = 1;                // the pixels drawn, from the targets' lower-left corner
    int target_width = 1, target_height = 1;  // the render system's targets (>= width, height: a reduced
                                              // preview; the pass's own targets follow them, not the frame)
    bool aux_outputs = false;                 // attachment 1 is written this frame (normal + view depth)
    // Preview quality (the editor while moving): Gaussians whose own footprint is under a pixel are not
    // drawn (GaussianView::min_footprint_px); the HQ (still) frame draws every Gaussian.
    bool preview = false;
    // RenderSettings::show_selection, show_weights: the point overlays asked for (runtime/gfx/point_marks.h).
    bool show_selection = false, show_weights = false;
};

// The footprint (3σ radius before the 0.3 px² low-pass) under which preview frames drop a Gaussian.
inline constexpr float kPreviewMinFootprintPx = 1.0f;

// Bounding sphere of a Gaussian cloud (cloud space): the centres' box grown by 3 × the largest scale.
// With `flags`, of the Gaussians that are neither hidden nor deleted only.
BoundingSphere gaussian_bounding_sphere(const GaussianCloud& cloud, const PointFlags* flags = nullptr);
// Cached per entity (recomputed when the cloud's change stamp moves): for scene_camera's framing.
BoundingSphere cached_gaussian_bounds(ecs::Registry& registry, ecs::Entity entity);

// Uploads what changed and draws every Gaussian cloud; returns the number of Gaussians submitted.
Result<std::uint32_t> gaussian_pass(ecs::Registry& registry, const GaussianPassFrame& frame);

// The last frame's blend per cloud (quads, or the tile renderer past gl_render.h's quad_coverage_budget)
// and the tile renderer's work: (tile, Gaussian) entries prepared, entries staged before the tiles'
// pixels saturated. Reads a counter back (a sync): for tests and diagnostics, not every frame.
struct GaussianPassStats {
    std::uint32_t quad_clouds = 0, tile_clouds = 0;
    std::uint64_t covered_pixels = 0;  // the clouds' clipped pixel boxes, summed (the quads' fragments)
    std::uint64_t tile_entries = 0, tile_entries_staged = 0;
    std::uint64_t quad_budget_images = 0;  // the budget the blend choice used (gl_render.h)
};
GaussianPassStats gaussian_pass_stats(ecs::Registry& registry);

// The pass's renderer (made on first use; needs the context current): benchmarks and tests choose its
// sort and blend paths and its stage timing there, and read its last draw's counters.
Result<GlRenderer*> gaussian_pass_renderer(ecs::Registry& registry);

// Frees the pass's GL objects (while the context is current).
void release_gaussian_pass(ecs::Registry& registry);

}  // namespace sffd::render
