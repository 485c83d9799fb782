// Splat render system: GPU state, passes and frame capture. See splat_render.h for the data flow.
#include "systems/splat_render/splat_render.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_inverse.hpp>

#include "runtime/app/app.h"
#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl_object.h"
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
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/storage_limits.h"

namespace sffd::render {

namespace {

// Three DrawArraysIndirectCommands per cloud: sprites {n, 1, 0, 0}, quads {6, n, 0, 0}, and a textured
// cloud's flat-coloured sprites {n, 1, capacity, 0} (CPU cull only; the compute cull leaves n = 0).
constexpr std::size_t draw_command_words = 12;

// Per point cloud GPU objects owned by the renderer (the splats themselves live in GpuSplatStore).
struct CloudGpu {
    gfx::Buffer records;    // SplatRecord[2 capacity]: visible sprites, prepared by the cull pass; from
                            // `capacity` on, a textured cloud's sprites of one texture colour (CPU cull)
    gfx::Buffer quads;      // uint[capacity]: indices of visible splats drawn as quads
    gfx::Buffer commands;   // three DrawArraysIndirectCommands: sprites, quads, flat-coloured sprites
    gfx::Buffer frame_ubo;  // FrameBlock for this cloud
    std::uint32_t capacity = 0;
    gfx::Texture texture;   // material texture (sRGB), when the material has one
    gfx::Buffer uv_axes;    // vec4[count]: SplatCloud::uv_axes (zeros when absent), when textured
    std::vector<std::uint16_t> uniform_radius;  // uniform_texel_radius() of the texture (CPU cull)
    const std::vector<glm::vec4>* uv_axes_cpu = nullptr;  // the cloud's, valid during one render_system call
    std::uint64_t texture_version = 0;
    BoundingSphere bounds;  // cloud space, for the framing camera
    double mean_radius = 0;  // mean_splat_radius(), for the automatic raster path
    std::uint64_t bounds_version = 0;
    double footprint_px = 0;  // splat_footprint_px() this frame (cull_pass)
    bool flat_list = false;   // the CPU cull filled the flat-coloured sprite list this frame
    ComputeRasterCloud raster;  // sprites the compute rasteriser leaves to the rasteriser (compute_raster.h)
    const SplatMaterial* material = nullptr;  // valid during one render_system call
    std::uint32_t count = 0;
    GLuint splats = 0;      // draw buffer this frame

    // The CPU copy of the draw buffer for the CPU cull (cpu_cull.h): the store's mirror, or on a hardware
    // GPU with the CPU cull forced (no mirrors kept there) the renderer's own copy of the rest splats.
    std::vector<gpu::GpuSplat> cpu_own;
    std::uint64_t cpu_own_version = 0;  // SplatCloud change stamp cpu_own holds
    const std::vector<gpu::GpuSplat>* cpu_current = nullptr;
    CpuCullResult cpu_cull;
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
    Fence fence;                  // signals when the copies of the compute-culled clouds' commands landed
    std::uint64_t serial = 0;     // issue order
    std::uint64_t frame = 0;      // FrameContext::frame of the frame that issued it
    std::uint32_t cpu_points = 0, cpu_quads = 0;  // counts of the CPU-culled clouds, known at once
    std::uint32_t gpu_clouds = 0;  // clouds copied into the slot
    std::vector<std::uint8_t> parts;  // per copied cloud: counts_cull (its cull commands), counts_big (its
                                      // compute rasteriser's big-sprite commands)
};

constexpr std::uint8_t counts_cull = 1, counts_big = 2;
// Per cloud in the counts ring: the cull's three draw commands, then the compute rasteriser's two.
constexpr std::size_t counts_entry_words = draw_command_words + 10;

}  // namespace

// Registry resource: everything the renderer owns on the GPU.
struct SplatRenderState {
    // [textured][lit][lights]: cull pass variants (TEXTURED, LIT, LIGHTS in splat_color.glsl), compiled on
    // first use (cull_program)
    std::array<std::array<std::array<gfx::Program, SFFD_MAX_LIGHTS + 1>, 2>, 2> cull;
    std::array<gfx::Program, 2> visibility;  // [0] sprites, [1] quads
    // [textured: per-pixel texture lookups][clouds differ in material][sprites, quads]
    std::array<std::array<std::array<gfx::Program, 2>, 2>, 2> attribute;
    // [textured: per-pixel texture lookups][aux outputs][sprites, quads]
    std::array<std::array<std::array<gfx::Program, 2>, 2>, 2> preview;
    // [clouds differ in material][lights]: compiled on first use (shade_program)
    std::array<std::array<gfx::Program, SFFD_MAX_LIGHTS + 1>, 2> shade;
    gfx::Program display;  // sRGB copy for a window (PresentSource)
    gfx::VertexArray vao;          // empty: quads read their splats from SSBOs
    gfx::VertexArray records_vao;  // SplatRecord[] as vertex attributes 0..5 (buffer bound per cloud)
    float max_point_size = 1.0f;

    int width = 0, height = 0;
    bool aux_valid = false;  // the last frame wrote the normal + depth target
    gfx::Texture color, aux, depth, accum_color, accum_normal, accum_material;
    gfx::Framebuffer output_fbo, accum_fbo, depth_fbo;
    gfx::Texture display_color;  // RGBA8 sRGB-encoded, only when presenting to a window
    gfx::Framebuffer display_fbo;
    int display_width = 0, display_height = 0;

    gfx::Buffer display_ubo;        // FrameBlock with the background, for the display copy
    glm::vec4 last_background{0.0f};  // of the last rendered frame

    // The compute cull's visible counts come back through this ring, never by waiting (issue 15): a
    // persistently mapped buffer of counts_slot_count slots x counts_ring_clouds clouds x draw_command_words
    // uints (all three draw commands).
    static constexpr std::size_t counts_slot_count = 4;
    gfx::Buffer command_reset;  // immutable {0, 1, 0, 0, 6, 0, 0, 0, 0, 1, 0, 0}: copied over the draw commands
    gfx::Buffer counts_ring;
    const std::uint32_t* counts_mapped = nullptr;
    std::size_t counts_ring_clouds = 0;
    std::array<CountsSlot, counts_slot_count> counts_slots;
    std::uint64_t counts_issued = 0;  // serial of the last slot issued
    std::uint64_t counts_serial = 0;  // serial of the counts below (0: none arrived yet)
    std::uint64_t counts_frame = 0;
    std::uint32_t counts_points = 0, counts_quads = 0, counts_raster_sprites = 0;
    ComputeRaster compute_raster;  // compute rasteriser (compute_raster.h), compiled on first use

