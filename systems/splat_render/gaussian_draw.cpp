#include "systems/splat_render/gaussian_draw.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>

#include <tbb/parallel_sort.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/shader.h"
#include "runtime/gfx/ssbo_batch.h"
#include "shaders/common/bindings.h"
#include "shaders/gaussian/gaussian_layout.h"

namespace sffd::render {

Result<GlRenderer> create_gl_renderer() {
    GlRenderer r;
    auto project = gfx::load_compute_program("splat_render/gaussian/project.comp", "gaussian.project");
    if (!project) return project.error();
    auto splat = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/gaussian/splat.vert"},
                                    {GL_FRAGMENT_SHADER, "splat_render/gaussian/splat.frag"}},
                                   "gaussian.splat");
    if (!splat) return splat.error();
    r.project = std::move(*project);
    r.splat = std::move(*splat);
    const std::pair<gfx::Program*, const char*> tiles[] = {{&r.tile_count, "tile_count"},
                                                           {&r.tile_emit, "tile_emit"},
                                                           {&r.tile_ranges, "tile_ranges"},
                                                           {&r.tile_blend, "tile_blend"},
                                                           {&r.sort_payload, "sort_payload"},
                                                           {&r.gather, "gather"},
                                                           {&r.marks, "marks"}};
    for (const auto& [program, name] : tiles) {
        auto made = gfx::load_compute_program(std::string("splat_render/gaussian/") + name + ".comp",
                                              std::string("gaussian.") + name);
        if (!made) return made.error();
        *program = std::move(*made);
    }
    auto sorter = gfx::create_radix_sorter();
    if (!sorter) return sorter.error();
    r.sorter = std::move(*sorter);
    r.software = gfx::software_rasterizer();
    r.vao = gfx::VertexArray::create("gaussian.quads");
    r.proj_center = gfx::Buffer::create("gaussian.proj_center");
    r.proj_conic = gfx::Buffer::create("gaussian.proj_conic");
    r.proj_color = gfx::Buffer::create("gaussian.proj_color");
    r.sorted_center = gfx::Buffer::create("gaussian.sorted_center");
    r.sorted_conic = gfx::Buffer::create("gaussian.sorted_conic");
    r.sorted_color = gfx::Buffer::create("gaussian.sorted_color");
    r.order = gfx::Buffer::create("gaussian.order");
    r.depth = gfx::Buffer::create("gaussian.depth_keys");
    r.draw = gfx::Buffer::create("gaussian.draw_indirect");
    // The indirect command, the covered pixels and their wrap flag (project.comp), the range commands.
    glNamedBufferData(r.draw.id(), SFFD_GAUSS_DRAW_RANGE_COMMANDS, nullptr, GL_DYNAMIC_DRAW);
    r.tile_touched = gfx::Buffer::create("gaussian.tile_touched");
    r.tile_keys = gfx::Buffer::create("gaussian.tile_keys");
    r.tile_values = gfx::Buffer::create("gaussian.tile_values");
    r.tile_ranges_buffer = gfx::Buffer::create("gaussian.tile_ranges");
    r.tile_stats = gfx::Buffer::create("gaussian.tile_stats");
    glNamedBufferData(r.tile_stats.id(), 16, nullptr, GL_DYNAMIC_DRAW);
    reset_tile_stats(r);
    return r;
}

namespace {

// Buffer storage that grows (never zero-sized: GL needs a store to bind).
void upload(const gfx::Buffer& b, const void* data, std::size_t bytes) {
    glNamedBufferData(b.id(), GLsizeiptr(std::max<std::size_t>(bytes, 16)), nullptr, GL_DYNAMIC_DRAW);
    if (bytes > 0 && data) glNamedBufferSubData(b.id(), 0, GLsizeiptr(bytes), data);
}

void set(GLuint program, const char* name, float v) {
    glProgramUniform1f(program, glGetUniformLocation(program, name), v);
}
void set(GLuint program, const char* name, glm::vec2 v) {
    glProgramUniform2f(program, glGetUniformLocation(program, name), v.x, v.y);
}
void set(GLuint program, const char* name, glm::vec3 v) {
    glProgramUniform3f(program, glGetUniformLocation(program, name), v.x, v.y, v.z);
}

}  // namespace

GaussianBuffers gaussian_buffers(const gaussian::GpuGaussians& gpu) {
    GaussianBuffers b{gpu.draw_buffer(), gpu.sh_buffer(),       gpu.frames.id(),
                      gpu.drawn_count(), gpu.drawn_sh_degree(), gpu.has_frames()};
    b.marks_mode = gfx::resident_marks_mode(gpu);
    b.marks = b.marks_mode & SFFD_MARKS_PRESENT ? gpu.marks.id() : 0;
    b.preview_index = b.marks_mode & SFFD_MARKS_INDEXED ? gpu.preview_index.id() : 0;
    return b;
}

