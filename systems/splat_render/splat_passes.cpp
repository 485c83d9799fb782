// Splat render system: the splat passes (preview; HQ visibility, attributes, shading).
#include "systems/splat_render/splat_render_detail.h"

namespace sffd::render::detail {

namespace {

// The quad pass range by range (CloudGpu::quad_batches: splats past one storage block): each range's splats,
// uv axes and quads bound from its start, the quads' indices being relative to it; the counts are the CPU
// cull's. Leaves the whole buffers bound again for the passes after it.
void draw_quad_batches(const CloudGpu& gpu, GLuint program) {
    // The quads' marks are the whole cloud's: the range's first splat offsets them (passes with colour).
    const bool marked = glGetUniformLocation(program, "u_quad_mark_base") == SFFD_LOC_QUAD_MARK_BASE;
    for (const QuadBatch& b : gpu.quad_batches) {
        if (b.quad_count == 0) continue;
        if (marked) glProgramUniform1ui(program, SFFD_LOC_QUAD_MARK_BASE, GLuint(b.splats.first));
        gfx::bind_ssbo_range(SFFD_SSBO_SPLATS_DRAW, gpu.splats, b.splats, sizeof(gpu::GpuSplat));
        gfx::bind_ssbo_range(SFFD_SSBO_VISIBLE, gpu.quads.id(), {b.quad_first, b.quad_count},
                             sizeof(std::uint32_t));
        if (gpu.texture) gfx::bind_ssbo_range(SFFD_SSBO_UV_AXES, gpu.uv_axes, b.splats, sizeof(glm::vec4));
        glDrawArraysInstanced(GL_TRIANGLES, 0, 6, GLsizei(b.quad_count));
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_DRAW, gpu.splats);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE, gpu.quads.id());
    if (gpu.texture) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_UV_AXES, gpu.uv_axes);
    if (marked) glProgramUniform1ui(program, SFFD_LOC_QUAD_MARK_BASE, 0);
}

// programs: [sprites, quads] for the cloud; flat: the program for a textured cloud's flat-coloured sprites
// (CpuCullResult::flat_records: the untextured variant of the pass; null for passes without colour).
// big: the HQ passes of the compute rasteriser's frame draw only the sprites it left to them (indexed
// draws over ComputeRasterCloud::big) and the quads.
// sprites false: only the quads (the CPU drew the sprites of this pass).
void draw_cloud(const SplatRenderState& s, const std::array<gfx::Program, 2>& programs, const CloudGpu& gpu,
                const gfx::Program* flat = nullptr, bool big = false, bool sprites = true) {
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, gpu.frame_ubo.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_DRAW, gpu.splats);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE, gpu.quads.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE_SPLATS, gpu.records.id());
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.commands.id());
    glBindTextureUnit(SFFD_TEX_MATERIAL, material_texture(gpu));
    if (gpu.texture) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_UV_AXES, gpu.uv_axes);
    bind_marks(s, gpu);
    glVertexArrayVertexBuffer(s.records_vao.id(), 0, gpu.records.id(), 0, GLsizei(SFFD_SPLAT_RECORD_BYTES));
    if (big) glVertexArrayElementBuffer(s.records_vao.id(), gpu.raster.big.id());
    glBindVertexArray(s.records_vao.id());
    glUseProgram(programs[0].id());
    if (sprites && big) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.raster.commands.id());
        glDrawElementsIndirect(GL_POINTS, GL_UNSIGNED_INT, nullptr);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.commands.id());
    } else if (sprites) {
        glDrawArraysIndirect(GL_POINTS, nullptr);
    }
    glBindVertexArray(s.vao.id());
    glUseProgram(programs[1].id());
    if (gpu.quad_batches.empty())
        glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(4 * sizeof(std::uint32_t)));
    else draw_quad_batches(gpu, programs[1].id());
    if (gpu.texture && sprites) {
        glBindVertexArray(s.records_vao.id());
        glUseProgram(flat ? flat->id() : programs[0].id());
        if (big) {
            glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gpu.raster.commands.id());
            glDrawElementsIndirect(GL_POINTS, GL_UNSIGNED_INT,
                                   reinterpret_cast<const void*>(5 * sizeof(std::uint32_t)));
        } else {
            glDrawArraysIndirect(GL_POINTS, reinterpret_cast<const void*>(8 * sizeof(std::uint32_t)));
        }
    }
}

// The preview programs over every drawn cloud, into the output targets (preview_pass, the warm-up).
void draw_preview_clouds(const SplatRenderState& s, const FramePlan& plan) {
    glBindFramebuffer(GL_FRAMEBUFFER, s.output_fbo.id());
    glDepthFunc(GL_LESS);
    const int aux = plan.settings.aux_outputs ? 1 : 0;
    for (const CloudGpu* gpu : plan.drawn) {
        // Nothing left for GL when the CPU drew the sprites and no quad was kept.
        if (gpu->cpu_raster && gpu->cpu_cull.visible_quads == 0) continue;
        draw_cloud(s, s.preview[gpu->texture ? 1 : 0][aux], *gpu, &s.preview[0][aux][0]);
    }
}

}  // namespace

