// Splat render system: the state resource, its programs and render targets, and the per-cloud GPU objects.
#include "systems/splat_render/splat_render_detail.h"

namespace sffd::render {

namespace {

using namespace detail;

Result<gfx::Program> splat_program(const char* fragment, const char* label, int pass, int quad, int aux = 1,
                                   int materials = 0, int textured = -1) {
    gfx::Defines defines{{"PASS", std::to_string(pass)},
                         {"SHAPE_QUAD", std::to_string(quad)},
                         {"AUX", std::to_string(aux)},
                         {"MATERIALS", std::to_string(materials)}};
    if (textured >= 0) defines.push_back({"TEXTURED", std::to_string(textured)});  // else read per draw
    return gfx::load_program({{GL_VERTEX_SHADER, "splat_render/splat.vert"}, {GL_FRAGMENT_SHADER, fragment}},
                             label, defines);
}

}  // namespace

namespace detail {

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

// Whether the CPU cull may run this frame, so CPU copies of the splats are worth keeping.
bool cpu_cull_wanted(const SplatRenderState& s, CullPath path) {
    return path == CullPath::cpu || (path == CullPath::automatic && (s.software || s.cull_over_limit));
}

namespace {

// The cloud's point marks this frame: the residency's buffers and the mode bits (frame.counts.z) for what
// it holds and what `settings` asks to see; the columns for the CPU cull. An overlay (tint, weights) draws
// a textured cloud flat, each splat in the texel at its centre (SFFD_MARKS_TEXEL), by the untextured
// programs.
void sync_marks(const ecs::Registry& reg, ecs::Entity e, const SplatCloud& cloud,
                const gfx::GpuSplats& splats, const RenderSettings& settings, CloudGpu& gpu) {
    std::uint32_t mode = gfx::resident_marks_mode(splats);
    if (settings.show_selection && (mode & SFFD_MARKS_PRESENT) && splats.marks_state.any_selected())
        mode |= SFFD_MARKS_SELECTION;
    if (settings.show_weights) mode |= SFFD_MARKS_WEIGHTS;
    gpu.marks_mode = mode;
    gpu.marks = mode & SFFD_MARKS_PRESENT ? splats.marks.id() : 0;
    gpu.preview_index = mode & SFFD_MARKS_INDEXED ? splats.preview_index.id() : 0;
    gpu.cpu_marks = {};
    if (mode & SFFD_MARKS_PRESENT) {
        const std::size_t n = cloud.size();
        const PointFlags* flags = reg.try_get<PointFlags>(e);
        const PointWeights* weights = reg.try_get<PointWeights>(e);
        gpu.cpu_marks.flags = flags && flags->bits.size() == n ? flags->bits.data() : nullptr;
        gpu.cpu_marks.weights = weights && weights->values.size() == n ? weights->values.data() : nullptr;
        gpu.cpu_marks.points = n;
        if (mode & SFFD_MARKS_INDEXED)
            gpu.cpu_marks.index = splats.preview_indices.data(),
            gpu.cpu_marks.index_count = splats.preview_indices.size();
    }
    gpu.overlay_texture = 0;
    if ((mode & (SFFD_MARKS_SELECTION | SFFD_MARKS_WEIGHTS)) && gpu.texture) {
        // Drawn flat: each splat in its centre's texel, then the overlay (the tint has no slot in the
        // per-pixel lookups' records).
        gpu.marks_mode |= SFFD_MARKS_TEXEL;
        gpu.cpu_marks.texels = {cloud.texture.rgba8.data(), cloud.texture.width, cloud.texture.height};
        gpu.overlay_texture = gpu.texture;
        gpu.texture = 0, gpu.uv_axes = 0;
        gpu.uv_axes_cpu = nullptr;
    }
}

}  // namespace

void bind_marks(const SplatRenderState& s, const CloudGpu& gpu) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_POINT_MARKS,
                     gpu.marks ? gpu.marks : s.command_reset.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_PREVIEW_INDEX,
                     gpu.preview_index ? gpu.preview_index : s.command_reset.id());
}