// Hardware GPUs: the GPU sort (no readback, no CPU work). Software rasterizers: the CPU sort, faster
// there at every size measured (bench_gaussian_gl, 1200x797 frames, see systems/gaussian/README.md):
// llvmpipe's "GPU" is the same CPU cores, and TBB's sort of 64-bit (key, index) pairs beats 8 radix
// passes of compute shaders run by llvmpipe: in-frame sort time at load avg ~10, 1M: 131 vs 814 ms,
// 6M: 1122 vs 4912 ms (100k, earlier scatter: 12 vs 211 ms); the key readback is a memcpy there.
bool gpu_sort_preferred(const GlRenderer& r) { return !r.software; }

namespace {

// The per-draw scratch buffers (projections, sort keys and payloads, tile counts) hold `n` Gaussians.
void ensure_scratch(GlRenderer& r, std::size_t n) {
    if (r.scratch >= n && r.scratch > 0) return;
    for (const gfx::Buffer* b :
         {&r.proj_center, &r.proj_conic, &r.proj_color, &r.sorted_center, &r.sorted_conic, &r.sorted_color})
        upload(*b, nullptr, n * SFFD_GPU_PROJECTED_STRIDE);
    upload(r.depth, nullptr, n * sizeof(std::uint32_t));
    upload(r.order, nullptr, n * sizeof(std::uint32_t));  // payloads (sort_payload.comp) or the CPU order
    upload(r.tile_touched, nullptr, (n + 1) * sizeof(std::uint32_t));  // + the scan's total
    r.scratch = std::max<std::size_t>(n, 1);
}

// The ranges of the depth order every pass after the projection works in: the projection arrays (16
// bytes a Gaussian, per Gaussian and depth-ordered), the order and the tile counts (4 bytes) bound from
// each range's first element. One range when they all fit one storage block, the same loops either way.
Result<std::vector<gfx::SsboBatch>> blend_ranges(std::size_t n) {
    const std::uint64_t strides[] = {SFFD_GPU_PROJECTED_STRIDE, sizeof(std::uint32_t)};
    auto ranges = gfx::ssbo_batches(n, strides);
    if (!ranges)
        return make_error("draw_gaussians(): " + std::to_string(n) +
                          " Gaussians: the projection (gaussian.proj_center) cannot be cut into ranges: " +
                          ranges.message() + "; the cloud is not drawn");
    return ranges;
}

// Binds the three arrays of `centers`..`colors` (one range of them) at the projection's points; the tile
// preparation reads only centres and conics, the conics at its own point.
enum class ProjectionReader { tile_preparation, blend };
void bind_projection(GLuint center, GLuint conic, GLuint color, const gfx::SsboBatch& range,
                     ProjectionReader reader) {
    gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CENTER, center, range, SFFD_GPU_PROJECTED_STRIDE);
    if (reader == ProjectionReader::tile_preparation) {
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_TILE_CONIC, conic, range, SFFD_GPU_PROJECTED_STRIDE);
        return;
    }
    gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CONIC, conic, range, SFFD_GPU_PROJECTED_STRIDE);
    gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_COLOR, color, range, SFFD_GPU_PROJECTED_STRIDE);
}
void bind_sorted(const GlRenderer& r, const gfx::SsboBatch& range, ProjectionReader reader) {
    bind_projection(r.sorted_center.id(), r.sorted_conic.id(), r.sorted_color.id(), range, reader);
}

// The draw buffer holds one command per range (the quads' draws, written by gather.comp).
void ensure_draw_ranges(GlRenderer& r, std::size_t ranges) {
    if (r.draw_ranges >= ranges) return;
    glNamedBufferData(r.draw.id(), GLsizeiptr(SFFD_GAUSS_DRAW_RANGE_COMMANDS + 16 * ranges), nullptr,
                      GL_DYNAMIC_DRAW);
    r.draw_ranges = ranges;
}