// Clears the output targets and sets the state every splat pass shares.
void begin_splat_passes(SplatRenderState& s, const FramePlan& plan) {
    const RenderSettings& settings = plan.settings;
    const glm::vec4 background = plan.common.background;
    const glm::vec4 no_hit(0.0f, 0.0f, 0.0f, -1.0f);
    const float far_depth = 1.0f;
    // Only the frame's pixels: a reduced preview reads nothing outside its corner, and on a CPU rasteriser
    // clearing the whole RGBA32F + depth targets was 1.6 ms of a half-size preview of the sphere.
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, plan.width, plan.height);
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_COLOR, 0, &background.x);
    if (settings.aux_outputs) glClearNamedFramebufferfv(s.output_fbo.id(), GL_COLOR, 1, &no_hit.x);
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_DEPTH, 0, &far_depth);
    glDisable(GL_SCISSOR_TEST);
    glViewport(0, 0, plan.width, plan.height);
    glBindVertexArray(s.vao.id());
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);

    // Without aux outputs only attachment 0 is written (the preview program variant has no aux output).
    const GLenum with_aux[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1},
                 without_aux[2] = {GL_COLOR_ATTACHMENT0, GL_NONE};
    glNamedFramebufferDrawBuffers(s.output_fbo.id(), 2, settings.aux_outputs ? with_aux : without_aux);
    s.aux_valid = settings.aux_outputs;
}

// The sprites of the clouds the CPU cull took, rasterised on the CPU (cpu_raster.h) for `pass` and
// uploaded into the targets over the cleared frame (the visibility pass: its depth only); returns the
// sprites drawn.
std::uint32_t cpu_sprites(SplatRenderState& s, const FramePlan& plan, SpritePass pass) {
    std::vector<SpriteRun> runs;
    for (const CloudGpu* gpu : plan.drawn) {
        if (!gpu->cpu_raster) continue;
        const CpuCullResult& r = gpu->cpu_cull;
        const TexelView* texture = gpu->texture ? &gpu->raster_texels : nullptr;
        CpuCullResult::for_each_run(r.records, r.record_counts, r.block,
                                    [&](std::size_t, const SplatRecord* p, std::size_t k) {
                                        runs.push_back({p, k, texture});
                                    });
        CpuCullResult::for_each_run(r.flat_records, r.flat_counts, r.block,
                                    [&](std::size_t, const SplatRecord* p, std::size_t k) {
                                        runs.push_back({p, k});
                                    });
    }
    CpuRasterImage& image = s.cpu_raster;
    if (runs.empty()) {  // nothing of last frame's image may be uploaded again (attribute_pass reads it)
        image.rect = glm::ivec4(0);
        image.sprites = 0;
        return 0;
    }
    rasterize_sprites_cpu(runs, plan.common, plan.width, plan.height, plan.common.background,
                          {s.min_point_size, s.max_point_size}, pass, plan.settings.aux_outputs, image);
    const glm::ivec4 r = image.rect;
    if (r.z <= 0 || r.w <= 0) return 0;
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
    glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(s.depth.id(), 0, r.x, r.y, r.z, r.w, GL_DEPTH_COMPONENT, GL_FLOAT,
                        image.depth.data());
    if (pass != SpritePass::preview) return image.sprites;  // HQ: depth only (the sums go to attribute_pass)
    glTextureSubImage2D(s.color.id(), 0, r.x, r.y, r.z, r.w, GL_RGBA, GL_HALF_FLOAT, image.color.data());
    if (plan.settings.aux_outputs)
        glTextureSubImage2D(s.aux.id(), 0, r.x, r.y, r.z, r.w, GL_RGBA, GL_FLOAT, image.aux.data());
    return image.sprites;
}

// Preview: one pass of opaque ray-cast ellipses into the output targets (the CPU's part first).
void preview_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, RenderStats& stats) {
    auto scope = profiling::gpu_scope(reg, "render.preview");
    if (plan.cpu_raster) stats.cpu_sprites = cpu_sprites(s, plan, SpritePass::preview);
    draw_preview_clouds(s, plan);
}

// Drivers may compile a program's fragment code for the state it first draws with (llvmpipe does, at
// the draw): the first preview of an editor that opened in HQ then took 19-24 ms instead of 9-10 (the
// sphere's first drag frame, 2-core machine). One preview draw of the clouds into a single scissored pixel of
// the output, in the same state, at the first HQ frame moves that cost to start-up; the pixel is cleared
// again before HQ draws.
void warm_preview_programs(SplatRenderState& s, const FramePlan& plan) {
    if (s.preview_warm || plan.drawn.empty()) return;
    s.preview_warm = true;
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, 1, 1);
    draw_preview_clouds(s, plan);
    const float far_depth = 1.0f;
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_COLOR, 0, &plan.common.background.x);
    glClearNamedFramebufferfv(s.output_fbo.id(), GL_DEPTH, 0, &far_depth);
    glDisable(GL_SCISSOR_TEST);
}

