// Splat render system (rendering phase): surface splatting of every SplatCloud in the registry, then every
// GaussianCloud (3D Gaussians, gaussian_pass.h) over them, in the same frame.
//
//   reads   SplatCloud (+ Transform), Camera, DirectionalLight, AmbientLight, RenderSettings (resource),
//           GpuSplatStore (draw_buffer(), state, CPU mirrors; kept by residency_system and ffd_system,
//           runtime/gfx/splat_store.h), DeformedSplats bounds; GaussianCloud (+ Transform),
//           GpuGaussianStore (gaussian_pass.h). Never uploads a cloud: a cloud not resident is not drawn.
//   writes  SplatRenderState (resource: its GL programs, per-cloud cull buffers and textures, the
//           offscreen targets), RenderStats
//
// HQ (Botsch et al. 2005): cull + compact (a compute pass, or cpu_cull.h on a software rasterizer) ->
// visibility (depth, eps-offset ray-cast ellipses) -> attribute (additive RGBA32F: w*colour, w; w*normal,
// w*depth) -> normalise + deferred Blinn-Phong. Preview: one pass of opaque ray-cast ellipses. Output: a
// linear RGBA16F colour target plus an RGBA32F target with world normal and view-axis depth;
// capture_frame() reads both back into a FrameImage (PNG/EXR writers in
// image_io.h). A scene without a Camera is framed automatically; without lights it gets a default one.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/app/frame_loop.h"
#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/gl.h"
#include "systems/splat_render/image_io.h"