// Step 1: projection of one cloud's Gaussians; resets and fills the indirect draw command. With the GPU
// sort (r.gpu_sort_used), also its payloads.
Status project_gl(GlRenderer& r, const GaussianBuffers& b, const GaussianView& v) {
    const std::size_t n = b.count;
    // Per Gaussian, every buffer here is indexed by its own index: clouds whose SH (12 K bytes a Gaussian)
    // or other arrays exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE are projected in element ranges bound with
    // glBindBufferRange (the sort payloads offset by the range's first Gaussian, u_base).
    const std::uint64_t sh_stride = std::uint64_t(sh_coeffs(b.sh_degree)) * 3 * sizeof(float);
    const std::uint64_t strides[] = {sizeof(gpu::GpuGaussian), sh_stride, 3 * sizeof(glm::vec4),
                                     SFFD_GPU_PROJECTED_STRIDE, sizeof(std::uint32_t)};
    auto batches = gfx::ssbo_batches(n, strides);
    if (!batches) return make_error("draw_gaussians(): " + batches.message());
    ensure_scratch(r, n);
    // Write-after-read: the previous draw (another cloud this frame, or the last frame) read the scratch
    // buffers as SSBOs and the command as an indirect draw; SHADER_STORAGE makes this dispatch's writes
    // wait for every access issued before it (GL 4.5 §7.12.2), the command read included.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.project.reuse");
    // 4 strip vertices per quad, drawn count accumulated on the GPU; covered pixels, wrap flag.
    const GLuint command[6] = {4, 0, 0, 0, 0, 0};
    glNamedBufferSubData(r.draw.id(), 0, sizeof(command), command);
    const double tan_half = std::tan(glm::radians(v.fov_y_degrees) * 0.5);
    const GLuint pp = r.project.id();
    glProgramUniformMatrix4fv(pp, glGetUniformLocation(pp, "u_view"), 1, GL_FALSE,
                              glm::value_ptr(glm::mat4(v.view)));
    set(pp, "u_eye", glm::vec3(v.eye));
    set(pp, "u_size", glm::vec2(float(v.width), float(v.height)));
    set(pp, "u_focal", float(v.height / (2.0 * tan_half)));
    set(pp, "u_limit", glm::vec2(float(1.3 * tan_half * v.width / v.height), float(1.3 * tan_half)));
    set(pp, "u_near", float(v.near_plane));
    set(pp, "u_min_footprint", v.min_footprint_px);
    glProgramUniform1i(pp, glGetUniformLocation(pp, "u_degree"), b.sh_degree);
    glProgramUniform1i(pp, glGetUniformLocation(pp, "u_frames"), b.has_frames ? 1 : 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DRAW, r.draw.id());
    // A buffer with no store cannot be bound: the frames slot falls back to the Gaussians (never read).
    const GLuint frames = b.has_frames && b.frames ? b.frames : b.gaussians;
    const std::uint64_t frame_stride =
        frames == b.gaussians ? sizeof(gpu::GpuGaussian) : 3 * sizeof(glm::vec4);
    glUseProgram(pp);
    for (const gfx::SsboBatch& batch : *batches) {
        glProgramUniform1ui(pp, glGetUniformLocation(pp, "u_count"), GLuint(batch.count));
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_IN, b.gaussians, batch, sizeof(gpu::GpuGaussian));
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_SH, b.sh, batch, sh_stride);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CENTER, r.proj_center.id(), batch,
                             SFFD_GPU_PROJECTED_STRIDE);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CONIC, r.proj_conic.id(), batch, SFFD_GPU_PROJECTED_STRIDE);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_COLOR, r.proj_color.id(), batch, SFFD_GPU_PROJECTED_STRIDE);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_FRAMES, frames, batch, frame_stride);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_DEPTH, r.depth.id(), batch, sizeof(std::uint32_t));
        if (Status st = gfx::dispatch_1d(batch.count, 64, std::max(1u, r.max_groups_x)); !st)
            return st.error();
    }
    // Point marks: gone Gaussians out of the drawn ones, overlay colours (marks.comp), range by range.
    if (b.marks_mode != 0) {
        gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.marks");
        const GLuint mp = r.marks.id();
        glUseProgram(mp);
        glProgramUniform1ui(mp, glGetUniformLocation(mp, "u_mode"), b.marks_mode);
        set(mp, "u_size", glm::vec2(float(v.width), float(v.height)));
        // A buffer with no store cannot be bound: a missing one is never read (its mode bit is off).
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_POINT_MARKS, b.marks ? b.marks : r.draw.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_PREVIEW_INDEX,
                         b.preview_index ? b.preview_index : r.draw.id());
        for (const gfx::SsboBatch& batch : *batches) {
            glProgramUniform1ui(mp, glGetUniformLocation(mp, "u_count"), GLuint(batch.count));
            glProgramUniform1ui(mp, glGetUniformLocation(mp, "u_base"), GLuint(batch.first));
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CENTER, r.proj_center.id(), batch,
                                 SFFD_GPU_PROJECTED_STRIDE);
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_CONIC, r.proj_conic.id(), batch,
                                 SFFD_GPU_PROJECTED_STRIDE);
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_PROJ_COLOR, r.proj_color.id(), batch,
                                 SFFD_GPU_PROJECTED_STRIDE);
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_DEPTH, r.depth.id(), batch, sizeof(std::uint32_t));
            if (Status st = gfx::dispatch_1d(batch.count, 64, std::max(1u, r.max_groups_x)); !st)
                return st.error();
        }
    }
    // The GPU sort's payloads, the Gaussians' indices in the whole cloud (the CPU sort uploads its order).
    const GLuint op = r.sort_payload.id();
    if (r.gpu_sort_used) glUseProgram(op);
    for (std::size_t k = 0; r.gpu_sort_used && k < batches->size(); ++k) {
        const gfx::SsboBatch& batch = (*batches)[k];
        glProgramUniform1ui(op, glGetUniformLocation(op, "u_count"), GLuint(batch.count));
        glProgramUniform1ui(op, glGetUniformLocation(op, "u_base"), GLuint(batch.first));
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_ORDER, r.order.id(), batch, sizeof(std::uint32_t));
        if (Status st = gfx::dispatch_1d(batch.count, 64, std::max(1u, r.max_groups_x)); !st)
            return st.error();
    }
    glUseProgram(0);
    // Next: the depth keys read back (CPU sort: BUFFER_UPDATE) or sorted as SSBOs, the projections read
    // as SSBOs by the quads and tile passes, the draw command's atomically counted instances drawn
    // indirectly (COMMAND).
    gfx::memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT,
                        "gaussian.project");
    return {};
}