    std::unordered_map<ecs::Entity, CloudGpu> clouds;
    bool software = false;  // the context is a software rasterizer (gfx::software_rasterizer)
    bool cull_over_limit = false;  // some cloud's compute-cull buffers exceed the storage block size (storage_limits.h)
    std::uint32_t cpu_splat_passes = 0;  // this frame's loops over a cloud's splats on the CPU (RenderStats)
    bool failed = false;
};

namespace {

Result<gfx::Program> splat_program(const char* fragment, const char* label, int pass, int quad, int aux = 1,
                                   int materials = 0, int textured = -1) {
    gfx::Defines defines{{"PASS", std::to_string(pass)}, {"SHAPE_QUAD", std::to_string(quad)},
                         {"AUX", std::to_string(aux)}, {"MATERIALS", std::to_string(materials)}};
    if (textured >= 0) defines.push_back({"TEXTURED", std::to_string(textured)});  // else read per draw
    return gfx::load_program({{GL_VERTEX_SHADER, "splat_render/splat.vert"}, {GL_FRAGMENT_SHADER, fragment}}, label,
                             defines);
}

gfx::Texture make_target(GLenum format, int w, int h, const char* label) {
    gfx::Texture t = gfx::Texture::create(label, GL_TEXTURE_2D);
    glTextureStorage2D(t.id(), 1, format, w, h);
    glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

void ensure_targets(SplatRenderState& s, int w, int h) {
    if (s.width == w && s.height == h && s.output_fbo) return;
    s.width = w, s.height = h;
    s.color = make_target(GL_RGBA16F, w, h, "render.color");
    s.aux = make_target(GL_RGBA32F, w, h, "render.normal_depth");
    s.depth = make_target(GL_DEPTH_COMPONENT32F, w, h, "render.depth");
    s.accum_color = make_target(GL_RGBA32F, w, h, "render.accum_color");
    s.accum_normal = make_target(GL_RGBA32F, w, h, "render.accum_normal");
    s.accum_material = make_target(GL_RG32F, w, h, "render.accum_material");

    s.output_fbo = gfx::Framebuffer::create("render.output");
    glNamedFramebufferTexture(s.output_fbo.id(), GL_COLOR_ATTACHMENT0, s.color.id(), 0);
    glNamedFramebufferTexture(s.output_fbo.id(), GL_COLOR_ATTACHMENT1, s.aux.id(), 0);
    glNamedFramebufferTexture(s.output_fbo.id(), GL_DEPTH_ATTACHMENT, s.depth.id(), 0);
    const GLenum two[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(s.output_fbo.id(), 2, two);

    s.accum_fbo = gfx::Framebuffer::create("render.accum");
    glNamedFramebufferTexture(s.accum_fbo.id(), GL_COLOR_ATTACHMENT0, s.accum_color.id(), 0);
    glNamedFramebufferTexture(s.accum_fbo.id(), GL_COLOR_ATTACHMENT1, s.accum_normal.id(), 0);
    glNamedFramebufferTexture(s.accum_fbo.id(), GL_COLOR_ATTACHMENT2, s.accum_material.id(), 0);
    glNamedFramebufferTexture(s.accum_fbo.id(), GL_DEPTH_ATTACHMENT, s.depth.id(), 0);
    glNamedFramebufferDrawBuffers(s.accum_fbo.id(), 2, two);

    s.depth_fbo = gfx::Framebuffer::create("render.visibility");
    glNamedFramebufferTexture(s.depth_fbo.id(), GL_DEPTH_ATTACHMENT, s.depth.id(), 0);
    glNamedFramebufferDrawBuffer(s.depth_fbo.id(), GL_NONE);
}

void upload_texture(CloudGpu& gpu, const SplatMaterial& m) {
    if (m.texture_rgba8.empty() || m.texture_width <= 0 || m.texture_height <= 0 ||
        m.texture_rgba8.size() < std::size_t(m.texture_width) * std::size_t(m.texture_height) * 4) {
        gpu.texture.reset();
        return;
    }
    gpu.texture = gfx::Texture::create("render.material", GL_TEXTURE_2D);
    const int levels = 1 + int(std::floor(std::log2(std::max(m.texture_width, m.texture_height))));
    glTextureStorage2D(gpu.texture.id(), levels, GL_SRGB8_ALPHA8, m.texture_width, m.texture_height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // Row 0 of the texels is v = 0, which is also GL's first row (t = 0).
    glTextureSubImage2D(gpu.texture.id(), 0, 0, 0, m.texture_width, m.texture_height, GL_RGBA, GL_UNSIGNED_BYTE,
                        m.texture_rgba8.data());
    glGenerateTextureMipmap(gpu.texture.id());
    // Mipmapped: the HQ attribute pass filters per pixel with textureGrad (the cull's per-splat lookups ask
    // for level 0 explicitly).
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

// The uv frames the textured passes read (SFFD_SSBO_UV_AXES), zeros for a cloud without them (then every
// fragment samples the splat's centre uv at level 0).
void upload_uv_axes(CloudGpu& gpu, const SplatCloud& cloud) {
    gpu.uniform_radius.clear();
    if (!gpu.texture) {
        gpu.uv_axes.reset();
        return;
    }
    const SplatMaterial& m = cloud.material;
    gpu.uniform_radius = uniform_texel_radius(m.texture_rgba8.data(), m.texture_width, m.texture_height);
    std::vector<glm::vec4> zeros;
    const std::vector<glm::vec4>* data = &cloud.uv_axes;
    if (cloud.uv_axes.size() != cloud.size()) zeros.assign(cloud.size(), glm::vec4(0.0f)), data = &zeros;
    gpu.uv_axes = gfx::Buffer::create("render.uv_axes");
    glNamedBufferData(gpu.uv_axes.id(), GLsizeiptr(std::max<std::size_t>(data->size(), 1) * sizeof(glm::vec4)),
                      data->empty() ? nullptr : data->data(), GL_STATIC_DRAW);
}

// Whether the CPU cull may run this frame, so CPU copies of the splats are worth keeping.
bool cpu_cull_wanted(const SplatRenderState& s, CullPath path) {
    return path == CullPath::cpu || (path == CullPath::automatic && (s.software || s.cull_over_limit));
}

// Refreshes the renderer's own per-cloud objects (cull buffers, texture, bounds) for the clouds that are
// resident in GpuSplatStore (residency_system uploads them; this only reads the store) and drops objects
// of clouds that no longer exist. keep_cpu: the CPU cull may run, so point cpu_current at a CPU copy of
// the draw buffer.
void sync_clouds(ecs::Registry& reg, SplatRenderState& s, const gfx::GpuSplatStore& store, bool keep_cpu) {
    for (auto it = s.clouds.begin(); it != s.clouds.end();)
        it = reg.valid(it->first) && reg.has<SplatCloud>(it->first) && store.clouds.contains(it->first) ? std::next(it)
                                                                                                     : s.clouds.erase(it);

    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        const auto sit = store.clouds.find(e);
        if (sit == store.clouds.end()) return;  // not resident (no residency phase ran): not drawn
        const gfx::GpuSplats& splats = sit->second;
        const std::uint64_t version = reg.version<SplatCloud>(e);
        CloudGpu& gpu = s.clouds[e];
        const auto n = static_cast<std::uint32_t>(cloud.size());
        if (!gpu.frame_ubo) {
            gpu.frame_ubo = gfx::Buffer::create("render.frame_block");
            glNamedBufferData(gpu.frame_ubo.id(), sizeof(gpu::FrameBlock), nullptr, GL_DYNAMIC_DRAW);
            gpu.commands = gfx::Buffer::create("render.draw_commands");
            glNamedBufferData(gpu.commands.id(), draw_command_words * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_DRAW);
        }
        if (gpu.capacity < n || !gpu.records) {
            gpu.capacity = std::max<std::uint32_t>(n, 1);
            gpu.records = gfx::Buffer::create("render.visible_splats");
            glNamedBufferData(gpu.records.id(), GLsizeiptr(2 * std::size_t(gpu.capacity) * sizeof(SplatRecord)), nullptr,
                              GL_DYNAMIC_DRAW);
            gpu.quads = gfx::Buffer::create("render.visible_quads");
            glNamedBufferData(gpu.quads.id(), GLsizeiptr(std::size_t(gpu.capacity) * sizeof(std::uint32_t)), nullptr,
                              GL_DYNAMIC_DRAW);
        }
        if (gpu.texture_version != version) {
            upload_texture(gpu, cloud.material);
            upload_uv_axes(gpu, cloud);
            gpu.texture_version = version;
        }
        gpu.uv_axes_cpu = gpu.texture && cloud.uv_axes.size() == n ? &cloud.uv_axes : nullptr;
        if (gpu.bounds_version != version) {
            gpu.bounds = bounding_sphere(cloud);
            gpu.mean_radius = mean_splat_radius(cloud);
            ++s.cpu_splat_passes;
            gpu.bounds_version = version;
        }
        gpu.material = &cloud.material;
        gpu.count = std::min(n, splats.count);
        gpu.splats = splats.draw_buffer();
        // The CPU copy of the draw buffer: the store's mirror (rest, or the CPU deformation's output);
        // none when the FFD compute pass wrote `deformed` (those splats exist only on the GPU).
        gpu.cpu_current = nullptr;
        if (!keep_cpu) {
            gpu.cpu_own = {}, gpu.cpu_cull = {};
            return;
        }
        gpu.cpu_current = splats.cpu_current();
        if (!gpu.cpu_current && splats.state == gfx::Residency::rest && splats.rest_version == version) {
            if (gpu.cpu_own_version != version || gpu.cpu_own.size() != n) {
                gpu.cpu_own = pack_splats(cloud), gpu.cpu_own_version = version;  // the CPU cull was just chosen
                ++s.cpu_splat_passes;
            }
            if (gpu.cpu_own.size() == gpu.count) gpu.cpu_current = &gpu.cpu_own;
        }
    });
}

struct ViewSetup {
    Camera camera;
    glm::dmat4 view{1.0};
    glm::dmat4 projection{1.0};
};

ViewSetup choose_camera(ecs::Registry& reg, const SplatRenderState& s, double aspect) {
    ViewSetup v;
    // The one default-camera rule (camera_math.h), fed with the bounds cached per uploaded cloud.
    v.camera = scene_camera(
        reg, aspect,
        [&](ecs::Entity e, const SplatCloud&) {
            auto it = s.clouds.find(e);
            return it == s.clouds.end() ? BoundingSphere{glm::dvec3(0.0), -1.0} : it->second.bounds;
        },
        [&](ecs::Entity e, const GaussianCloud&) { return cached_gaussian_bounds(reg, e); });
    v.view = view_matrix(v.camera);
    v.projection = projection_matrix(v.camera, aspect);
    return v;
}

gpu::FrameBlock frame_block(ecs::Registry& reg, const RenderSettings& settings, const ViewSetup& view,
                            float max_point_size) {
    gpu::FrameBlock b = camera_frame_block(view.view, view.projection, settings.width, settings.height,
                                           settings.visibility_epsilon, max_point_size, settings.culling);
    std::uint32_t lights = 0;
    reg.view<const DirectionalLight>().each([&](const DirectionalLight& l) {
        if (lights >= SFFD_MAX_LIGHTS) return;
        b.light_dir[lights] = glm::vec4(-glm::normalize(l.direction), 0.0f);
        b.light_color[lights] = glm::vec4(l.color * l.intensity, 0.0f);
        ++lights;
    });
    bool has_ambient = false;
    reg.view<const AmbientLight>().each([&](const AmbientLight& a) {
        b.ambient += glm::vec4(a.color * a.intensity, 0.0f);
        has_ambient = true;
    });
    if (lights == 0 && !has_ambient) {  // an unlit scene gets the default key light and ambient
        const DirectionalLight l;
        const AmbientLight a;
        b.light_dir[0] = glm::vec4(-glm::normalize(l.direction), 0.0f);
        b.light_color[0] = glm::vec4(l.color * l.intensity, 0.0f);
        b.ambient = glm::vec4(a.color * a.intensity, 0.0f);
        lights = 1;
    }
    b.background = glm::vec4(settings.background.value_or(glm::vec3(0.0f)), 0.0f);
    b.counts = glm::uvec4(0u, lights, 0u, 0u);
    return b;
}

// Pixel rectangle (x, y, width, height; GL's bottom-left origin) that holds every cloud's projection:
// the deformer's world box when the cloud is deformed, else the rest bounding sphere; the whole frame
// when a bound reaches behind the near plane or a deformed cloud has no box.
glm::ivec4 screen_rect(ecs::Registry& reg, const ViewSetup& view, int w, int h) {
    const glm::ivec4 full(0, 0, w, h);
    const double p00 = view.projection[0][0], p11 = view.projection[1][1];
    const double near_plane = double(view.camera.near_plane);
    glm::dvec2 lo(1e30), hi(-1e30);
    bool everything = false;
    auto add_ball = [&](const glm::dvec3& world_center, double radius) {
        const glm::dvec3 c = glm::dvec3(view.view * glm::dvec4(world_center, 1.0));
        const double depth = -c.z, near_depth = depth - radius;
        if (near_depth <= near_plane) {
            everything = true;
            return;
        }
        const glm::dvec2 ndc(p00 * c.x / depth, p11 * c.y / depth);
        const glm::dvec2 half(radius * std::sqrt(p00 * p00 + ndc.x * ndc.x) / near_depth,
                              radius * std::sqrt(p11 * p11 + ndc.y * ndc.y) / near_depth);
        lo = glm::min(lo, ndc - half);
        hi = glm::max(hi, ndc + half);
    };
    const auto* store = reg.try_resource<gfx::GpuSplatStore>();
    const auto* state = reg.try_resource<SplatRenderState>();
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        if (everything || cloud.size() == 0) return;
        const auto sit = store ? store->clouds.find(e) : decltype(store->clouds.end()){};
        const bool deformed = store && sit != store->clouds.end() && sit->second.is_deformed();
        if (deformed) {
            const auto* d = reg.try_get<DeformedSplats>(e);
            if (!d || d->bounds_max.x < d->bounds_min.x) {
                everything = true;
                return;
            }
            // Box -> ball around it, grown by 4x the largest rest splat radius (the box holds the centres;
            // deformed axes are longer by the local stretch).
            const auto cit = state->clouds.find(e);
            const double splat_r = cit != state->clouds.end() ? cit->second.bounds.max_splat_radius : 0.0;
            add_ball(0.5 * (d->bounds_min + d->bounds_max), 0.5 * glm::length(d->bounds_max - d->bounds_min) + 4.0 * splat_r);
            return;
        }
        const auto cit = state->clouds.find(e);
        if (cit == state->clouds.end()) return;
        const glm::dmat4 m = model_matrix(reg.try_get<Transform>(e), cloud.origin);
        const double scale = std::max({glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])),
                                       glm::length(glm::dvec3(m[2]))});
        add_ball(glm::dvec3(m * glm::dvec4(cit->second.bounds.center, 1.0)), cit->second.bounds.radius * scale);
    });
    if (everything) return full;
    if (hi.x < lo.x) return glm::ivec4(0, 0, 0, 0);
    const int x0 = std::clamp(int(std::floor((lo.x * 0.5 + 0.5) * w)) - 1, 0, w);
    const int x1 = std::clamp(int(std::ceil((hi.x * 0.5 + 0.5) * w)) + 1, 0, w);
    const int y0 = std::clamp(int(std::floor((lo.y * 0.5 + 0.5) * h)) - 1, 0, h);
    const int y1 = std::clamp(int(std::ceil((hi.y * 0.5 + 0.5) * h)) + 1, 0, h);
    return glm::ivec4(x0, y0, x1 - x0, y1 - y0);
}