// Refreshes the renderer's own per-cloud objects (cull buffers, bounds) for the clouds that are resident
// in GpuSplatStore (residency_system uploads them and their textures; this only reads the store) and
// drops objects of clouds that no longer exist. cpu_cull: the CPU cull may run, so name the resident
// cloud whose draw buffer it reads (cpu_source).
void sync_clouds(ecs::Registry& reg, SplatRenderState& s, gfx::GpuSplatStore* store, bool cpu_cull,
                 const RenderSettings& settings) {
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        gfx::GpuSplats* resident = nullptr;
        if (store)
            if (auto it = store->clouds.find(e); it != store->clouds.end()) resident = &it->second;
        if (!resident) {  // not resident (no residency phase ran): not drawn
            reg.remove<CloudGpu>(e);
            return;
        }
        gfx::GpuSplats& splats = *resident;
        const std::uint64_t version = reg.version<SplatCloud>(e);
        CloudGpu* made = reg.try_get<CloudGpu>(e);
        CloudGpu& gpu = made ? *made : reg.emplace<CloudGpu>(e);
        const auto n = static_cast<std::uint32_t>(cloud.size());
        if (!gpu.frame_ubo) {
            gpu.frame_ubo = gfx::Buffer::create("render.frame_block");
            glNamedBufferData(gpu.frame_ubo.id(), sizeof(gpu::FrameBlock), nullptr, GL_DYNAMIC_DRAW);
            gpu.commands = gfx::Buffer::create("render.draw_commands");
            glNamedBufferData(gpu.commands.id(), draw_command_words * sizeof(std::uint32_t), nullptr,
                              GL_DYNAMIC_DRAW);
        }
        // The flat-coloured run after the capacity is written and read for textured clouds only: an
        // untextured cloud's buffer holds one run (96 bytes a splat instead of 192, host memory on llvmpipe).
        const std::uint32_t runs = splats.texture.id() ? 2u : 1u;
        if (gpu.capacity < n || !gpu.records || gpu.record_runs < runs) {
            gpu.capacity = std::max<std::uint32_t>(n, 1);
            gpu.record_runs = runs;
            gpu.records = gfx::Buffer::create("render.visible_splats");
            glNamedBufferData(gpu.records.id(),
                              GLsizeiptr(runs * std::size_t(gpu.capacity) * sizeof(SplatRecord)), nullptr,
                              GL_DYNAMIC_DRAW);
            gpu.quads = gfx::Buffer::create("render.visible_quads");
            glNamedBufferData(gpu.quads.id(), GLsizeiptr(std::size_t(gpu.capacity) * sizeof(std::uint32_t)),
                              nullptr, GL_DYNAMIC_DRAW);
        }
        gpu.texture = splats.texture.id();
        gpu.uv_axes = gpu.texture ? splats.uv_axes.id() : 0;
        if (gpu.texture_version != splats.texture_version) {
            // The CPU cull's per-texture data (derived on the CPU, never uploaded).
            gpu.uniform_radius.clear();
            gpu.pyramid = {}, gpu.pyramid_made = false;
            if (gpu.texture)
                gpu.uniform_radius = uniform_texel_radius(cloud.texture.rgba8.data(), cloud.texture.width,
                                                          cloud.texture.height);
            gpu.texture_version = splats.texture_version;
        }
        gpu.uv_axes_cpu = gpu.texture && cloud.uv_axes.size() == n ? &cloud.uv_axes : nullptr;
        gpu.texture_texels = &cloud.texture;
        // The framing camera's bounds leave hidden and deleted points out (recomputed when the flags move).
        const std::uint64_t flags_version = std::as_const(reg).version<PointFlags>(e);
        if (gpu.bounds_version != version || gpu.bounds_flags_version != flags_version) {
            gpu.bounds = bounding_sphere(cloud, std::as_const(reg).try_get<PointFlags>(e));
            gpu.bounds_flags_version = flags_version;
            gpu.mean_radius = mean_splat_radius(cloud);
            ++s.cpu_splat_passes;
            gpu.bounds_version = version;
        }
        // Read every frame, never uploaded: a material edit changes this cloud's uniforms only.
        const SplatMaterial* material = reg.try_get<SplatMaterial>(e);
        gpu.material = material ? *material : SplatMaterial{};
        gpu.colored = cloud.colors.size() == n;
        gpu.count = std::min(n, splats.drawn_count());  // a budgeted preview draws a subset
        gpu.splats = splats.draw_buffer();
        sync_marks(reg, e, cloud, splats, settings, gpu);
        // What the CPU cull may read: the rest splats, or the CPU deformation's output; the FFD compute
        // pass's output only when its compute-cull records exceed one storage block (it has no other way).
        gpu.cpu_source = nullptr;
        if (!cpu_cull) {
            gpu.cpu_cull = {};
            return;
        }
        const bool current = splats.rest_version == version && gpu.count == splats.drawn_count();
        if (!current) return;
        if (splats.state != gfx::Residency::deformed_gpu) {
            gpu.cpu_source = &splats;
        } else if (const Status fits = compute_cull_fits(gpu.count); !fits) {
            warn_once("render_system(): " + fits.message() +
                      ": a deformed cloud is read back from the GPU and culled on the CPU");
            gpu.cpu_source = &splats;
        }
    });
}