// Step 2, CPU: read back the keys only (4 bytes per Gaussian) and sort (key, index) pairs of the drawn
// ones: the index breaks ties, so the order equals the reference's stable sort (and is deterministic).
void sort_cpu(GlRenderer& r, std::size_t n) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::uint32_t> depth(n);
    if (n > 0) glGetNamedBufferSubData(r.depth.id(), 0, GLsizeiptr(n * sizeof(std::uint32_t)), depth.data());
    std::vector<std::uint64_t> keys;
    keys.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (depth[i] != SFFD_GAUSS_NOT_DRAWN)
            keys.push_back(std::uint64_t(depth[i]) << 32 | std::uint64_t(i));
    tbb::parallel_sort(keys.begin(), keys.end());
    std::vector<std::uint32_t> order(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) order[k] = std::uint32_t(keys[k] & 0xffffffffu);
    if (!order.empty())
        glNamedBufferSubData(r.order.id(), 0, GLsizeiptr(order.size() * sizeof(std::uint32_t)), order.data());
    r.sort_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Step 2, GPU: all keys sorted with their indices; the not-drawn keys (0xffffffff) end up last, so the
// first `drawn count` entries of `order` are the drawn Gaussians front to back. No readback.
Status sort_gpu(GlRenderer& r, std::size_t n) {
    r.sorter.max_groups_x = std::max(1u, r.max_groups_x);
    return gfx::radix_sort(r.sorter, r.depth.id(), r.order.id(), std::uint32_t(n));
}

// Step 2b: the projection gathered into depth order (gather.comp), one dispatch per (destination range,
// source range): each destination range takes its Gaussians from every source range in turn, so no pass
// binds more than one range of any array. The first dispatch of each destination range also writes its
// quads' draw command.
Status gather_gl(GlRenderer& r, const std::vector<gfx::SsboBatch>& ranges) {
    const GLuint gp = r.gather.id();
    glUseProgram(gp);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DRAW, r.draw.id());
    for (std::size_t j = 0; j < ranges.size(); ++j) {
        const gfx::SsboBatch& dst = ranges[j];
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_ORDER, r.order.id(), dst, sizeof(std::uint32_t));
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_SORTED_CENTER, r.sorted_center.id(), dst,
                             SFFD_GPU_PROJECTED_STRIDE);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_SORTED_CONIC, r.sorted_conic.id(), dst,
                             SFFD_GPU_PROJECTED_STRIDE);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_SORTED_COLOR, r.sorted_color.id(), dst,
                             SFFD_GPU_PROJECTED_STRIDE);
        glProgramUniform1ui(gp, glGetUniformLocation(gp, "u_count"), GLuint(dst.count));
        glProgramUniform1ui(gp, glGetUniformLocation(gp, "u_first"), GLuint(dst.first));
        glProgramUniform1ui(gp, glGetUniformLocation(gp, "u_range"), GLuint(j));
        for (std::size_t k = 0; k < ranges.size(); ++k) {
            const gfx::SsboBatch& src = ranges[k];
            bind_projection(r.proj_center.id(), r.proj_conic.id(), r.proj_color.id(), src,
                            ProjectionReader::blend);
            glProgramUniform1ui(gp, glGetUniformLocation(gp, "u_src_first"), GLuint(src.first));
            glProgramUniform1ui(gp, glGetUniformLocation(gp, "u_src_count"), GLuint(src.count));
            glProgramUniform1i(gp, glGetUniformLocation(gp, "u_write_command"), k == 0 ? 1 : 0);
            if (Status st = gfx::dispatch_1d(dst.count, 64, std::max(1u, r.max_groups_x)); !st) return st;
        }
    }
    glUseProgram(0);
    // The blend reads the depth-ordered arrays as storage blocks and the range commands as indirect draws.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT, "gaussian.gather");
    return {};
}

