// Splat render system: the cull pass (compute cull or CPU cull) that fills the draw lists.
#include "systems/splat_render/splat_render_detail.h"

#include "runtime/gfx/splat_pack.h"

namespace sffd::render::detail {

namespace {

// The CPU cull's quad list into `gpu.quads`: as it is when the splats the quad pass reads fit one storage
// block; else regrouped per range of splats (storage_limits.h), the quad pass then drawing range by range.
Status upload_quads(CloudGpu& gpu) {
    const CpuCullResult& r = gpu.cpu_cull;
    gpu.quad_batches.clear();
    const std::uint64_t strides[] = {sizeof(gpu::GpuSplat), gpu.texture ? sizeof(glm::vec4) : 0};
    auto batches = gfx::ssbo_batches(gpu.count, strides);
    if (!batches) return batches.error();
    if (batches->size() <= 1) {
        CpuCullResult::for_each_run(
            r.quads, r.quad_counts, r.block, [&](std::size_t at, const std::uint32_t* p, std::size_t k) {
                glNamedBufferSubData(gpu.quads.id(), GLintptr(at * sizeof(std::uint32_t)),
                                     GLsizeiptr(k * sizeof(std::uint32_t)), p);
            });
        return {};
    }
    std::vector<std::uint32_t> quads, laid_out;
    quads.reserve(r.visible_quads);
    CpuCullResult::for_each_run(
        r.quads, r.quad_counts, r.block,
        [&](std::size_t, const std::uint32_t* p, std::size_t k) { quads.insert(quads.end(), p, p + k); });
    const auto align_words = std::uint32_t(std::max(gfx::limits().ssbo_offset_alignment, 4) / 4);
    gpu.quad_batches = layout_quad_batches(quads, *batches, align_words, laid_out);
    // The alignment padding can outgrow the capacity-sized list: grow it (rare: clouds past the limit).
    GLint64 size = 0;
    glGetNamedBufferParameteri64v(gpu.quads.id(), GL_BUFFER_SIZE, &size);
    const std::size_t bytes = laid_out.size() * sizeof(std::uint32_t);
    if (std::uint64_t(size) < bytes)
        glNamedBufferData(gpu.quads.id(), GLsizeiptr(bytes), nullptr, GL_DYNAMIC_DRAW);
    if (!laid_out.empty()) glNamedBufferSubData(gpu.quads.id(), 0, GLsizeiptr(bytes), laid_out.data());
    return {};
}

// The base colour as 8-bit sRGB, decoded as the shaders decode packed colours: what a cloud without
// colours drew when its base colour was packed into every splat, so its images stay the same.
glm::vec4 quantised_base_color(const glm::vec4& linear) {
    glm::vec4 out(1.0f);
    for (int k = 0; k < 3; ++k)
        out[k] = std::pow((float(gfx::encode_srgb8(linear[k])) / 255.0f + 0.055f) * (1.0f / 1.055f), 2.4f);
    return out;
}

// The compute cull of one cloud (cull.comp), with its frame block bound: a count pass, the exclusive scan
// of the work groups' counts, and the pass that writes the lists in splat order at the scanned offsets.
Status compute_cull(SplatRenderState& s, CloudGpu& gpu, GLuint program, bool textured) {
    gfx::RadixSorter* scan = scan_programs(s);
    if (!scan) return make_error("the compute cull has no scan programs");
    const std::uint32_t groups = (gpu.count + SFFD_CULL_GROUP_SIZE - 1) / SFFD_CULL_GROUP_SIZE;
    if (!gpu.cull_groups || gpu.cull_group_capacity < groups) {
        gpu.cull_groups = gfx::Buffer::create("render.cull_groups");
        glNamedBufferStorage(gpu.cull_groups.id(),
                             GLsizeiptr((2 * std::size_t(groups) + 1) * sizeof(std::uint32_t)), nullptr, 0);
        gpu.cull_group_capacity = groups;
    }
    // The scan binds its own buffers: both passes bind theirs.
    const auto bind = [&](std::uint32_t count_pass) {
        glUseProgram(program);
        glProgramUniform1ui(program, SFFD_LOC_CULL_PASS, count_pass);
        glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, gpu.frame_ubo.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_DRAW, gpu.splats);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE, gpu.quads.id());
        // Only the sprites' run of the records (compute_cull_fits: the whole buffer may exceed one block).
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE_SPLATS, gpu.records.id(), 0,
                          GLsizeiptr(std::size_t(gpu.count) * sizeof(SplatRecord)));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_DRAW_INDIRECT, gpu.commands.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_CULL_GROUPS, gpu.cull_groups.id());
        if (textured) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_UV_AXES, gpu.uv_axes);
        bind_marks(s, gpu);
        glBindTextureUnit(SFFD_TEX_MATERIAL, material_texture(gpu));
    };
    // A compute pass, not a vertex shader with rasterizer discard: llvmpipe runs compute on its worker
    // threads, vertex shaders on the calling thread (measured: same CPU, 2x the main-thread time).
    bind(1);
    if (Status st = gfx::dispatch_1d(gpu.count, SFFD_CULL_GROUP_SIZE); !st) return st;
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "render.cull.count");
    if (Status st = gfx::exclusive_scan(*scan, gpu.cull_groups.id(), 2 * groups); !st) return st;
    bind(0);
    return gfx::dispatch_1d(gpu.count, SFFD_CULL_GROUP_SIZE);
}