namespace sffd::render {

enum class Quality : std::uint8_t { hq, preview };

// Where culling and compaction run. automatic: on the CPU (cpu_cull.h) when the context is a software
// rasterizer and the cloud's current splats are on the CPU (not deformed, or deformed by the FFD system's
// CPU path); the compute pass otherwise. compute / cpu force one (cpu still falls back to compute for a
// cloud deformed on the GPU: its splats exist only there).
enum class CullPath : std::uint8_t { automatic, compute, cpu };

// Who rasterises the HQ passes' sprites (compute_raster.h). raster: point sprites and quads through the
// fixed-function pipeline. compute: sprites up to SFFD_RASTER_MAX_SPRITE pixels by compute shaders with
// 32-bit atomics, larger ones and quads by the rasteriser in the same frame (hybrid). automatic: compute when
// the splats are on average small on screen: at most 6 px on a hardware GPU, 1.8 px on a software rasterizer
// (llvmpipe's measured break-even, compute_raster.h). Preview and frames whose clouds differ in material
// always rasterise.
enum class RasterPath : std::uint8_t { automatic, raster, compute };

// Who rasterises the sprites of the clouds the CPU cull took (it holds their records). raster: point
// sprites through the fixed-function pipeline. cpu: the CPU (cpu_raster.h), with the same ray casts and
// texture lookups as the programs: a preview frame's sprites (colour, depth, aux), and an HQ frame's
// visibility pass (depth) unless the compute rasteriser takes it; the images are uploaded into the targets
// and GL draws the rest (quads, compute-culled clouds, the HQ attribute and shade passes) over them.
// automatic: cpu on a software rasterizer, raster on a hardware GPU.
enum class SpritePath : std::uint8_t { automatic, raster, cpu };

// Registry resource; zero-initialised fields are the defaults.
struct RenderSettings {
    Quality quality = Quality::hq;
    int width = 1280;
    int height = 720;
    std::optional<glm::vec3> background;  // linear RGB for display; captured frames keep alpha 0 there
    bool culling = true;                  // back-face + frustum culling (off: classify only)
    CullPath cull_path = CullPath::automatic;
    RasterPath raster_path = RasterPath::automatic;
    SpritePath sprite_path = SpritePath::automatic;
    float visibility_epsilon = 1.0f;  // HQ depth offset along the view ray, in units of each splat's radius
    bool time_passes = false;         // glFinish after each pass and record CPU times in RenderStats
    bool aux_outputs = false;         // also write the normal + depth target (EXR Z, N; capture_frame's
                                      // depth/normal); off for interaction: it costs the preview ~10%
    // Preview frames render width/d x height/d pixels (d = preview_divider, 1..8) into the corner of the
    // full-size targets, and everything that reads the frame (the display copy, capture_frame, overlays
    // through output_frame_size) scales it up, nearest: 1/d^2 of the fill for interaction where fill is
    // what a frame costs (a CPU rasteriser). HQ frames always render at full size.
    int preview_divider = 1;
    // A reduced preview (preview_divider > 1, CPU cull) colours each textured splat once, by a lookup at
    // its centre at the mip level its footprint picks, instead of per pixel: at that size a splat spans
    // a few pixels and about as many texels of its level, and on a CPU rasteriser the per-pixel lookups
    // were a fifth of the frame. Full-size previews and HQ frames always filter per pixel.
    bool reduced_preview_flat_texture = true;
    // Point overlays (runtime/gfx/point_marks.h), surface splats and Gaussians alike, on every path:
    // selected points (PointFlags kPointSelected, not hidden or deleted) drawn half way to yellow; every
    // point in the colour of its PointWeights value (blue 0, green 0.5, red 1; 1 without weights), lit as
    // its own colour would be. Either draws a textured surface cloud flat (each splat in its centre's
    // texel). Off by default (`render` shows the scene as it is); the editor turns the selection on.
    // Hidden and deleted points are never drawn, whatever these say.
    bool show_selection = false;
    bool show_weights = false;
};

// Registry resource (optional), kept by an application whose own UI covers part of the window (the
// editor's panels): the rectangle where the frame is seen, in the UI's window units from the top left, of
// a window window_width x window_height in those units (scaled to the framebuffer). display_system fills
// the rest of the window with the background and copies only this rectangle: the UI draws over the rest.
struct DisplayViewport {
    float x = 0, y = 0, width = 0, height = 0;
    float window_width = 0, window_height = 0;
};
// The framebuffer pixels (x, y, width, height; GL's lower-left origin) of a `width` x `height` window that
// `v` covers: every pixel it touches, clipped to the window; the whole window when v has no window size.
glm::ivec4 display_viewport_pixels(const DisplayViewport& v, int width, int height);

// Registry resource written by render_system; pass times only when RenderSettings::time_passes.
// The visible counts come from the GPU without waiting for it: they are those of frame `counts_frame`, the
// newest frame whose read-back has landed (with time_passes: this frame; otherwise usually a frame or two
// back); counts_valid is false until the first one lands.
struct RenderStats {
    std::uint64_t frame = 0;
    std::uint32_t splats = 0;          // splats submitted (all clouds), this frame
    std::uint32_t visible_points = 0;  // after culling, drawn as sprites (all clouds), frame counts_frame
    std::uint32_t visible_quads = 0;   // after culling, drawn as quads (all clouds), frame counts_frame
    std::uint64_t counts_frame = 0;
    bool counts_valid = false;
    std::uint32_t cpu_culled_clouds = 0;        // clouds culled on the CPU this frame (CullPath)
    std::uint32_t compute_culled_clouds = 0;    // clouds culled by the compute pass this frame
    std::uint32_t compute_rastered_clouds = 0;  // clouds whose HQ sprites went through the compute rasteriser
    std::uint32_t raster_sprites = 0;  // of those clouds' sprites, the ones too large for it, drawn by the
                                       // rasteriser (frame counts_frame; included in visible_points)
    std::uint32_t cpu_splat_passes =
        0;                          // loops over a cloud's splats on the CPU this frame (uploads of
                                    // changed clouds, their bounds, the CPU cull): 0 in a GPU-resident frame
    std::uint32_t cpu_sprites = 0;  // sprites the CPU rasterised this frame (SpritePath): preview or HQ
                                    // visibility
    bool cpu_attribute = false;     // the HQ attribute pass ran on the CPU too (SpritePath)
    std::uint32_t gaussians = 0;    // 3D Gaussians submitted (all GaussianClouds), this frame
    double cull_ms = 0, visibility_ms = 0, attribute_ms = 0, shade_ms = 0, preview_ms = 0, total_ms = 0;
    double gaussian_ms = 0;  // the Gaussian pass (gaussian_pass.h), with time_passes
};

// Compiles the programs and creates the state resource (SplatRenderState). Needs a current GL 4.5
// context. render_system calls it on first use; call it yourself to get shader errors as a Status.
Status init_render_state(ecs::Registry& registry);

void render_system(ecs::Registry& registry, const FrameContext& frame);

// Display copy for a window (present phase, after every overlay has drawn into the output target): the
// linear colour target over the background, sRGB-encoded into an RGBA8 texture, published as the
// app::PresentSource that present_blit_system shows; only inside the DisplayViewport when there is one.
// Headless contexts skip it.
void display_system(ecs::Registry& registry, const FrameContext& frame);

// Reads the last rendered frame back (call after render_system, same context). Depth and normals only
// when RenderSettings::aux_outputs was on for that frame (else +inf and 0).
Result<FrameImage> capture_frame(ecs::Registry& registry);

// The offscreen framebuffer holding the last frame (colour attachment 0 linear RGBA16F, attachment 1
// normal+depth, depth attachment), for overlays and presenting; 0 before the first frame.
GLuint output_framebuffer(const ecs::Registry& registry);
// The pixels of those targets the last frame covers, from their lower-left corner: the targets' size, or
// less for a preview frame with RenderSettings::preview_divider > 1. Overlays draw into this rectangle.
glm::ivec2 output_frame_size(const ecs::Registry& registry);
// The pixels of that frame that may differ from the cleared background (x, y, width, height from its
// lower-left corner, inside output_frame_size()): the squares of the splats' sprites when the CPU culled
// every cloud and nothing else was drawn, else the whole frame. A system that draws into
// output_framebuffer() after the render system adds its own pixels (include_drawn_pixels), since the
// display copies only this part of the frame into the window and clears the rest to the background: on a
// CPU rasteriser the copy costs per pixel, and a model seldom fills the view.
glm::ivec4 drawn_pixels(const ecs::Registry& registry);
void include_drawn_pixels(ecs::Registry& registry, const glm::ivec4& pixels);
// The output colour target as the window shows it before the display copy (straight linear colour, the
// overlays included, alpha > 0 where anything was drawn), top row first, scaled up to the targets' size.
Result<std::vector<glm::vec4>> capture_output_color(ecs::Registry& registry);

// Frees the state's GL objects (while the context is current): erases the SplatRenderState resource.
void release_render_state(ecs::Registry& registry);

}  // namespace sffd::render