// The cull pass variant for an (un)textured material, (un)lit colours and `lights` lights, compiled once.
Status cull_program(SplatRenderState& s, bool textured, bool lit, std::uint32_t lights) {
    lights = std::min<std::uint32_t>(lights, SFFD_MAX_LIGHTS);
    gfx::Program& program = s.cull[textured][lit][lit ? lights : 0];
    if (program) return {};
    auto cull = gfx::load_compute_program("splat_render/cull.comp", "render.cull",
                                          {{"TEXTURED", textured ? "1" : "0"},
                                           {"LIT", lit ? "1" : "0"},
                                           {"LIGHTS", std::to_string(lit ? lights : 0)}});
    if (!cull) return make_error(cull.message());
    program = std::move(cull.value());
    return {};
}

gfx::RadixSorter* scan_programs(SplatRenderState& s) {
    if (!s.scan) {
        auto scan = gfx::create_radix_sorter();
        if (!scan) {
            log::error("render_system(): ", scan.message());
            return nullptr;
        }
        s.scan = std::move(*scan);
    }
    return &*s.scan;
}

// The deferred shading program for `lights` directional lights (LIGHTS in lighting.glsl), with one
// material for the frame or blended ones (MATERIALS), compiled once.
Status shade_program(SplatRenderState& s, bool materials, std::uint32_t lights) {
    gfx::Program& program = s.shade[materials][std::min<std::uint32_t>(lights, SFFD_MAX_LIGHTS)];
    if (program) return {};
    auto shade = gfx::load_program(
        {{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "splat_render/shade.frag"}},
        "render.shade", {{"LIGHTS", std::to_string(lights)}, {"MATERIALS", materials ? "1" : "0"}});
    if (!shade) return make_error(shade.message());
    program = std::move(shade.value());
    return {};
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

}  // namespace detail

using namespace detail;

Status init_render_state(ecs::Registry& registry) {
    SplatRenderState s;
    if (Status st = cull_program(s, false, false, 1); !st) return st;
    for (int quad = 0; quad < 2; ++quad) {
        auto vis = splat_program("splat_render/visibility.frag",
                                 quad ? "render.visibility.quads" : "render.visibility", 0, quad, 0);
        if (!vis) return make_error(vis.message());
        for (int textured = 0; textured < 2; ++textured)
            for (int materials = 0; materials < 2; ++materials) {
                auto attr = splat_program("splat_render/attribute.frag",
                                          quad ? "render.attribute.quads" : "render.attribute", 1, quad, 0,
                                          materials, textured);
                if (!attr) return make_error(attr.message());
                s.attribute[textured][materials][quad] = std::move(attr.value());
            }
        for (int textured = 0; textured < 2; ++textured)
            for (int aux = 0; aux < 2; ++aux) {
                auto prev = splat_program("splat_render/preview.frag",
                                          quad ? "render.preview.quads" : "render.preview", 2, quad, aux, 0,
                                          textured);
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
    s.min_point_size = range[0];
    s.software = gfx::software_rasterizer();
    s.cloud_gone = registry.on_destroy<SplatCloud>().connect(
        [](ecs::Registry& reg, ecs::Entity e) { reg.remove<CloudGpu>(e); });
    registry.set_resource<SplatRenderState>(std::move(s));
    return {};
}

void release_render_state(ecs::Registry& registry) {
    release_gaussian_pass(registry);
    std::vector<ecs::Entity> drawn;
    registry.view<const CloudGpu>().each([&](ecs::Entity e, const CloudGpu&) { drawn.push_back(e); });
    for (ecs::Entity e : drawn) registry.remove<CloudGpu>(e);
    registry.erase_resource<SplatRenderState>();
}

}  // namespace sffd::render