// programs: [sprites, quads] for the cloud; flat: the program for a textured cloud's flat-coloured sprites
// (CpuCullResult::flat_records: the untextured variant of the pass; null for passes without colour).
// big: the HQ passes of the compute rasteriser's frame draw only the sprites it left to them (indexed
// draws over ComputeRasterCloud::big) and the quads.
void draw_cloud(const SplatRenderState& s, const std::array<gfx::Program, 2>& programs, const CloudGpu& gpu,
                const gfx::Program* flat = nullptr, bool big = false) {
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, gpu.frame_ubo.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_DRAW, gpu.splats);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE, gpu.quads.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE_SPLATS, gpu.records.id());
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.commands.id());
    glBindTextureUnit(SFFD_TEX_MATERIAL, gpu.texture.id());
    if (gpu.texture) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_UV_AXES, gpu.uv_axes.id());
    glVertexArrayVertexBuffer(s.records_vao.id(), 0, gpu.records.id(), 0, GLsizei(SFFD_SPLAT_RECORD_BYTES));
    if (big) glVertexArrayElementBuffer(s.records_vao.id(), gpu.raster.big.id());
    glBindVertexArray(s.records_vao.id());
    glUseProgram(programs[0].id());
    if (big) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.raster.commands.id());
        glDrawElementsIndirect(GL_POINTS, GL_UNSIGNED_INT, nullptr);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.commands.id());
    } else {
        glDrawArraysIndirect(GL_POINTS, nullptr);
    }
    glBindVertexArray(s.vao.id());
    glUseProgram(programs[1].id());
    glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(4 * sizeof(std::uint32_t)));
    if (gpu.texture) {
        glBindVertexArray(s.records_vao.id());
        glUseProgram(flat ? flat->id() : programs[0].id());
        if (big) {
            glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.raster.commands.id());
            glDrawElementsIndirect(GL_POINTS, GL_UNSIGNED_INT, reinterpret_cast<const void*>(5 * sizeof(std::uint32_t)));
        } else {
            glDrawArraysIndirect(GL_POINTS, reinterpret_cast<const void*>(8 * sizeof(std::uint32_t)));
        }
    }
}