// Step 3, quads: one instanced quad per drawn Gaussian, range by range of the depth order (front to
// back), each range's count from its indirect command, blended into the framebuffer and viewport bound
// now (depth test state is the caller's).
void blend_quads(GlRenderer& r, const GaussianView& v, const std::vector<gfx::SsboBatch>& ranges,
                 const gfx::Program* splat_program) {
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFuncSeparate(GL_ONE_MINUS_DST_ALPHA, GL_ONE, GL_ONE_MINUS_DST_ALPHA, GL_ONE);
    const GLuint sp = splat_program ? splat_program->id() : r.splat.id();
    set(sp, "u_size", glm::vec2(float(v.width), float(v.height)));
    set(sp, "u_ndc_depth", glm::vec2(v.ndc_depth));
    glUseProgram(sp);
    glBindVertexArray(r.vao.id());
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, r.draw.id());
    for (std::size_t j = 0; j < ranges.size(); ++j) {
        bind_sorted(r, ranges[j], ProjectionReader::blend);
        glDrawArraysIndirect(GL_TRIANGLE_STRIP,
                             reinterpret_cast<const void*>(SFFD_GAUSS_DRAW_RANGE_COMMANDS + 16 * j));
    }
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    glDisable(GL_BLEND);
    glBindVertexArray(0);
    glUseProgram(0);
}

void tile_uniforms(GLuint program, const TileTargets& o, glm::uvec2 tiles) {
    set(program, "u_size", glm::vec2(float(o.width), float(o.height)));
    glProgramUniform2ui(program, glGetUniformLocation(program, "u_tiles"), tiles.x, tiles.y);
}

double stage_ms(const GlRenderer& r, std::chrono::steady_clock::time_point& t);

// Says once per renderer (and `said` flag) why a frame took another way than the one asked for.
void warn_fallback(bool& said, const std::string& message) {
    if (said) return;
    said = true;
    log::warn(message);
}

// Steps 1 and 2 (projection, depth sort, gather) of one cloud, with the stage times of benchmarks; the
// ranges of the depth order into `ranges`. Refused before any GL work when not one range fits.
Status project_and_sort(GlRenderer& r, const GaussianBuffers& b, const GaussianView& v,
                        std::vector<gfx::SsboBatch>& ranges) {
    auto made = blend_ranges(b.count);
    if (!made) return made.error();
    ranges = std::move(*made);
    ensure_draw_ranges(r, ranges.size());  // before the projection writes the command's count into it
    auto t = std::chrono::steady_clock::now();
    r.gpu_sort_used =
        r.sort_path == SortPath::gpu || (r.sort_path == SortPath::automatic && gpu_sort_preferred(r));
    // The radix sort scatters at random: its keys and payloads are one storage block each, or the keys are
    // read back and sorted on the CPU.
    const std::uint64_t key_bytes = std::uint64_t(b.count) * sizeof(std::uint32_t);
    if (r.gpu_sort_used && !gfx::ssbo_fits(key_bytes)) {
        warn_fallback(r.sort_fallback_warned,
                      "draw_gaussians(): " + gfx::ssbo_too_large("gaussian.depth_keys", key_bytes) +
                          " (the GPU sort binds them whole); sorting on the CPU");
        r.gpu_sort_used = false;
    }
    if (Status st = project_gl(r, b, v); !st) return st.error();
    r.project_ms = stage_ms(r, t);
    if (r.gpu_sort_used) {
        if (Status st = sort_gpu(r, b.count); !st) return st.error();
    } else {
        sort_cpu(r, b.count);
    }
    if (Status st = gather_gl(r, ranges); !st) return st.error();
    const double ms = stage_ms(r, t);
    if (r.gpu_sort_used) r.sort_ms = ms;
    return {};
}

