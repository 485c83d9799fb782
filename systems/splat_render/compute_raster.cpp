// Compute splat rasteriser: programs, per-pixel buffers and dispatches. See compute_raster.h.
#include "systems/splat_render/compute_raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/bindings.h"
#include "shaders/splat_render/compute_raster.h"
#include "shaders/splat_render/splat_record.h"

namespace sffd::render {

namespace {

constexpr GLint list_uniform = 0;            // u_list in compute_visibility.comp / compute_attribute.comp
constexpr GLint rect_uniform = 1;            // u_rect in compute_attribute.comp
constexpr GLint write_pass_uniform = 1;      // u_write_pass in compute_visibility.comp
constexpr std::uint32_t command_words = 10;  // two DrawElementsIndirectCommands
constexpr std::uint32_t depth_clear = 0x3f800000u;  // 1.0f: RASTER_DEPTH_CLEAR

// The record lists of a cloud: {first record, word of the cull's commands with the length, list id}.
template <class Fn>
void for_each_list(const ComputeRasterDraw& d, Fn&& fn) {
    fn(glm::uvec4(0u, 0u, 0u, d.count));
    if (d.flat_list) fn(glm::uvec4(d.capacity, 8u, 1u, d.count));
}

void bind_cloud(const ComputeRasterDraw& d) {
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, d.frame_ubo);
    // The sprites' run of the records, and the flat-coloured run when there is one (the whole buffer may
    // exceed one storage block: compute_raster_records_fit).
    const std::size_t runs = d.flat_list ? 2 : 1;
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_VISIBLE_SPLATS, d.records, 0,
                      GLsizeiptr(runs * std::max<std::size_t>(d.capacity, 1) * SFFD_SPLAT_RECORD_BYTES));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_DRAW_INDIRECT, d.commands);
}

}  // namespace

Status init_compute_raster(ComputeRaster& raster) {
    if (raster.visibility) return {};
    auto vis = gfx::load_compute_program("splat_render/compute_visibility.comp", "render.compute.visibility");
    if (!vis) return make_error(vis.message());
    for (int textured = 0; textured < 2; ++textured) {
        auto attr =
            gfx::load_compute_program("splat_render/compute_attribute.comp", "render.compute.attribute",
                                      {{"TEXTURED", textured ? "1" : "0"}});
        if (!attr) return make_error(attr.message());
        raster.attribute[std::size_t(textured)] = std::move(attr.value());
    }
    auto merge = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                    {GL_FRAGMENT_SHADER, "splat_render/compute_merge.frag"}},
                                   "render.compute.merge");
    if (!merge) return make_error(merge.message());
    auto resolve = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                      {GL_FRAGMENT_SHADER, "splat_render/compute_resolve.frag"}},
                                     "render.compute.resolve");
    if (!resolve) return make_error(resolve.message());
    raster.merge = std::move(merge.value());
    raster.resolve = std::move(resolve.value());
    raster.visibility = std::move(vis.value());
    return {};
}

void ensure_compute_raster_cloud(ComputeRasterCloud& cloud, std::uint32_t capacity) {
    if (cloud.big && cloud.capacity >= capacity) return;
    cloud.capacity = std::max<std::uint32_t>(capacity, 1);
    cloud.big = gfx::Buffer::create("render.compute.big_sprites");
    glNamedBufferStorage(cloud.big.id(), GLsizeiptr(2 * std::size_t(cloud.capacity) * sizeof(std::uint32_t)),
                         nullptr, 0);
    // The constant words (instances 1, first index) are set once here; each frame only the two counts are
    // cleared on the GPU (compute_raster_visibility), never uploaded from the CPU into a buffer the GPU
    // writes.
    const std::uint32_t init[command_words] = {0, 1, 0, 0, 0, 0, 1, cloud.capacity, 0, 0};
    cloud.commands = gfx::Buffer::create("render.compute.big_commands");
    glNamedBufferStorage(cloud.commands.id(), sizeof init, init, GL_DYNAMIC_STORAGE_BIT);
    const std::size_t groups =
        (std::size_t(cloud.capacity) + SFFD_RASTER_GROUP_SIZE - 1) / SFFD_RASTER_GROUP_SIZE;
    for (gfx::Buffer& g : cloud.groups) {
        g = gfx::Buffer::create("render.compute.big_groups");
        glNamedBufferStorage(g.id(), GLsizeiptr((groups + 1) * sizeof(std::uint32_t)), nullptr, 0);
    }
}