// The cull pass variant for an (un)textured material, (un)lit colours and `lights` lights, compiled once.
Status cull_program(SplatRenderState& s, bool textured, bool lit, std::uint32_t lights) {
    lights = std::min<std::uint32_t>(lights, SFFD_MAX_LIGHTS);
    gfx::Program& program = s.cull[textured][lit][lit ? lights : 0];
    if (program) return {};
    auto cull = gfx::load_compute_program("splat_render/cull.comp", "render.cull",
                                          {{"TEXTURED", textured ? "1" : "0"}, {"LIT", lit ? "1" : "0"},
                                           {"LIGHTS", std::to_string(lit ? lights : 0)}});
    if (!cull) return make_error(cull.message());
    program = std::move(cull.value());
    return {};
}

// The deferred shading program for `lights` directional lights (LIGHTS in lighting.glsl), with one
// material for the frame or blended ones (MATERIALS), compiled once.
Status shade_program(SplatRenderState& s, bool materials, std::uint32_t lights) {
    gfx::Program& program = s.shade[materials][std::min<std::uint32_t>(lights, SFFD_MAX_LIGHTS)];
    if (program) return {};
    auto shade = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                    {GL_FRAGMENT_SHADER, "splat_render/shade.frag"}},
                                   "render.shade", {{"LIGHTS", std::to_string(lights)}, {"MATERIALS", materials ? "1" : "0"}});
    if (!shade) return make_error(shade.message());
    program = std::move(shade.value());
    return {};
}

}  // namespace

Status init_render_state(ecs::Registry& registry) {
    SplatRenderState s;
    if (Status st = cull_program(s, false, false, 1); !st) return st;
    for (int quad = 0; quad < 2; ++quad) {
        auto vis = splat_program("splat_render/visibility.frag", quad ? "render.visibility.quads" : "render.visibility", 0, quad, 0);
        if (!vis) return make_error(vis.message());
        for (int textured = 0; textured < 2; ++textured)
            for (int materials = 0; materials < 2; ++materials) {
                auto attr = splat_program("splat_render/attribute.frag", quad ? "render.attribute.quads" : "render.attribute",
                                          1, quad, 0, materials, textured);
                if (!attr) return make_error(attr.message());
                s.attribute[textured][materials][quad] = std::move(attr.value());
            }
        for (int textured = 0; textured < 2; ++textured)
            for (int aux = 0; aux < 2; ++aux) {
                auto prev = splat_program("splat_render/preview.frag", quad ? "render.preview.quads" : "render.preview", 2,
                                          quad, aux, 0, textured);
                if (!prev) return make_error(prev.message());
                s.preview[textured][aux][quad] = std::move(prev.value());
            }
        s.visibility[quad] = std::move(vis.value());
    }
    // The shading program of the common case (one light) now, so shader errors surface here.
    if (Status st = shade_program(s, false, 1); !st) return st;
    auto display = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                      {GL_FRAGMENT_SHADER, "splat_render/display.frag"}},
                                     "render.display");
    if (!display) return make_error(display.message());
    s.display = std::move(display.value());
    s.vao = gfx::VertexArray::create("render.empty");
    s.command_reset = gfx::Buffer::create("render.draw_commands.reset");
    const std::uint32_t reset[draw_command_words] = {0, 1, 0, 0, 6, 0, 0, 0, 0, 1, 0, 0};
    glNamedBufferStorage(s.command_reset.id(), sizeof reset, reset, 0);
    s.records_vao = gfx::VertexArray::create("render.splat_records");
    for (GLuint a = 0; a < GLuint(SFFD_SPLAT_RECORD_BYTES / 16); ++a) {
        glEnableVertexArrayAttrib(s.records_vao.id(), a);
        glVertexArrayAttribFormat(s.records_vao.id(), a, 4, GL_FLOAT, GL_FALSE, a * 16);
        glVertexArrayAttribBinding(s.records_vao.id(), a, 0);
    }
    GLfloat range[2] = {1.0f, 1.0f};
    glGetFloatv(GL_POINT_SIZE_RANGE, range);
    s.max_point_size = range[1];
    s.software = gfx::software_rasterizer();
    registry.set_resource<SplatRenderState>(std::move(s));
    return {};
}