// Whether the tile path's whole-bound buffers fit one storage block: the counts' scan (n + 1 uints), and
// once known the entries (tile keys, values: the emit pass writes them at random, the sort scatters).
Status tile_buffers_fit(std::size_t n, std::uint64_t entries) {
    const std::uint64_t counts = (std::uint64_t(n) + 1) * sizeof(std::uint32_t);
    if (!gfx::ssbo_fits(counts)) return make_error(gfx::ssbo_too_large("gaussian.tile_touched", counts));
    const std::uint64_t keys = entries * sizeof(std::uint32_t);
    if (!gfx::ssbo_fits(keys)) return make_error(gfx::ssbo_too_large("gaussian.tile_keys", keys));
    return {};
}

// The tile blend's per-pixel state carried between ranges, at the target's size, cleared (one blend of
// one cloud).
void clear_tile_state(GlRenderer& r, int width, int height) {
    if (r.tile_state_width < width || r.tile_state_height < height || !r.tile_state) {
        r.tile_state = gfx::Texture::create("gaussian.tile_state", GL_TEXTURE_2D);
        glTextureStorage2D(r.tile_state.id(), 1, GL_RG32F, width, height);
        r.tile_state_width = width, r.tile_state_height = height;
    }
    const float zero[2] = {0.0f, 0.0f};
    glClearTexImage(r.tile_state.id(), 0, GL_RG, GL_FLOAT, zero);
}

