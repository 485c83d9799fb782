// Internals of the splat render system shared by its source files (state resource, per-frame plan, pass
// entry points). Not a public header: only systems/splat_render's own sources include it.
#pragma once

#include "systems/splat_render/splat_render.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_inverse.hpp>

#include "runtime/app/app.h"
#include "runtime/core/log.h"
#include "runtime/ecs/signal.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/radix_sort.h"
#include "runtime/gfx/shader.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"
#include "shaders/splat_render/compute_raster.h"
#include "shaders/splat_render/frame_block.h"
#include "shaders/splat_render/splat_record.h"
#include "systems/ffd/components.h"
#include "runtime/app/pass_timer.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/compute_raster.h"
#include "systems/splat_render/cpu_cull.h"
#include "systems/splat_render/cpu_raster.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/storage_limits.h"

namespace sffd::render::detail {

// Three DrawArraysIndirectCommands per cloud: sprites {n, 1, 0, 0}, quads {6, n, 0, 0}, and a textured
// cloud's flat-coloured sprites {n, 1, capacity, 0} (CPU cull only; the compute cull leaves n = 0).
constexpr std::size_t draw_command_words = 12;

// The renderer's per-cloud objects (the splats and textures themselves live in GpuSplatStore): a component
// on the cloud entity, made by sync_clouds for a resident cloud and removed with its SplatCloud
// (SplatRenderState::cloud_gone) or when the cloud is no longer resident.
struct CloudGpu {
    gfx::Buffer records;   // SplatRecord[2 capacity]: visible sprites, prepared by the cull pass; from
                           // `capacity` on, a textured cloud's sprites of one texture colour (CPU cull)
    gfx::Buffer quads;     // uint[capacity]: indices of visible splats drawn as quads
    gfx::Buffer commands;  // three DrawArraysIndirectCommands: sprites, quads, flat-coloured sprites
    gfx::Buffer
        cull_groups;  // uint[2 G + 1]: the compute cull's per-group counts, then their scan (cull.comp)
    std::uint32_t cull_group_capacity = 0;
    gfx::Buffer frame_ubo;  // FrameBlock for this cloud
    std::uint32_t capacity = 0;
    std::uint32_t record_runs = 0;  // runs of `capacity` records in `records`: 2 with the flat run
    // The cloud's texture (sRGB) and uv frames (vec4[count]) this frame, when it has one: the residency's
    // (GpuSplats::texture, uv_axes), never uploaded here.
    GLuint texture = 0;
    GLuint uv_axes = 0;
    std::vector<std::uint16_t> uniform_radius;  // uniform_texel_radius() of the texture (CPU cull)
    TexturePyramid pyramid;                     // its mip levels, made when a reduced preview asks
    bool pyramid_made = false;
    const std::vector<glm::vec4>* uv_axes_cpu = nullptr;  // the cloud's, valid during one render_system call
    const SplatTexture* texture_texels = nullptr;         // the cloud's, valid during one render_system call
    BoundingSphere bounds;                                // cloud space, for the framing camera
    double mean_radius = 0;  // mean_splat_radius(), for the automatic raster path
    std::uint64_t bounds_version = 0;
    std::uint64_t bounds_flags_version =
        0;                    // registry.version<PointFlags> the bounds left gone points out of
    double footprint_px = 0;  // splat_footprint_px() this frame (cull_pass)
    bool flat_list = false;   // the CPU cull filled the flat-coloured sprite list this frame
    // The CPU rasterises this frame's sprites of the cloud (SpritePath): a preview's, whose draw commands
    // are then empty (GL draws only its quads), or an HQ frame's visibility pass. raster_texels: its
    // texture for that (pyramid included).
    bool cpu_raster = false;
    TexelView raster_texels;
    // This frame's CPU-culled sprite records are in `records` and counted by `commands`: always off the
    // CPU sprite path; on it only once the frame knows GL draws them (upload_gl_sprites).
    bool gl_sprites = false;
    ComputeRasterCloud raster;  // sprites the compute rasteriser leaves to the rasteriser (compute_raster.h)
    SplatMaterial material;     // the cloud's SplatMaterial this frame (the defaults when it has none)
    bool colored = false;       // per-splat colours (else the packed colour is white, times the base colour)
    std::uint32_t count = 0;
    GLuint splats = 0;  // draw buffer this frame
    // The cloud's point marks this frame (runtime/gfx/point_marks.h): the mode the passes read them by
    // (FrameBlock counts.z: SFFD_MARKS_*), the residency's buffers (0: none; the passes then bind a
    // placeholder they never read), and the columns the CPU cull reads them from. A frame that shows an
    // overlay (selection tint, weights) draws a textured cloud untextured (`texture` 0 then).
    std::uint32_t marks_mode = 0;
    GLuint marks = 0, preview_index = 0;
    GLuint overlay_texture =
        0;  // a textured cloud's texture while an overlay draws it flat (SFFD_MARKS_TEXEL)
    MarksView cpu_marks;