void release_render_state(ecs::Registry& registry) {
    release_gaussian_pass(registry);
    registry.erase_resource<SplatRenderState>();
}

namespace {

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
};

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
    double total_ms() const { return std::chrono::duration<double, std::milli>(clock::now() - m_start).count(); }

private:
    using clock = std::chrono::steady_clock;
    bool m_enabled;
    clock::time_point m_start = clock::now(), m_lap = m_start;
};

// The ring that brings the compute cull's visible counts back without waiting: each frame copies the draw
// commands of its compute-culled clouds into one slot of a persistently mapped buffer and fences it; a later
// frame reads the slot once glClientWaitSync(fence, 0 timeout) says the copies landed.
void ensure_counts_ring(SplatRenderState& s, std::size_t clouds) {
    if (s.counts_ring && s.counts_ring_clouds >= clouds) return;
    for (CountsSlot& slot : s.counts_slots) slot = CountsSlot{};  // in flight into the old ring: dropped
    s.counts_ring_clouds = std::max<std::size_t>(clouds, 4);
    const auto bytes = GLsizeiptr(SplatRenderState::counts_slot_count * s.counts_ring_clouds * counts_entry_words * sizeof(std::uint32_t));
    const GLbitfield map = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    s.counts_ring = gfx::Buffer::create("render.visible_counts");
    glNamedBufferStorage(s.counts_ring.id(), bytes, nullptr, map | GL_CLIENT_STORAGE_BIT);
    s.counts_mapped = static_cast<const std::uint32_t*>(glMapNamedBufferRange(s.counts_ring.id(), 0, bytes, map));
}

// Frees every slot whose fence has signalled (a zero-timeout poll) and keeps the newest one's counts.
void collect_counts(SplatRenderState& s) {
    for (std::size_t i = 0; i < s.counts_slots.size(); ++i) {
        CountsSlot& slot = s.counts_slots[i];
        if (!slot.fence) continue;
        const GLenum state = glClientWaitSync(slot.fence.get(), 0, 0);
        if (state != GL_ALREADY_SIGNALED && state != GL_CONDITION_SATISFIED) continue;
        slot.fence.reset();
        if (slot.serial <= s.counts_serial || !s.counts_mapped) continue;
        std::uint32_t points = slot.cpu_points, quads = slot.cpu_quads, big = 0;
        const std::uint32_t* p = s.counts_mapped + i * s.counts_ring_clouds * counts_entry_words;
        for (std::uint32_t c = 0; c < slot.gpu_clouds; ++c) {
            const std::uint32_t* commands = p + c * counts_entry_words;
            if (slot.parts[c] & counts_cull) {
                points += commands[0] + commands[8];  // sprites + flat-coloured sprites
                quads += commands[5];
            }
            if (slot.parts[c] & counts_big) big += commands[draw_command_words] + commands[draw_command_words + 5];
        }
        s.counts_serial = slot.serial, s.counts_frame = slot.frame;
        s.counts_points = points, s.counts_quads = quads, s.counts_raster_sprites = big;
    }
}

// Copies this frame's GPU-side draw commands into a free slot of the ring and fences it (the oldest slot
// when every one is still in flight: its counts are dropped, never waited for).
void issue_counts(SplatRenderState& s, const std::vector<CountsSource>& computed, std::uint32_t cpu_points,
                  std::uint32_t cpu_quads, std::uint64_t frame) {
    ensure_counts_ring(s, computed.size());
    std::size_t at = 0;
    for (std::size_t i = 0; i < s.counts_slots.size(); ++i) {
        if (!s.counts_slots[i].fence) {
            at = i;
            break;
        }
        if (s.counts_slots[i].serial < s.counts_slots[at].serial) at = i;
    }
    CountsSlot& slot = s.counts_slots[at];
    slot.parts.assign(computed.size(), 0);
    // The copies read counters that shader atomics wrote (cull.comp, compute_visibility.comp).
    if (!computed.empty()) gfx::memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT, "render.counts");
    for (std::size_t c = 0; c < computed.size(); ++c) {
        const GLintptr entry = GLintptr((at * s.counts_ring_clouds + c) * counts_entry_words * sizeof(std::uint32_t));
        if (computed[c].parts & counts_cull)
            glCopyNamedBufferSubData(computed[c].gpu->commands.id(), s.counts_ring.id(), 0, entry,
                                     draw_command_words * sizeof(std::uint32_t));
        if (computed[c].parts & counts_big)
            glCopyNamedBufferSubData(computed[c].gpu->raster.commands.id(), s.counts_ring.id(), 0,
                                     entry + GLintptr(draw_command_words * sizeof(std::uint32_t)), 10 * sizeof(std::uint32_t));
        slot.parts[c] = computed[c].parts;
    }
    slot.fence = Fence(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
    glFlush();  // a fence signals only once submitted; polls never flush (a headless run has no swap)
    slot.serial = ++s.counts_issued, slot.frame = frame;
    slot.cpu_points = cpu_points, slot.cpu_quads = cpu_quads;
    slot.gpu_clouds = std::uint32_t(computed.size());
}