// The CPU cull's draw commands, and with `sprites` its sprite records (a textured cloud's flat-coloured ones
// after the capacity) uploaded run by run into the buffer the draws read; without, the commands draw only
// the quads.
void upload_cpu_culled(CloudGpu& gpu, bool sprites) {
    const CpuCullResult& r = gpu.cpu_cull;
    auto upload = [&](const auto& records, const auto& counts, std::size_t offset) {
        CpuCullResult::for_each_run(
            records, counts, r.block, [&](std::size_t at, const SplatRecord* p, std::size_t k) {
                glNamedBufferSubData(gpu.records.id(), GLintptr((offset + at) * sizeof(SplatRecord)),
                                     GLsizeiptr(k * sizeof(SplatRecord)), p);
            });
    };
    if (sprites) {
        upload(r.records, r.record_counts, 0);
        upload(r.flat_records, r.flat_counts, gpu.capacity);
    }
    const std::uint32_t commands[draw_command_words] = {sprites ? r.visible_records : 0u,
                                                        1,
                                                        0,
                                                        0,
                                                        6,
                                                        r.visible_quads,
                                                        0,
                                                        0,
                                                        sprites ? r.visible_flat : 0u,
                                                        1,
                                                        gpu.capacity,
                                                        0};
    glNamedBufferSubData(gpu.commands.id(), 0, sizeof commands, commands);
    gpu.gl_sprites = sprites;
}

}  // namespace

void upload_gl_sprites(const FramePlan& plan) {
    const bool hq = plan.settings.quality == Quality::hq;
    for (CloudGpu* gpu : plan.drawn)
        if (!gpu->gl_sprites && (!gpu->cpu_raster || (hq && !plan.cpu_hq))) upload_cpu_culled(*gpu, true);
}