    // The resident cloud, when the CPU cull may read its draw buffer this frame (gfx::read_splats_on_cpu:
    // the residency decides how, in place or from its copy; the renderer keeps none): its rest or its CPU
    // deformation's output where the CPU cull is wanted, any deformed buffer whose compute-cull records
    // exceed one storage block (storage_limits.h). Null: the compute cull only.
    gfx::GpuSplats* cpu_source = nullptr;
    std::uint64_t texture_version = 0;  // GpuSplats::texture_version uniform_radius was made from
    CpuCullResult cpu_cull;
    // The CPU cull's quad pass per range of splats when the splats (or uv axes) exceed one storage block
    // (storage_limits.h); empty: one indirect draw over the whole cloud.
    std::vector<QuadBatch> quad_batches;
};

// Owner of a fence sync object (GLsync is not a GL name, so gfx::GlObject does not cover it): move-only,
// deleted with its owner.
class Fence {
public:
    Fence() = default;
    explicit Fence(GLsync sync) : m_sync(sync) {}
    Fence(Fence&& other) noexcept : m_sync(std::exchange(other.m_sync, nullptr)) {}
    Fence& operator=(Fence&& other) noexcept {
        if (this != &other) reset(), m_sync = std::exchange(other.m_sync, nullptr);
        return *this;
    }
    Fence(const Fence&) = delete;
    Fence& operator=(const Fence&) = delete;
    ~Fence() { reset(); }
    void reset() {
        if (m_sync) glDeleteSync(m_sync);
        m_sync = nullptr;
    }
    GLsync get() const { return m_sync; }
    explicit operator bool() const { return m_sync != nullptr; }

private:
    GLsync m_sync = nullptr;
};

// One frame's visible counts on their way back (SplatRenderState::counts_ring).
struct CountsSlot {
    Fence fence;               // signals when the copies of the compute-culled clouds' commands landed
    std::uint64_t serial = 0;  // issue order
    std::uint64_t frame = 0;   // FrameContext::frame of the frame that issued it
    std::uint32_t cpu_points = 0, cpu_quads = 0;  // counts of the CPU-culled clouds, known at once
    std::uint32_t gpu_clouds = 0;                 // clouds copied into the slot
    std::vector<std::uint8_t> parts;  // per copied cloud: counts_cull (its cull commands), counts_big (its
                                      // compute rasteriser's big-sprite commands)
};

constexpr std::uint8_t counts_cull = 1, counts_big = 2;
// Per cloud in the counts ring: the cull's three draw commands, then the compute rasteriser's two.
constexpr std::size_t counts_entry_words = draw_command_words + 10;

// Registry resource: everything the renderer owns on the GPU.
struct SplatRenderState {
    // [textured][lit][lights]: cull pass variants (TEXTURED, LIT, LIGHTS in splat_color.glsl), compiled on
    // first use (cull_program)
    std::array<std::array<std::array<gfx::Program, SFFD_MAX_LIGHTS + 1>, 2>, 2> cull;
    // The exclusive scan of the compute cull's and the compute rasteriser's ordered lists (scan_programs)
    std::optional<gfx::RadixSorter> scan;
    std::array<gfx::Program, 2> visibility;  // [0] sprites, [1] quads
    // [textured: per-pixel texture lookups][clouds differ in material][sprites, quads]
    std::array<std::array<std::array<gfx::Program, 2>, 2>, 2> attribute;
    // [textured: per-pixel texture lookups][aux outputs][sprites, quads]
    std::array<std::array<std::array<gfx::Program, 2>, 2>, 2> preview;
    // [clouds differ in material][lights]: compiled on first use (shade_program)
    std::array<std::array<gfx::Program, SFFD_MAX_LIGHTS + 1>, 2> shade;
    gfx::Program display;          // sRGB copy for a window (PresentSource)
    gfx::VertexArray vao;          // empty: quads read their splats from SSBOs
    gfx::VertexArray records_vao;  // SplatRecord[] as vertex attributes 0..5 (buffer bound per cloud)
    float max_point_size = 1.0f;
    float min_point_size = 1.0f;  // GL_POINT_SIZE_RANGE, for the CPU preview's sprite squares
    CpuRasterImage cpu_raster;    // the CPU-rasterised part of the last frame (SpritePath)