// Per-cloud uniforms, then culling and compaction of every cloud (the compute pass, or cpu_cull.h).
void cull_pass(ecs::Registry& reg, SplatRenderState& s, FramePlan& plan, RenderStats& stats) {
    const RenderSettings& settings = plan.settings;
    auto scope = profiling::gpu_scope(reg, "render.cull");
    // Write-after-read across frames: the last frame's draws fetched records, quads and commands that this
    // pass overwrites, by shader stores (compute cull) or by copies and sub-data uploads (CPU cull).
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT, "render.cull.reuse");
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        CloudGpu& gpu = s.clouds[e];
        if (gpu.count == 0 || gpu.splats == 0) return;
        gpu::FrameBlock b = plan.common;
        const glm::dmat4 mv = plan.view.view * model_matrix(reg.try_get<Transform>(e), cloud.origin);
        b.model_view = glm::mat4(mv);
        b.normal_view = glm::mat4(glm::mat3(glm::inverseTranspose(glm::dmat3(mv))));
        gpu.footprint_px = splat_footprint_px(mv, gpu.bounds.center, gpu.mean_radius, plan.view.projection[1][1], plan.height);
        gpu.flat_list = false;
        b.params.w = gpu.texture ? 1.0f : 0.0f;
        b.material = glm::vec4(gpu.material->specular, gpu.material->shininess, 0.0f, 0.0f);
        b.counts.x = gpu.count;
        b.counts.w = settings.quality == Quality::preview ? 1u : 0u;  // cull pass lights sprites in preview
        glNamedBufferSubData(gpu.frame_ubo.id(), 0, sizeof b, &b);
        if (gpu.cpu_current && cpu_cull_wanted(s, settings.cull_path)) {
            // CPU cull (cpu_cull.h): the same records, uploaded run by run into the buffers the draws read.
            TexelView texels;
            if (gpu.texture)
                texels = {gpu.material->texture_rgba8.data(), gpu.material->texture_width, gpu.material->texture_height,
                          gpu.uv_axes_cpu ? gpu.uv_axes_cpu->data() : nullptr,
                          gpu.uniform_radius.empty() ? nullptr : gpu.uniform_radius.data()};
            CpuCullResult& r = gpu.cpu_cull;
            cull_splats_cpu(std::span(gpu.cpu_current->data(), gpu.count), b, texels, r);
            ++s.cpu_splat_passes;
            CpuCullResult::for_each_run(r.records, r.record_counts, r.block, [&](std::size_t at, const SplatRecord* p, std::size_t k) {
                glNamedBufferSubData(gpu.records.id(), GLintptr(at * sizeof(SplatRecord)), GLsizeiptr(k * sizeof(SplatRecord)), p);
            });
            CpuCullResult::for_each_run(r.quads, r.quad_counts, r.block, [&](std::size_t at, const std::uint32_t* p, std::size_t k) {
                glNamedBufferSubData(gpu.quads.id(), GLintptr(at * sizeof(std::uint32_t)), GLsizeiptr(k * sizeof(std::uint32_t)), p);
            });
            CpuCullResult::for_each_run(r.flat_records, r.flat_counts, r.block, [&](std::size_t at, const SplatRecord* p, std::size_t k) {
                glNamedBufferSubData(gpu.records.id(), GLintptr((gpu.capacity + at) * sizeof(SplatRecord)),
                                     GLsizeiptr(k * sizeof(SplatRecord)), p);
            });
            const std::uint32_t commands[draw_command_words] = {r.visible_records, 1, 0, 0, 6, r.visible_quads, 0, 0, r.visible_flat, 1, gpu.capacity, 0};
            glNamedBufferSubData(gpu.commands.id(), 0, sizeof commands, commands);
            plan.cpu_points += r.visible_records + r.visible_flat;
            plan.cpu_quads += r.visible_quads;
            gpu.flat_list = bool(gpu.texture);
            ++stats.cpu_culled_clouds;
        } else {
            // Reset the counts on the GPU (a copy from an immutable buffer): a CPU upload into a buffer the
            // GPU writes every frame makes drivers move it to host memory (NVIDIA's performance warning).
            // The third command (flat-coloured sprites) stays empty: only the CPU cull fills it.
            if (Status st = compute_cull_fits(gpu.count); !st) {
                warn_once("render_system(): " + st.message() + "; the cloud is not drawn (the automatic cull path takes the CPU cull)");
                return;
            }
            glCopyNamedBufferSubData(s.command_reset.id(), gpu.commands.id(), 0, 0, draw_command_words * sizeof(std::uint32_t));
            const bool textured = bool(gpu.texture), lit = b.counts.w == 1u;
            if (Status st = cull_program(s, textured, lit, b.counts.y); !st) log::error("render_system(): ", st.message());
            glUseProgram(s.cull[textured][lit][lit ? std::min<std::uint32_t>(b.counts.y, SFFD_MAX_LIGHTS) : 0].id());
            glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, gpu.frame_ubo.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_DRAW, gpu.splats);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE, gpu.quads.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE_SPLATS, gpu.records.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_DRAW_INDIRECT, gpu.commands.id());
            if (textured) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_UV_AXES, gpu.uv_axes.id());
            glBindTextureUnit(SFFD_TEX_MATERIAL, gpu.texture.id());
            // A compute pass, not a vertex shader with rasterizer discard: llvmpipe runs compute on its worker
            // threads, vertex shaders on the calling thread (measured: same CPU, 2x the main-thread time).
            if (Status st = gfx::dispatch_1d(gpu.count, SFFD_CULL_GROUP_SIZE); !st) log::error("render_system(): ", st.message());
            ++stats.compute_culled_clouds;
            plan.gpu_counts.push_back({&gpu, counts_cull});
        }
        stats.splats += gpu.count;
        plan.drawn.push_back(&gpu);
    });
    // Records are fetched as vertex attributes (records_vao), quads and records read as SSBOs, commands
    // drawn indirectly and copied into the counts ring.
    gfx::memory_barrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT |
                            GL_BUFFER_UPDATE_BARRIER_BIT,
                        "render.cull");
}

// Clears the output targets and sets the state every splat pass shares.
void begin_splat_passes(SplatRenderState& s, const FramePlan& plan) {
    const RenderSettings& settings = plan.settings;
    const glm::vec4 background = plan.common.background;
    const glm::vec4 no_hit(0.0f, 0.0f, 0.0f, -1.0f);
    const float far_depth = 1.0f;
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_COLOR, 0, &background.x);
    if (settings.aux_outputs) glClearNamedFramebufferfv(s.output_fbo.id(), GL_COLOR, 1, &no_hit.x);
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_DEPTH, 0, &far_depth);
    glViewport(0, 0, plan.width, plan.height);
    glBindVertexArray(s.vao.id());
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);

    // Without aux outputs only attachment 0 is written (the preview program variant has no aux output).
    const GLenum with_aux[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1}, without_aux[2] = {GL_COLOR_ATTACHMENT0, GL_NONE};
    glNamedFramebufferDrawBuffers(s.output_fbo.id(), 2, settings.aux_outputs ? with_aux : without_aux);
    s.aux_valid = settings.aux_outputs;
}

// Preview: one pass of opaque ray-cast ellipses into the output targets.
void preview_pass(ecs::Registry& reg, const SplatRenderState& s, const FramePlan& plan) {
    glBindFramebuffer(GL_FRAMEBUFFER, s.output_fbo.id());
    glDepthFunc(GL_LESS);
    auto scope = profiling::gpu_scope(reg, "render.preview");
    const int aux = plan.settings.aux_outputs ? 1 : 0;
    for (const CloudGpu* gpu : plan.drawn) draw_cloud(s, s.preview[gpu->texture ? 1 : 0][aux], *gpu, &s.preview[0][aux][0]);
}

// HQ 1. visibility: eps-offset depth only.
// With the compute rasteriser (plan.compute): its visibility pass first, the rasteriser draws only what it
// left over, then its depths are merged into the depth target inside `rect` (where the accumulation runs).
void visibility_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, const glm::ivec4& rect) {
    glBindFramebuffer(GL_FRAMEBUFFER, s.depth_fbo.id());
    glDepthFunc(GL_LESS);
    auto scope = profiling::gpu_scope(reg, "render.hq.visibility");
    const bool big = !plan.compute.empty();
    if (big) compute_raster_visibility(s.compute_raster, plan.compute, plan.width, plan.height);
    for (const CloudGpu* gpu : plan.drawn) draw_cloud(s, s.visibility, *gpu, nullptr, big);
    if (big) {
        glEnable(GL_SCISSOR_TEST);
        glScissor(rect.x, rect.y, rect.z, rect.w);
        glBindVertexArray(s.vao.id());  // full-screen triangle from gl_VertexID, no attributes
        compute_raster_merge(s.compute_raster, plan.drawn.front()->frame_ubo.id());
        glDisable(GL_SCISSOR_TEST);
    }
}