void compute_raster_visibility(ComputeRaster& raster, gfx::RadixSorter& scan,
                               std::span<const ComputeRasterDraw> draws, int width, int height) {
    if (!raster.depth || raster.width != width || raster.height != height) {
        const std::size_t pixels = std::size_t(std::max(width, 1)) * std::size_t(std::max(height, 1));
        raster.depth = gfx::Buffer::create("render.compute.depth");
        glNamedBufferStorage(raster.depth.id(), GLsizeiptr(pixels * sizeof(std::uint32_t)), nullptr,
                             GL_DYNAMIC_STORAGE_BIT);
        raster.sums = gfx::Buffer::create("render.compute.sums");
        glNamedBufferStorage(raster.sums.id(),
                             GLsizeiptr(pixels * SFFD_RASTER_SUM_WORDS * sizeof(std::uint32_t)), nullptr,
                             GL_DYNAMIC_STORAGE_BIT);
        const std::uint32_t zero = 0;
        glClearNamedBufferData(raster.sums.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        raster.width = width, raster.height = height;
    }
    // The clears below overwrite depth words and counters that the last frame's shaders wrote (atomics) and
    // read; the big lists are overwritten by this pass's stores after the last frame's indexed draws.
    gfx::memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT,
                        "render.compute.visibility.reuse");
    glClearNamedBufferData(raster.depth.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &depth_clear);
    for (const ComputeRasterDraw& d : draws) {
        const std::uint32_t zero = 0;
        glClearNamedBufferSubData(d.cloud->commands.id(), GL_R32UI, 0, sizeof zero, GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &zero);
        glClearNamedBufferSubData(d.cloud->commands.id(), GL_R32UI, 5 * sizeof zero, sizeof zero,
                                  GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        for_each_list(d, [&](const glm::uvec4& list) {
            // The scan binds its own buffers: both dispatches bind theirs.
            const auto bind = [&](std::uint32_t write_pass) {
                glUseProgram(raster.visibility.id());
                glUniform4ui(list_uniform, list.x, list.y, list.z, list.w);
                glUniform1ui(write_pass_uniform, write_pass);
                bind_cloud(d);
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_DEPTH, raster.depth.id());
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_BIG, d.cloud->big.id());
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_BIG_COMMANDS,
                                 d.cloud->commands.id());
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_GROUPS,
                                 d.cloud->groups[list.z].id());
            };
            bind(0);
            if (Status st = gfx::dispatch_1d(d.count, SFFD_RASTER_GROUP_SIZE); !st)
                log::error("render_system(): ", st.message());
            gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "render.compute.visibility.count");
            const auto groups =
                std::uint32_t((d.count + SFFD_RASTER_GROUP_SIZE - 1) / SFFD_RASTER_GROUP_SIZE);
            if (Status st = gfx::exclusive_scan(scan, d.cloud->groups[list.z].id(), groups); !st)
                log::error("render_system(): ", st.message());
            bind(1);
            if (Status st = gfx::dispatch_1d(d.count, SFFD_RASTER_GROUP_SIZE); !st)
                log::error("render_system(): ", st.message());
        });
    }
    // The big lists feed indirect indexed draws (ELEMENT_ARRAY, COMMAND) whose records are fetched as vertex
    // attributes; the depth words the merge pass's SSBO reads; the counters are copied into the counts ring.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT |
                            GL_ELEMENT_ARRAY_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT |
                            GL_BUFFER_UPDATE_BARRIER_BIT,
                        "render.compute.visibility");
}

void compute_raster_merge(const ComputeRaster& raster, GLuint frame_ubo) {
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, frame_ubo);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_DEPTH, raster.depth.id());
    glUseProgram(raster.merge.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

void compute_raster_attribute(const ComputeRaster& raster, std::span<const ComputeRasterDraw> draws,
                              const glm::ivec4& rect, GLuint depth_texture) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_DEPTH, raster.depth.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_SUMS, raster.sums.id());
    glBindTextureUnit(SFFD_TEX_DEPTH, depth_texture);
    for (const ComputeRasterDraw& d : draws) {
        bind_cloud(d);
        glBindTextureUnit(SFFD_TEX_MATERIAL, d.texture);
        for_each_list(d, [&](const glm::uvec4& list) {
            // The flat-coloured list keeps the untextured meaning of its records (splat_record.h).
            const bool textured = d.texture != 0 && list.z == 0u;
            glUseProgram(raster.attribute[textured].id());
            glUniform4i(rect_uniform, rect.x, rect.y, rect.x + rect.z, rect.y + rect.w);
            glUniform4ui(list_uniform, list.x, list.y, list.z, list.w);
            if (Status st = gfx::dispatch_1d(d.count, SFFD_RASTER_GROUP_SIZE); !st)
                log::error("render_system(): ", st.message());
        });
    }
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT,
                        "render.compute.attribute");  // sums, read by the resolve
}

void compute_raster_resolve(const ComputeRaster& raster, GLuint frame_ubo) {
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, frame_ubo);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_DEPTH, raster.depth.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_RASTER_SUMS, raster.sums.id());
    glUseProgram(raster.resolve.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    // The zeroed words are next read by next frame's compute attribute pass.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "render.compute.resolve");
}

double splat_footprint_px(const glm::dmat4& model_view, const glm::dvec3& center, double radius, double p11,
                          int height) {
    const double depth = -(model_view * glm::dvec4(center, 1.0)).z;
    const double scale =
        std::max({glm::length(glm::dvec3(model_view[0])), glm::length(glm::dvec3(model_view[1])),
                  glm::length(glm::dvec3(model_view[2]))});
    if (depth <= 0.0) return std::numeric_limits<double>::infinity();
    return 2.0 * radius * scale * p11 * 0.5 * double(height) / depth;
}

double mean_splat_radius(const SplatCloud& cloud) {
    const std::size_t n = std::min(cloud.axis_u.size(), cloud.axis_v.size());
    if (n == 0) return 0.0;
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i)
        sum += double(std::max(glm::length(cloud.axis_u[i]), glm::length(cloud.axis_v[i])));
    return sum / double(n);
}

}  // namespace sffd::render