    int width = 0, height = 0;              // the targets
    int frame_width = 0, frame_height = 0;  // what the last frame covered of them (preview_divider)
    glm::ivec4 drawn{0};                    // drawn_pixels() of the last frame
    bool aux_valid = false;                 // the last frame wrote the normal + depth target
    gfx::Texture color, aux, depth, accum_color, accum_normal, accum_material;
    gfx::Framebuffer output_fbo, accum_fbo, depth_fbo;
    // RGBA8 sRGB-encoded: only when presenting to a window of another size than the frame (the display
    // pass writes the window itself otherwise)
    gfx::Texture display_color;
    gfx::Framebuffer display_fbo;
    int display_width = 0, display_height = 0;

    gfx::Buffer display_ubo;             // FrameBlock with the background, for the display copy
    glm::vec4 display_background{0.0f};  // the background display_ubo holds
    glm::vec4 last_background{0.0f};     // of the last rendered frame
    // The Gaussian pass's last refusal, logged once: a cloud past a GPU limit is refused every frame, and
    // repeating the same line at 60 Hz would bury everything else in the log.
    std::string gaussian_refusal;

    // The compute cull's visible counts come back through this ring, never by waiting (the frame must not
    // stall on a read-back): a persistently mapped buffer of counts_slot_count slots x counts_ring_clouds
    // clouds x draw_command_words uints (all three draw commands).
    static constexpr std::size_t counts_slot_count = 4;
    gfx::Buffer
        command_reset;  // immutable {0, 1, 0, 0, 6, 0, 0, 0, 0, 1, 0, 0}: copied over the draw commands
    gfx::Buffer counts_ring;
    const std::uint32_t* counts_mapped = nullptr;
    std::size_t counts_ring_clouds = 0;
    std::array<CountsSlot, counts_slot_count> counts_slots;
    std::uint64_t counts_issued = 0;  // serial of the last slot issued
    std::uint64_t counts_serial = 0;  // serial of the counts below (0: none arrived yet)
    std::uint64_t counts_frame = 0;
    std::uint32_t counts_points = 0, counts_quads = 0, counts_raster_sprites = 0;
    ComputeRaster compute_raster;  // compute rasteriser (compute_raster.h), compiled on first use