// Whether the HQ passes of this frame run on the compute rasteriser (RenderSettings::raster_path), and its
// per-cloud inputs (plan.compute) when they do.
void plan_compute_raster(SplatRenderState& s, FramePlan& plan, bool materials, RenderStats& stats) {
    const RenderSettings& settings = plan.settings;
    if (settings.quality != Quality::hq || materials || plan.drawn.empty() || settings.raster_path == RasterPath::raster)
        return;
    if (settings.raster_path == RasterPath::automatic) {
        // Mean on-screen splat diameter over every drawn splat, against the measured break-even (compute_raster.h).
        double splats = 0, footprint = 0;
        for (const CloudGpu* gpu : plan.drawn) splats += gpu->count, footprint += gpu->count * gpu->footprint_px;
        const double limit = s.software ? compute_raster_software_max_footprint : compute_raster_hardware_max_footprint;
        if (!(footprint <= limit * splats)) return;
    }
    if (Status st = compute_raster_fits(plan.width, plan.height); !st) return warn_once("render_system(): " + st.message());
    if (Status st = init_compute_raster(s.compute_raster); !st) {
        log::error("render_system(): ", st.message());
        return;
    }
    for (CloudGpu* gpu : plan.drawn) {
        ensure_compute_raster_cloud(gpu->raster, gpu->capacity);
        plan.compute.push_back({&gpu->raster, gpu->frame_ubo.id(), gpu->records.id(), gpu->commands.id(), gpu->texture.id(),
                                gpu->count, gpu->capacity, gpu->flat_list});
        auto it = std::find_if(plan.gpu_counts.begin(), plan.gpu_counts.end(), [&](const CountsSource& c) { return c.gpu == gpu; });
        if (it == plan.gpu_counts.end()) plan.gpu_counts.push_back({gpu, counts_big});
        else it->parts |= counts_big;
    }
    stats.compute_rastered_clouds = std::uint32_t(plan.compute.size());
}

// Whether the drawn clouds differ in specular/shininess: then they blend into a third target (per-pixel
// materials); one material for every cloud is a uniform, as cheap as before.
bool clouds_differ_in_material(const FramePlan& plan) {
    return std::any_of(plan.drawn.begin(), plan.drawn.end(), [&](const CloudGpu* g) {
        return g->material->specular != plan.drawn.front()->material->specular ||
               g->material->shininess != plan.drawn.front()->material->shininess;
    });
}

// HQ 2. attributes: additive, depth-tested against the offset surface, no depth writes; only inside the
// screen rectangle the clouds can cover (`rect`: clears of two RGBA32F targets and the shading pass are a
// large part of a small scene's frame on llvmpipe). Leaves the scissor test on for shade_pass.
void attribute_pass(ecs::Registry& reg, const SplatRenderState& s, const FramePlan& plan, const glm::ivec4& rect,
                    bool materials) {
    glEnable(GL_SCISSOR_TEST);
    glScissor(rect.x, rect.y, rect.z, rect.w);
    const GLenum accum_buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glNamedFramebufferDrawBuffers(s.accum_fbo.id(), materials ? 3 : 2, accum_buffers);
    const glm::vec4 zero(0.0f);
    glClearNamedFramebufferfv(s.accum_fbo.id(), GL_COLOR, 0, &zero.x);
    glClearNamedFramebufferfv(s.accum_fbo.id(), GL_COLOR, 1, &zero.x);
    if (materials) glClearNamedFramebufferfv(s.accum_fbo.id(), GL_COLOR, 2, &zero.x);
    glBindFramebuffer(GL_FRAMEBUFFER, s.accum_fbo.id());
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    {
        auto scope = profiling::gpu_scope(reg, "render.hq.attribute");
        const bool big = !plan.compute.empty();
        for (const CloudGpu* gpu : plan.drawn)
            draw_cloud(s, s.attribute[gpu->texture ? 1 : 0][materials], *gpu, &s.attribute[0][materials][0], big);
        if (big) {
            compute_raster_attribute(s.compute_raster, plan.compute, rect, s.depth.id());
            glDepthFunc(GL_NOTEQUAL);  // the resolve runs where a surface is visible (not the cleared 1.0)
            glBindVertexArray(s.vao.id());
            compute_raster_resolve(s.compute_raster, plan.drawn.front()->frame_ubo.id());
        }
    }
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
}

// HQ 3. normalise + shade into the output targets. Early depth test skips background pixels (depth still
// 1.0) before the shader runs. Ends the scissor test attribute_pass began.
void shade_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, bool materials) {
    glBindFramebuffer(GL_FRAMEBUFFER, s.output_fbo.id());
    glBindTextureUnit(SFFD_TEX_ACCUM_COLOR, s.accum_color.id());
    glBindTextureUnit(SFFD_TEX_ACCUM_NORMAL, s.accum_normal.id());
    glBindTextureUnit(SFFD_TEX_ACCUM_MATERIAL, s.accum_material.id());
    glDepthFunc(GL_NOTEQUAL);
    glDepthMask(GL_FALSE);
    if (!plan.drawn.empty()) glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, plan.drawn.front()->frame_ubo.id());
    const std::uint32_t lights = std::min<std::uint32_t>(plan.common.counts.y, SFFD_MAX_LIGHTS);
    if (Status st = shade_program(s, materials, lights); !st) log::error("render_system(): ", st.message());
    glUseProgram(s.shade[materials][lights].id());
    {
        auto scope = profiling::gpu_scope(reg, "render.hq.shade");
        if (!plan.drawn.empty()) glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glDisable(GL_SCISSOR_TEST);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
}

void end_splat_passes() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);
    glUseProgram(0);
}

// The state resource, created on first use (a failed start is remembered: no retry every frame).
SplatRenderState& render_state(ecs::Registry& reg) {
    if (!reg.try_resource<SplatRenderState>()) {
        if (Status st = init_render_state(reg); !st) {
            log::error("render_system(): ", st.message());
            SplatRenderState failed;
            failed.failed = true;
            reg.set_resource<SplatRenderState>(std::move(failed));
        }
    }
    return reg.resource<SplatRenderState>();
}

}  // namespace