// HQ 1. visibility: eps-offset depth only.
// With the compute rasteriser (plan.compute): its visibility pass first, the rasteriser draws only what it
// left over, then its depths are merged into the depth target inside `rect` (where the accumulation runs).
// On the CPU sprite path (plan.cpu_raster) the CPU-culled clouds' sprites are the CPU's (cpu_sprites), GL
// draws their quads over that depth.
void visibility_pass(ecs::Registry& reg, SplatRenderState& s, const FramePlan& plan, const glm::ivec4& rect,
                     RenderStats& stats) {
    glBindFramebuffer(GL_FRAMEBUFFER, s.depth_fbo.id());
    glDepthFunc(GL_LESS);
    auto scope = profiling::gpu_scope(reg, "render.hq.visibility");
    const bool big = !plan.compute.empty();
    if (big) compute_raster_visibility(s.compute_raster, *s.scan, plan.compute, plan.width, plan.height);
    if (plan.cpu_raster)
        stats.cpu_sprites = cpu_sprites(s, plan, plan.cpu_hq ? SpritePass::hq : SpritePass::visibility);
    for (const CloudGpu* gpu : plan.drawn) {
        if (gpu->cpu_raster && gpu->cpu_cull.visible_quads == 0) continue;
        draw_cloud(s, s.visibility, *gpu, nullptr, big, !gpu->cpu_raster);
    }
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
    if (settings.quality != Quality::hq || materials || plan.drawn.empty() ||
        settings.raster_path == RasterPath::raster)
        return;
    if (settings.raster_path == RasterPath::automatic) {
        // Mean on-screen splat diameter over every drawn splat, against the measured break-even
        // (compute_raster.h).
        double splats = 0, footprint = 0;
        for (const CloudGpu* gpu : plan.drawn)
            splats += gpu->count, footprint += gpu->count * gpu->footprint_px;
        const double limit =
            s.software ? compute_raster_software_max_footprint : compute_raster_hardware_max_footprint;
        if (!(footprint <= limit * splats)) return;
    }
    if (Status st = compute_raster_fits(plan.width, plan.height); !st)
        return warn_once("render_system(): " + st.message());
    for (const CloudGpu* gpu : plan.drawn)
        if (Status st = compute_raster_records_fit(gpu->capacity, gpu->flat_list); !st)
            return warn_once("render_system(): " + st.message());
    if (Status st = init_compute_raster(s.compute_raster); !st) {
        log::error("render_system(): ", st.message());
        return;
    }
    if (!scan_programs(s)) return;  // its large-sprite lists are scanned (compute_visibility.comp)
    for (CloudGpu* gpu : plan.drawn) {
        ensure_compute_raster_cloud(gpu->raster, gpu->capacity);
        plan.compute.push_back({&gpu->raster, gpu->frame_ubo.id(), gpu->records.id(), gpu->commands.id(),
                                gpu->texture, gpu->count, gpu->capacity, gpu->flat_list});
        auto it = std::find_if(plan.gpu_counts.begin(), plan.gpu_counts.end(),
                               [&](const CountsSource& c) { return c.gpu == gpu; });
        if (it == plan.gpu_counts.end()) plan.gpu_counts.push_back({gpu, counts_big});
        else it->parts |= counts_big;
    }
    stats.compute_rastered_clouds = std::uint32_t(plan.compute.size());
}

// Whether the drawn clouds differ in specular/shininess: then they blend into a third target (per-pixel
// materials); one material for every cloud is a uniform, as cheap as before.
bool clouds_differ_in_material(const FramePlan& plan) {
    return std::any_of(plan.drawn.begin(), plan.drawn.end(), [&](const CloudGpu* g) {
        return g->material.specular != plan.drawn.front()->material.specular ||
               g->material.shininess != plan.drawn.front()->material.shininess;
    });
}

// HQ 2. attributes: additive, depth-tested against the offset surface, no depth writes; only inside the
// screen rectangle the clouds can cover (`rect`: clears of two RGBA32F targets and the shading pass are a
// large part of a small scene's frame on llvmpipe). Leaves the scissor test on for shade_pass.
void attribute_pass(ecs::Registry& reg, const SplatRenderState& s, const FramePlan& plan,
                    const glm::ivec4& rect, bool materials) {
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
        // The CPU's sums (made with its visibility pass) are the whole pass: nothing is left for GL.
        if (plan.cpu_hq && s.cpu_raster.rect.z > 0 && s.cpu_raster.rect.w > 0) {
            const glm::ivec4 r = s.cpu_raster.rect;
            glTextureSubImage2D(s.accum_color.id(), 0, r.x, r.y, r.z, r.w, GL_RGBA, GL_FLOAT,
                                s.cpu_raster.accum_color.data());
            glTextureSubImage2D(s.accum_normal.id(), 0, r.x, r.y, r.z, r.w, GL_RGBA, GL_FLOAT,
                                s.cpu_raster.accum_normal.data());
        }
        if (!plan.cpu_hq)
            for (const CloudGpu* gpu : plan.drawn)
                draw_cloud(s, s.attribute[gpu->texture ? 1 : 0][materials], *gpu,
                           &s.attribute[0][materials][0], big);
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
    if (!plan.drawn.empty())
        glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, plan.drawn.front()->frame_ubo.id());
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

}  // namespace sffd::render::detail