    // Removes an entity's CloudGpu when its SplatCloud goes (component removed or entity destroyed).
    ecs::ScopedConnection cloud_gone;
    bool software = false;      // the context is a software rasterizer (gfx::software_rasterizer)
    bool preview_warm = false;  // the preview programs have drawn once (warm_preview_programs)
    bool cull_over_limit =
        false;  // some cloud's compute-cull buffers exceed the storage block size (storage_limits.h)
    std::uint32_t cpu_splat_passes = 0;  // this frame's loops over a cloud's splats on the CPU (RenderStats)
    bool failed = false;
};

struct ViewSetup {
    Camera camera;
    glm::dmat4 view{1.0};
    glm::dmat4 projection{1.0};
};

// A cloud whose counts live on the GPU this frame: its cull commands (compute cull) and/or its compute
// rasteriser's big-sprite commands.
struct CountsSource {
    const CloudGpu* gpu = nullptr;
    std::uint8_t parts = 0;  // counts_cull | counts_big
};

// What the passes of one frame share: the settings, the camera, the per-cloud uniforms' common part and the
// clouds that reached the draw lists (cull_pass fills `drawn`).
struct FramePlan {
    RenderSettings settings;
    int width = 1, height = 1;
    ViewSetup view;
    gpu::FrameBlock common;
    std::vector<CloudGpu*> drawn;
    // Visible counts: the CPU-culled clouds' now, the others' through the counts ring (issue_counts).
    std::vector<CountsSource> gpu_counts;
    std::uint32_t cpu_points = 0, cpu_quads = 0;
    std::vector<ComputeRasterDraw> compute;  // clouds on the compute rasteriser this frame (HQ)
    // The frame pixels the splats may cover (cull_pass; lo > hi: none), and whether that is known: only
    // the CPU cull gives the sprites' squares.
    glm::vec2 drawn_lo{1e30f}, drawn_hi{-1e30f};
    bool drawn_known = true;
    // The CPU-culled clouds' sprites are rasterised on the CPU (SpritePath): the preview's, or the HQ
    // visibility pass's.
    bool cpu_raster = false;
    // HQ: the CPU also runs the attribute pass (SpritePass::hq), every cloud's sprites being its own and
    // no quads left to GL (whose depth it would not see); GL only shades.
    bool cpu_hq = false;
};

// The plan's drawn pixels as a rectangle (x, y, width, height) inside its frame: the whole frame when not
// known.
glm::ivec4 plan_drawn_rect(const FramePlan& plan);
// The common part of two rectangles (x, y, width, height); width and height 0 when they do not meet.
glm::ivec4 intersect_rects(const glm::ivec4& a, const glm::ivec4& b);

// CPU time per pass for RenderStats, only with RenderSettings::time_passes (glFinish after each pass).
class PassLaps {
public:
    explicit PassLaps(bool enabled) : m_enabled(enabled) {}
    void lap(double& slot) {
        if (!m_enabled) return;
        glFinish();
        const auto now = clock::now();
        slot += std::chrono::duration<double, std::milli>(now - m_lap).count();
        m_lap = now;
    }
    double total_ms() const {
        return std::chrono::duration<double, std::milli>(clock::now() - m_start).count();
    }

private:
    using clock = std::chrono::steady_clock;
    bool m_enabled;
    clock::time_point m_start = clock::now(), m_lap = m_start;
};

// render_state.cpp: the state resource, its programs and targets, the per-cloud objects.
gfx::Texture make_target(GLenum format, int w, int h, const char* label);
void ensure_targets(SplatRenderState& s, int w, int h);
bool cpu_cull_wanted(const SplatRenderState& s, CullPath path);
void sync_clouds(ecs::Registry& reg, SplatRenderState& s, gfx::GpuSplatStore* store, bool cpu_cull,
                 const RenderSettings& settings);
// Binds a cloud's marks and preview indices (or the placeholder where it has none) for the passes that
// read them (the cull, the quads).
void bind_marks(const SplatRenderState& s, const CloudGpu& gpu);
// The texture the passes sample: the cloud's, or under an overlay the one it is drawn flat from.
inline GLuint material_texture(const CloudGpu& gpu) {
    return gpu.texture ? gpu.texture : gpu.overlay_texture;
}
Status cull_program(SplatRenderState& s, bool textured, bool lit, std::uint32_t lights);
// The scan programs (SplatRenderState::scan), compiled on first use; null with the error logged.
gfx::RadixSorter* scan_programs(SplatRenderState& s);
Status shade_program(SplatRenderState& s, bool materials, std::uint32_t lights);
SplatRenderState& render_state(ecs::Registry& reg);

// frame_view.cpp: camera, per-frame uniforms and the screen rectangle the clouds cover.
ViewSetup choose_camera(ecs::Registry& reg, const SplatRenderState& s, double aspect);
gpu::FrameBlock frame_block(ecs::Registry& reg, const RenderSettings& settings, const ViewSetup& view,
                            float max_point_size);
glm::ivec4 screen_rect(ecs::Registry& reg, const ViewSetup& view, int w, int h);

// visible_counts.cpp: the ring that brings the GPU's visible counts back without waiting.
void collect_counts(SplatRenderState& s);
void issue_counts(SplatRenderState& s, const std::vector<CountsSource>& computed, std::uint32_t cpu_points,
                  std::uint32_t cpu_quads, std::uint64_t frame);

// cull_pass.cpp
void cull_pass(ecs::Registry& reg, SplatRenderState& s, FramePlan& plan, RenderStats& stats);
// After the frame's choices (compute rasteriser, cpu_hq): uploads the CPU-culled sprites GL still draws,
// those of an HQ frame whose attribute pass is GL's or whose sprites went back to GL.
void upload_gl_sprites(const FramePlan& plan);

// splat_passes.cpp: the preview pass and the three HQ passes.
void begin_splat_passes(SplatRenderState& s, const FramePlan& plan);
void preview_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, RenderStats& stats);
void warm_preview_programs(SplatRenderState& s, const FramePlan& plan);
void visibility_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, const glm::ivec4& rect,
                     RenderStats& stats);
void plan_compute_raster(SplatRenderState& s, FramePlan& plan, bool materials, RenderStats& stats);
bool clouds_differ_in_material(const FramePlan& plan);
void attribute_pass(ecs::Registry& reg, const SplatRenderState& s, const FramePlan& plan,
                    const glm::ivec4& rect, bool materials);
void shade_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, bool materials);
void end_splat_passes();

}  // namespace sffd::render::detail