// Step 3, tiles (3DGS's rasterizer in compute): per drawn Gaussian in depth order the tiles it touches,
// their exclusive scan, one (tile id, depth position) entry per overlap in depth order, a stable radix
// sort by tile id (so (tile, depth) order), per-tile ranges, and a 16x16 group per tile blending front to
// back. The counts and entries are written range by range of the depth order, and the blend runs once
// per range, front to back, the images carrying each pixel's state across. One readback: the entry count
// (4 bytes), to size the entry buffers, as 3DGS does. Blends into what o.color holds (GL_TEXTURE_FETCH,
// framebuffer and image accesses after it see the result).
// With `over_capacity`, more entries than kMaxTileEntries, or counts or entries past one storage block,
// set it and return before blending (no error).
Status blend_tiles(GlRenderer& r, const TileTargets& o, std::size_t n,
                   const std::vector<gfx::SsboBatch>& ranges, bool* over_capacity = nullptr) {
    const glm::uvec2 tiles((unsigned(o.width) + SFFD_GAUSS_TILE - 1) / SFFD_GAUSS_TILE,
                           (unsigned(o.height) + SFFD_GAUSS_TILE - 1) / SFFD_GAUSS_TILE);
    const std::uint64_t tile_count = std::uint64_t(tiles.x) * tiles.y;
    if (tiles.x > gfx::kMinMaxComputeGroups || tiles.y > gfx::kMinMaxComputeGroups)
        return make_error("draw_gaussians(): image too large for one tile group per tile");
    const auto refuse = [&](const Status& st) -> Status {
        if (!over_capacity) return make_error("draw_gaussians(): " + st.message() + "; use BlendPath::quads");
        warn_fallback(r.tile_fallback_warned, "draw_gaussians(): " + st.message() +
                                                  " (the tile path binds it whole); blending with quads");
        *over_capacity = true;
        return {};
    };
    if (Status st = tile_buffers_fit(n, 0); !st) return refuse(st);
    const std::uint32_t max_x = std::max(1u, r.max_groups_x);
    r.sorter.max_groups_x = max_x;
    auto t = std::chrono::steady_clock::now();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DRAW, r.draw.id());
    for (GLuint p : {r.tile_count.id(), r.tile_emit.id()}) tile_uniforms(p, o, tiles);
    glUseProgram(r.tile_count.id());
    for (const gfx::SsboBatch& range : ranges) {
        bind_sorted(r, range, ProjectionReader::tile_preparation);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_TOUCHED, r.tile_touched.id(), range, sizeof(std::uint32_t));
        glProgramUniform1ui(r.tile_count.id(), glGetUniformLocation(r.tile_count.id(), "u_count"),
                            GLuint(range.count));
        glProgramUniform1ui(r.tile_count.id(), glGetUniformLocation(r.tile_count.id(), "u_base"),
                            GLuint(range.first));
        if (Status st = gfx::dispatch_1d(range.count, 64, max_x); !st) return st.error();
    }
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.tiles.count");  // the scan reads them
    if (Status st = gfx::exclusive_scan(r.sorter, r.tile_touched.id(), std::uint32_t(n)); !st)
        return st.error();
    GLuint entries = 0;
    glGetNamedBufferSubData(r.tile_touched.id(), GLintptr(n * sizeof(std::uint32_t)), sizeof(GLuint),
                            &entries);
    r.tile_entries = entries;
    // 8 bytes per entry; past 2^28 entries (2 GiB) the quad path is the one to use. (A true total past
    // 2^32 would wrap; the emit pass never writes past the capacity, so that is a wrong image at worst.)
    if (entries > kMaxTileEntries && over_capacity) {
        *over_capacity = true;
        return {};
    }
    if (entries > kMaxTileEntries)
        return make_error("draw_gaussians(): " + std::to_string(entries) +
                          " tile entries exceed the tile path's 2^28; use BlendPath::quads");
    // The emit, sort and ranges passes index the entry arrays at random: no ranges, one storage block each.
    if (Status st = tile_buffers_fit(n, entries); !st) return refuse(st);
    if (entries > r.tile_entry_capacity) {
        upload(r.tile_keys, nullptr, std::size_t(entries) * sizeof(std::uint32_t));
        upload(r.tile_values, nullptr, std::size_t(entries) * sizeof(std::uint32_t));
        r.tile_entry_capacity = entries;
    }
    if (r.tile_ranges_buffer_tiles != tile_count) {
        upload(r.tile_ranges_buffer, nullptr, std::size_t(tile_count) * 2 * sizeof(std::uint32_t));
        r.tile_ranges_buffer_tiles = tile_count;
    }
    glClearNamedBufferData(r.tile_ranges_buffer.id(), GL_RG32UI, GL_RG_INTEGER, GL_UNSIGNED_INT, nullptr);
    // gfx::exclusive_scan bound its own buffers (points 0 and 4): bind every buffer the emit pass reads.
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DRAW, r.draw.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_KEYS, r.tile_keys.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_VALUES, r.tile_values.id());
    const GLuint ep = r.tile_emit.id();
    glProgramUniform1ui(ep, glGetUniformLocation(ep, "u_capacity"), entries);
    glUseProgram(ep);
    for (const gfx::SsboBatch& range : ranges) {
        bind_sorted(r, range, ProjectionReader::tile_preparation);
        // The range's offsets and the next range's first (its end), the scan's total after the last.
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_TOUCHED, r.tile_touched.id(), {range.first, range.count + 1},
                             sizeof(std::uint32_t));
        glProgramUniform1ui(ep, glGetUniformLocation(ep, "u_count"), GLuint(range.count));
        glProgramUniform1ui(ep, glGetUniformLocation(ep, "u_base"), GLuint(range.first));
        if (Status st = gfx::dispatch_1d(range.count, 64, max_x); !st) return st.error();
    }
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.tiles.emit");  // the sort reads the entries
    // Keys run to tile_count itself (tile_emit.comp's unfilled slots), so the sort covers it too.
    int key_bits = 1;
    while (key_bits < 32 && (std::uint64_t(1) << key_bits) <= tile_count) ++key_bits;
    if (Status st = gfx::radix_sort(r.sorter, r.tile_keys.id(), r.tile_values.id(), entries, key_bits); !st)
        return st.error();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_KEYS, r.tile_keys.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_VALUES, r.tile_values.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_RANGES, r.tile_ranges_buffer.id());
    const GLuint rp = r.tile_ranges.id();
    glProgramUniform1ui(rp, glGetUniformLocation(rp, "u_entries"), entries);
    glProgramUniform1ui(rp, glGetUniformLocation(rp, "u_tile_count"), GLuint(tile_count));
    glUseProgram(rp);
    if (Status st = gfx::dispatch_1d(entries, 64, max_x); !st) return st.error();
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.tiles.ranges");  // the blend reads them
    r.tile_prepare_ms = stage_ms(r, t);
    clear_tile_state(r, o.width, o.height);
    const GLuint bp = r.tile_blend.id();
    tile_uniforms(bp, o, tiles);
    glProgramUniform1i(bp, glGetUniformLocation(bp, "u_depth_test"), o.surface_depth ? 1 : 0);
    glProgramUniform1i(bp, glGetUniformLocation(bp, "u_write_depth"), o.depth_sum ? 1 : 0);
    set(bp, "u_ndc_depth", glm::vec2(o.ndc_depth));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_STATS, r.tile_stats.id());
    glBindImageTexture(SFFD_GAUSS_IMAGE_COLOR, o.color, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    // Unused units stay bound to the colour (never accessed then: the uniforms above say so).
    glBindImageTexture(SFFD_GAUSS_IMAGE_DEPTH, o.depth_sum ? o.depth_sum : o.color, 0, GL_FALSE, 0,
                       GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(SFFD_GAUSS_IMAGE_STATE, r.tile_state.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RG32F);
    glBindTextureUnit(0, o.surface_depth);
    glUseProgram(bp);
    for (std::size_t k = 0; k < ranges.size(); ++k) {
        // The previous range's pass wrote the pixels this one continues from.
        if (k > 0) gfx::memory_barrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT, "gaussian.tiles.blend_range");
        bind_sorted(r, ranges[k], ProjectionReader::blend);
        glProgramUniform1ui(bp, glGetUniformLocation(bp, "u_src_first"), GLuint(ranges[k].first));
        glProgramUniform1ui(bp, glGetUniformLocation(bp, "u_src_count"), GLuint(ranges[k].count));
        glDispatchCompute(tiles.x, tiles.y, 1);
    }
    glUseProgram(0);
    glBindTextureUnit(0, 0);
    // The image is read back (glGetTextureImage: TEXTURE_UPDATE) or sampled/drawn by the composite
    // (TEXTURE_FETCH, FRAMEBUFFER), the next blend writes it again (SHADER_IMAGE_ACCESS), and the tile
    // statistics are read back (BUFFER_UPDATE).
    gfx::memory_barrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                            GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                            GL_BUFFER_UPDATE_BARRIER_BIT,
                        "gaussian.tiles.blend");
    r.tile_entries_total += entries;
    return {};
}