void render_system(ecs::Registry& reg, const FrameContext& frame) {
    SplatRenderState& s = render_state(reg);
    if (s.failed) return;
    if (!reg.try_resource<RenderSettings>()) reg.set_resource<RenderSettings>();
    if (!reg.try_resource<RenderStats>()) reg.set_resource<RenderStats>();
    RenderStats& stats = reg.resource<RenderStats>();
    stats = RenderStats{};
    stats.frame = frame.frame;

    s.cpu_splat_passes = 0;
    FramePlan plan;
    plan.settings = reg.resource<RenderSettings>();
    PassLaps laps(plan.settings.time_passes);
    plan.width = std::max(plan.settings.width, 1), plan.height = std::max(plan.settings.height, 1);
    ensure_targets(s, plan.width, plan.height);
    static const gfx::GpuSplatStore no_clouds;  // nothing resident: residency_system has not run
    const auto* store = reg.try_resource<gfx::GpuSplatStore>();
    s.cull_over_limit = false;
    reg.view<const SplatCloud>().each([&](const SplatCloud& c) { s.cull_over_limit |= !compute_cull_fits(c.size()).ok(); });
    sync_clouds(reg, s, store ? *store : no_clouds, cpu_cull_wanted(s, plan.settings.cull_path));
    plan.view = choose_camera(reg, s, double(plan.width) / double(plan.height));
    plan.common = frame_block(reg, plan.settings, plan.view, s.max_point_size);

    cull_pass(reg, s, plan, stats);
    const bool materials = plan.settings.quality == Quality::hq && clouds_differ_in_material(plan);
    plan_compute_raster(s, plan, materials, stats);
    // The counts ring's copies follow the passes that write the counts (cull; compute visibility).
    if (plan.compute.empty()) issue_counts(s, plan.gpu_counts, plan.cpu_points, plan.cpu_quads, stats.frame);
    laps.lap(stats.cull_ms);
    begin_splat_passes(s, plan);
    if (plan.settings.quality == Quality::preview) {
        preview_pass(reg, s, plan);
        laps.lap(stats.preview_ms);
    } else {
        const glm::ivec4 rect = screen_rect(reg, plan.view, plan.width, plan.height);
        visibility_pass(reg, s, plan, rect);
        if (!plan.compute.empty()) issue_counts(s, plan.gpu_counts, plan.cpu_points, plan.cpu_quads, stats.frame);
        laps.lap(stats.visibility_ms);
        attribute_pass(reg, s, plan, rect, materials);
        laps.lap(stats.attribute_ms);
        shade_pass(reg, s, plan, materials);
        laps.lap(stats.shade_ms);
    }
    end_splat_passes();
    // 3D Gaussians over the surface splats, depth-tested against them (gaussian_pass.h).
    if (reg.count<GaussianCloud>() > 0) {
        GaussianPassFrame gf;
        gf.camera = plan.view.camera, gf.view = plan.view.view, gf.projection = plan.view.projection;
        gf.output_fbo = s.output_fbo.id(), gf.color = s.color.id(), gf.aux = s.aux.id(), gf.depth = s.depth.id();
        gf.width = plan.width, gf.height = plan.height, gf.aux_outputs = plan.settings.aux_outputs;
        gf.preview = plan.settings.quality == Quality::preview;
        auto drawn = gaussian_pass(reg, gf);
        if (!drawn) log::error("render_system(): ", drawn.message());
        else stats.gaussians = *drawn;
        laps.lap(stats.gaussian_ms);
    }
    // Visible counts of the newest frame whose read-back has landed (with time_passes: this frame, the
    // glFinish of the laps has completed it; otherwise usually a frame or two back). Never waits.
    collect_counts(s);
    stats.counts_frame = s.counts_frame;
    stats.counts_valid = s.counts_serial != 0;
    stats.visible_points = s.counts_points;
    stats.visible_quads = s.counts_quads;
    stats.raster_sprites = s.counts_raster_sprites;
    stats.cpu_splat_passes = s.cpu_splat_passes;
    s.last_background = plan.common.background;
    if (plan.settings.time_passes) stats.total_ms = laps.total_ms();
}

void display_system(ecs::Registry& reg, const FrameContext&) {
    SplatRenderState* s = reg.try_resource<SplatRenderState>();
    if (!s || s->failed || !s->output_fbo) return;
    // Only a window shows the frame (headless runs capture the linear target).
    const auto* app_ctx = reg.try_resource<app::AppContext>();
    if (!app_ctx || !app_ctx->context || app_ctx->context->is_headless()) return;
    const int w = s->width, h = s->height;
    if (!s->display_fbo || s->display_width != w || s->display_height != h) {
        s->display_color = make_target(GL_RGBA8, w, h, "render.display");
        s->display_fbo = gfx::Framebuffer::create("render.display");
        glNamedFramebufferTexture(s->display_fbo.id(), GL_COLOR_ATTACHMENT0, s->display_color.id(), 0);
        s->display_width = w, s->display_height = h;
    }
    if (!s->display_ubo) {
        s->display_ubo = gfx::Buffer::create("render.display_block");
        glNamedBufferData(s->display_ubo.id(), sizeof(gpu::FrameBlock), nullptr, GL_DYNAMIC_DRAW);
    }
    gpu::FrameBlock b{};
    b.background = s->last_background;
    glNamedBufferSubData(s->display_ubo.id(), 0, sizeof b, &b);
    glBindFramebuffer(GL_FRAMEBUFFER, s->display_fbo.id());
    glViewport(0, 0, w, h);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, s->display_ubo.id());
    glBindTextureUnit(SFFD_TEX_ACCUM_COLOR, s->color.id());
    glBindVertexArray(s->vao.id());  // empty: the triangle comes from gl_VertexID
    glUseProgram(s->display.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glEnable(GL_DEPTH_TEST);
    glBindVertexArray(0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    auto& present = reg.try_resource<app::PresentSource>() ? reg.resource<app::PresentSource>()
                                                           : reg.set_resource<app::PresentSource>();
    present = app::PresentSource{s->display_fbo.id(), GL_COLOR_ATTACHMENT0, w, h};
}

Result<FrameImage> capture_frame(ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    if (!s || s->failed || !s->output_fbo) return make_error("capture_frame(): nothing rendered yet");
    const int w = s->width, h = s->height;
    const std::size_t n = std::size_t(w) * std::size_t(h);
    std::vector<glm::vec4> color(n), aux(n);
    glGetTextureImage(s->color.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(n * sizeof(glm::vec4)), color.data());
    if (s->aux_valid) glGetTextureImage(s->aux.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(n * sizeof(glm::vec4)), aux.data());
    FrameImage img;
    img.width = w, img.height = h;
    img.color.resize(n), img.depth.resize(n), img.normal.resize(n);
    for (int y = 0; y < h; ++y) {  // GL rows are bottom-up, images top-down
        const std::size_t src_row = std::size_t(h - 1 - y) * std::size_t(w), dst_row = std::size_t(y) * std::size_t(w);
        for (int x = 0; x < w; ++x) {
            const glm::vec4& c = color[src_row + std::size_t(x)];
            const glm::vec4& a = aux[src_row + std::size_t(x)];
            const bool hit = c.w > 0.0f && (!s->aux_valid || a.w >= 0.0f);
            img.color[dst_row + std::size_t(x)] = hit ? c : glm::vec4(0.0f);
            img.depth[dst_row + std::size_t(x)] = hit && s->aux_valid ? a.w : std::numeric_limits<float>::infinity();
            img.normal[dst_row + std::size_t(x)] = hit && s->aux_valid ? glm::vec3(a) : glm::vec3(0.0f);
        }
    }
    return img;
}

GLuint output_framebuffer(const ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    return s ? s->output_fbo.id() : 0;
}

GLuint output_color_texture(const ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    return s ? s->color.id() : 0;
}

}  // namespace sffd::render