// Per-cloud uniforms, then culling and compaction of every cloud (the compute pass, or cpu_cull.h).
void cull_pass(ecs::Registry& reg, SplatRenderState& s, FramePlan& plan, RenderStats& stats) {
    const RenderSettings& settings = plan.settings;
    auto scope = profiling::gpu_scope(reg, "render.cull");
    // Write-after-read across frames: the last frame's draws fetched records, quads and commands that this
    // pass overwrites, by shader stores (compute cull) or by copies and sub-data uploads (CPU cull).
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT, "render.cull.reuse");
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        CloudGpu* made = reg.try_get<CloudGpu>(e);
        if (!made || made->count == 0 || made->splats == 0) return;
        CloudGpu& gpu = *made;
        gpu::FrameBlock b = plan.common;
        const glm::dmat4 mv = plan.view.view * model_matrix(reg.try_get<Transform>(e), cloud.origin);
        b.model_view = glm::mat4(mv);
        b.normal_view = glm::mat4(glm::mat3(glm::inverseTranspose(glm::dmat3(mv))));
        gpu.footprint_px = splat_footprint_px(mv, gpu.bounds.center, gpu.mean_radius,
                                              plan.view.projection[1][1], plan.height);
        gpu.flat_list = false;
        gpu.cpu_raster = false;
        gpu.gl_sprites = true;  // the compute cull writes them; a CPU cull says (upload_cpu_culled)
        b.params.w = gpu.texture ? 1.0f : 0.0f;
        b.material = glm::vec4(gpu.material.specular, gpu.material.shininess, 0.0f, 0.0f);
        b.base_color = gpu.colored ? glm::vec4(1.0f) : quantised_base_color(gpu.material.base_color);
        b.counts.x = gpu.count;
        b.counts.z = gpu.marks_mode;  // point marks: gone points dropped, overlays (point_marks.glsl)
        b.counts.w = settings.quality == Quality::preview ? 1u : 0u;  // cull pass lights sprites in preview
        glNamedBufferSubData(gpu.frame_ubo.id(), 0, sizeof b, &b);
        // A cloud whose compute-cull records exceed one storage block takes the CPU cull on every path
        // (its splats read back when they exist only on the GPU: sync_clouds).
        const Status fits = compute_cull_fits(gpu.count);
        if (gpu.cpu_source && (!fits || cpu_cull_wanted(s, settings.cull_path))) {
            if (!fits && settings.cull_path != CullPath::cpu)
                warn_once("render_system(): " + fits.message() + "; the CPU cull takes the cloud");
            // CPU cull (cpu_cull.h): the same records, uploaded run by run into the buffers the draws read.
            TexelView texels;
            if (gpu.texture)
                texels = {gpu.texture_texels->rgba8.data(), gpu.texture_texels->width,
                          gpu.texture_texels->height, gpu.uv_axes_cpu ? gpu.uv_axes_cpu->data() : nullptr,
                          gpu.uniform_radius.empty() ? nullptr : gpu.uniform_radius.data()};
            const bool reduced_flat = settings.quality == Quality::preview && settings.preview_divider > 1 &&
                                      settings.reduced_preview_flat_texture;
            // The CPU rasteriser samples the texture's levels itself; a reduced preview colours sprites once.
            if (gpu.texture && (reduced_flat || plan.cpu_raster)) {
                if (!gpu.pyramid_made) {
                    gpu.pyramid =
                        build_texture_pyramid(gpu.texture_texels->rgba8.data(), gpu.texture_texels->width,
                                              gpu.texture_texels->height);
                    gpu.pyramid_made = true;
                }
                if (reduced_flat) texels.pyramid = &gpu.pyramid;
            }
            gpu.raster_texels = texels;
            gpu.raster_texels.pyramid = gpu.pyramid_made ? &gpu.pyramid : nullptr;
            CpuCullResult& r = gpu.cpu_cull;
            {
                // Read in place (mapped) or from the residency's copy; released before GL draws it.
                const gfx::CpuSplatRead read = gfx::read_splats_on_cpu(*gpu.cpu_source);
                if (read.splats().size() != gpu.count) {
                    warn_once("render_system(): a cloud's splats could not be read on the CPU; not drawn");
                    return;
                }
                cull_splats_cpu(read.splats(), b, texels, r, gpu.cpu_marks);
            }
            ++s.cpu_splat_passes;
            // On the CPU sprite path the sprites are the CPU's (preview_pass, visibility_pass): they reach
            // GL only if the frame turns out to need them there (upload_gl_sprites).
            gpu.cpu_raster = plan.cpu_raster;
            if (Status st = upload_quads(gpu); !st) {
                warn_once("render_system(): " + st.message() + "; the cloud is not drawn");
                return;
            }
            upload_cpu_culled(gpu, !gpu.cpu_raster);
            plan.drawn_lo = glm::min(plan.drawn_lo, r.pixels_lo);
            plan.drawn_hi = glm::max(plan.drawn_hi, r.pixels_hi);
            plan.drawn_known = plan.drawn_known && r.pixels_bounded;
            plan.cpu_points += r.visible_records + r.visible_flat;
            plan.cpu_quads += r.visible_quads;
            gpu.flat_list = bool(gpu.texture);
            ++stats.cpu_culled_clouds;
        } else {
            // Reset the counts on the GPU (a copy from an immutable buffer): a CPU upload into a buffer the
            // GPU writes every frame makes drivers move it to host memory (NVIDIA's performance warning).
            // The third command (flat-coloured sprites) stays empty: only the CPU cull fills it.
            if (!fits) {  // no CPU copy of the splats could be made (not resident as this version yet)
                warn_once("render_system(): " + fits.message() + "; the cloud is not drawn");
                return;
            }
            plan.drawn_known = false;  // the sprites' squares stay on the GPU
            glCopyNamedBufferSubData(s.command_reset.id(), gpu.commands.id(), 0, 0,
                                     draw_command_words * sizeof(std::uint32_t));
            const bool textured = bool(gpu.texture), lit = b.counts.w == 1u;
            if (Status st = cull_program(s, textured, lit, b.counts.y); !st)
                log::error("render_system(): ", st.message());
            const GLuint program =
                s.cull[textured][lit][lit ? std::min<std::uint32_t>(b.counts.y, SFFD_MAX_LIGHTS) : 0].id();
            if (Status st = compute_cull(s, gpu, program, textured); !st)
                log::error("render_system(): ", st.message());
            ++stats.compute_culled_clouds;
            plan.gpu_counts.push_back({&gpu, counts_cull});
        }
        stats.splats += gpu.count;
        plan.drawn.push_back(&gpu);
    });
    // Records are fetched as vertex attributes (records_vao), quads and records read as SSBOs, commands
    // drawn indirectly and copied into the counts ring.
    gfx::memory_barrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT |
                            GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT,
                        "render.cull");
}

}  // namespace sffd::render::detail