// Stage timing for benchmarks: the wall time since `t`, after waiting for the GL work (stage_timing).
double stage_ms(const GlRenderer& r, std::chrono::steady_clock::time_point& t) {
    if (!r.stage_timing) return 0.0;
    glFinish();
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
}

}  // namespace

Status draw_gaussians(GlRenderer& r, const GaussianBuffers& b, const GaussianView& v,
                      const gfx::Program* splat_program, const TileTargets* tiles) {
    if (b.count >= (std::size_t(1) << 31))
        return make_error("draw_gaussians(): more than 2^31 Gaussians in one draw");
    r.covered_pixels = 0;
    r.last_blend = BlendPath::quads;
    r.tile_entries = 0, r.tile_prepare_ms = 0.0;
    std::vector<gfx::SsboBatch> ranges;
    if (Status st = project_and_sort(r, b, v, ranges); !st) return st.error();
    auto blend_start = std::chrono::steady_clock::now();
    if (tiles) {
        // The covered pixels (8 bytes; waits for the projection only): quads up to the budget, where
        // their image is the one the reference tests compare; past it, the tile blend, whose work stops at
        // saturation (unless its entries outgrow their buffers: quads then, unbounded but right).
        r.covered_pixels = read_covered_pixels(r);
        if (r.blend_path == BlendPath::tiles || r.covered_pixels > quad_coverage_budget(r.software) *
                                                                       std::uint64_t(v.width) *
                                                                       std::uint64_t(v.height)) {
            TileTargets t = *tiles;
            t.width = v.width, t.height = v.height, t.ndc_depth = v.ndc_depth;
            bool over_capacity = false;
            if (Status st = blend_tiles(r, t, b.count, ranges, &over_capacity); !st) return st.error();
            if (!over_capacity) {
                r.last_blend = BlendPath::tiles;
                r.blend_ms = stage_ms(r, blend_start);
                return {};
            }
        }
    }
    blend_quads(r, v, ranges, splat_program);
    r.blend_ms = stage_ms(r, blend_start);
    return {};
}

std::uint64_t read_covered_pixels(const GlRenderer& r) {
    GLuint covered[2] = {0, 0};  // the sum, and its wrap flag (project.comp)
    glGetNamedBufferSubData(r.draw.id(), 16, sizeof(covered), covered);
    return covered[1] != 0 ? std::numeric_limits<std::uint64_t>::max() : covered[0];
}

void reset_tile_stats(GlRenderer& r) {
    const GLuint zero = 0;
    glNamedBufferSubData(r.tile_stats.id(), 0, sizeof(zero), &zero);
    r.tile_entries_total = 0;
}

TileStats tile_stats(const GlRenderer& r) {
    GLuint staged = 0;
    glGetNamedBufferSubData(r.tile_stats.id(), 0, sizeof(staged), &staged);
    return {r.tile_entries_total, staged};
}

}  // namespace sffd::render
