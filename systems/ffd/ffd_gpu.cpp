#include "systems/ffd/ffd_gpu.h"

#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/shader.h"
#include "runtime/scene/point_pages.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/gpu_kernel.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

struct GpuDeformer::Impl {
    std::optional<gfx::GlContext> context;  // only when created headless; destroyed last (declared first)
    detail::DeformPrograms programs;        // lattice set-up shared with the Gaussian deformer
    gfx::Buffer scratch, scratch_weights;
    // The deformer's own per-page counters (dispatches without a cloud's, and deform()): `stats_words`
    // held, `used_words` written since reset_stats().
    gfx::Buffer stats;
    std::size_t stats_words = 0, used_words = 0;
    detail::StatsReadbacks readbacks;  // queue_stats()
    std::size_t scratch_capacity = 0;
    std::uint64_t sync_readbacks = 0;
};

GpuDeformer::GpuDeformer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
GpuDeformer::GpuDeformer(GpuDeformer&&) noexcept = default;
GpuDeformer& GpuDeformer::operator=(GpuDeformer&&) noexcept = default;
GpuDeformer::~GpuDeformer() = default;

Result<GpuDeformer> GpuDeformer::create() {
    auto impl = std::make_unique<Impl>();
    auto programs = detail::DeformPrograms::create("ffd/deform.comp", "ffd.deform", "ffd");
    if (!programs) return programs.error();
    impl->programs = std::move(*programs);
    return GpuDeformer(std::move(impl));
}

Result<GpuDeformer> GpuDeformer::create_headless() {
    auto ctx = gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false});
    if (!ctx) return ctx.error();
    auto d = create();
    if (!d) return d.error();
    d->m_impl->context.emplace(std::move(*ctx));
    return d;
}

std::uint64_t GpuDeformer::upload_count() const { return m_impl->programs.uploads; }
void GpuDeformer::set_bernstein_kernel(GpuBernsteinKernel kernel) { m_impl->programs.kernel = kernel; }
GpuBernsteinKernel GpuDeformer::last_bernstein_kernel() const { return m_impl->programs.last_kernel; }
void GpuDeformer::retain_keys(const std::vector<std::uint64_t>& live) { m_impl->programs.retain_keys(live); }

Status GpuDeformer::dispatch(const Lattice& lattice, std::uint64_t key, std::uint64_t stamp,
                             const glm::dvec3& cloud_origin, GLuint in, GLuint out, std::uint32_t count,
                             GLuint weights, const DispatchPages& pages) {
    if (Status s = validate(lattice); !s) return s;
    Impl& m = *m_impl;
    // A weighted cloud runs programs of its own (FFD_WEIGHTS): the unweighted ones stay as they were.
    detail::DeformPrograms::Variant weighted;
    weighted.id = 1;
    weighted.defines = {{"FFD_WEIGHTS", "1"}};
    weighted.label = ".weighted";
    auto bound = m.programs.bind(lattice, key, stamp, cloud_origin, count, weights ? &weighted : nullptr);
    if (!bound) return bound.error();
    GLuint stats = pages.stats;
    if (!stats) {  // the deformer's own counters, grown to this cloud's pages keeping what they hold
        const std::size_t words = std::max<std::size_t>(page_count(count), 1) * kCounters;
        if (words > m.stats_words) {
            gfx::Buffer grown = gfx::Buffer::create("ffd.stats");
            // Written by the GPU (atomics), cleared and copied on the GPU; the CPU reads only copies
            // (StatsReadbacks). A READ hint puts a buffer in host memory on NVIDIA's driver.
            glNamedBufferData(grown.id(), GLsizeiptr(words * 4), nullptr, GL_DYNAMIC_COPY);
            glClearNamedBufferData(grown.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
            if (m.used_words)
                glCopyNamedBufferSubData(m.stats.id(), grown.id(), 0, 0, GLsizeiptr(m.used_words * 4));
            m.stats = std::move(grown), m.stats_words = words;
        }
        m.used_words = std::max(m.used_words, words);
        stats = m.stats.id();
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_STATS, stats);
    // Write-after-read across frames: the last frame's passes read `out` (the cull's SSBO loads, vertex
    // fetches) and this dispatch overwrites it.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "ffd.dispatch.reuse");
    // Clouds past GL_MAX_SHADER_STORAGE_BLOCK_SIZE (64 bytes a splat) run in element ranges; in place
    // (in == out) each batch reads and writes only its own range.
    const std::uint64_t strides[] = {sizeof(gpu::GpuSplat), sizeof(gpu::GpuSplat)};
    if (Status s = m.programs.dispatch_batches(
            *bound, count, strides,
            [&](const gfx::SsboBatch& batch) {
                gfx::bind_ssbo_range(SFFD_SSBO_SPLATS_IN, in, batch, sizeof(gpu::GpuSplat));
                gfx::bind_ssbo_range(SFFD_SSBO_SPLATS_OUT, out, batch, sizeof(gpu::GpuSplat));
                if (weights) gfx::bind_ssbo_range(SFFD_SSBO_WEIGHTS, weights, batch, sizeof(float));
            },
            pages.ranges);
        !s)
        return s;
    // Read next as SSBOs (cull), vertex attributes, and by copies and read-backs (statistics, deform()).
    gfx::memory_barrier(
        GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT,
        "ffd.dispatch");
    return {};
}

DeformStats GpuDeformer::read_stats() {
    std::uint32_t v[kCounters] = {};
    if (m_impl->used_words) detail::read_page_counters(m_impl->stats.id(), m_impl->used_words, kCounters, v);
    ++m_impl->sync_readbacks;
    DeformStats s;
    s.inverted = v[0];
    s.inside = v[1];
    s.backend = Backend::fast;
    return s;
}

void GpuDeformer::reset_stats() {
    // A clear in the command stream (null data = zeros): no CPU upload into a buffer that the previous
    // frame's dispatch may still be using, so no implicit wait.
    if (m_impl->stats)
        glClearNamedBufferData(m_impl->stats.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    m_impl->used_words = 0;
}

bool GpuDeformer::queue_stats(std::uint64_t tag) {
    return queue_stats(tag, m_impl->stats.id(), m_impl->used_words);
}

bool GpuDeformer::queue_stats(std::uint64_t tag, GLuint page_stats, std::size_t words) {
    return m_impl->readbacks.queue(page_stats, words, tag, "ffd.stats_readback");
}

std::vector<GpuDeformer::TaggedStats> GpuDeformer::poll_stats() {
    std::vector<TaggedStats> done;
    m_impl->readbacks.poll([&](std::uint64_t tag, const std::uint32_t* counters, std::size_t words) {
        std::uint32_t counts[kCounters];
        detail::sum_page_counters(counters, words, kCounters, counts);
        DeformStats s;
        s.inverted = counts[0];
        s.inside = counts[1];
        s.backend = Backend::fast;
        done.push_back({tag, s});
    });
    return done;
}

std::size_t GpuDeformer::pending_stats() const { return m_impl->readbacks.pending(); }

std::uint64_t GpuDeformer::sync_readbacks() const { return m_impl->sync_readbacks; }

Result<DeformStats> GpuDeformer::deform(const Lattice& lattice, const PointsIn& in, const PointsOut& out) {
    if (Status s = validate(lattice); !s) return s.error();
    Impl& m = *m_impl;
    std::vector<gpu::GpuSplat> splats(in.count);
    for (std::size_t i = 0; i < in.count; ++i) {
        gpu::GpuSplat& s = splats[i];
        const glm::vec3 p = in.positions[i];
        const glm::vec3 n = in.normals ? in.normals[i] : glm::vec3(0, 0, 1);
        const glm::vec3 u = in.axis_u ? in.axis_u[i] : glm::vec3(0);
        const glm::vec3 v = in.axis_v ? in.axis_v[i] : glm::vec3(0);
        s = gpu::GpuSplat{{p.x, p.y, p.z, 0}, {n.x, n.y, n.z, 1}, {u.x, u.y, u.z, 0}, {v.x, v.y, v.z, 0}};
    }
    const std::size_t bytes = std::max<std::size_t>(splats.size(), 1) * sizeof(gpu::GpuSplat);
    if (!m.scratch || bytes > m.scratch_capacity) {
        m.scratch = gfx::Buffer::create("ffd.scratch_splats");
        glNamedBufferData(m.scratch.id(), GLsizeiptr(bytes), nullptr, GL_DYNAMIC_COPY);
        m.scratch_capacity = bytes;
    }
    if (!splats.empty())
        glNamedBufferSubData(m.scratch.id(), 0, GLsizeiptr(splats.size() * sizeof(gpu::GpuSplat)),
                             splats.data());
    GLuint weights = 0;
    if (in.weights && in.count > 0) {
        gfx::fill_buffer(m.scratch_weights, "ffd.scratch_weights", in.weights, in.count * sizeof(float));
        weights = m.scratch_weights.id();
    }
    reset_stats();
    if (Status s = dispatch(lattice, ~std::uint64_t(0), 0, in.origin, m.scratch.id(), m.scratch.id(),
                            std::uint32_t(in.count), weights);
        !s)
        return s.error();
    if (!splats.empty())
        glGetNamedBufferSubData(m.scratch.id(), 0, GLsizeiptr(splats.size() * sizeof(gpu::GpuSplat)),
                                splats.data()),
            ++m.sync_readbacks;
    for (std::size_t i = 0; i < in.count; ++i) {
        const gpu::GpuSplat& s = splats[i];
        out.positions[i] = glm::vec3(s.center[0], s.center[1], s.center[2]);
        if (in.normals && out.normals) out.normals[i] = glm::vec3(s.normal[0], s.normal[1], s.normal[2]);
        if (in.axis_u && out.axis_u) out.axis_u[i] = glm::vec3(s.axis_u[0], s.axis_u[1], s.axis_u[2]);
        if (in.axis_v && out.axis_v) out.axis_v[i] = glm::vec3(s.axis_v[0], s.axis_v[1], s.axis_v[2]);
    }
    DeformStats st = read_stats();
    return st;
}

GLuint resident_weights(gfx::ResidentCloud& cloud, std::span<const float> weights, std::uint64_t key) {
    if (weights.empty() || weights.size() != cloud.count) {
        cloud.weights = gfx::Buffer();  // none (or not one per point: weight 1, as the CPU path reads it)
        cloud.weights_key = 0;
        return 0;
    }
    if (!cloud.weights || cloud.weights_key != key) {
        gfx::fill_buffer(cloud.weights, "cloud.weights", weights.data(), weights.size() * sizeof(float));
        cloud.weights_key = key;
    }
    return cloud.weights.id();
}

std::vector<gfx::SsboBatch> page_runs(std::span<const std::uint32_t> pages, std::size_t count) {
    std::vector<gfx::SsboBatch> runs;
    for (std::uint32_t p : pages) {
        const PageRange r = page_range(p, count);
        if (r.count == 0) continue;
        if (!runs.empty() && runs.back().first + runs.back().count == r.first) runs.back().count += r.count;
        else runs.push_back({r.first, r.count});
    }
    return runs;
}

bool resident_page_stats(gfx::ResidentCloud& cloud, std::size_t pages, std::size_t per_page) {
    const std::size_t words = std::max<std::size_t>(pages, 1) * per_page;
    if (cloud.page_stats && cloud.page_stats_words == words) return true;
    cloud.page_stats = gfx::Buffer::create("cloud.page_stats");
    glNamedBufferData(cloud.page_stats.id(), GLsizeiptr(words * sizeof(std::uint32_t)), nullptr,
                      GL_DYNAMIC_COPY);
    glClearNamedBufferData(cloud.page_stats.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    cloud.page_stats_words = words;
    return false;
}

void clear_page_stats(const gfx::ResidentCloud& cloud, std::span<const gfx::SsboBatch> ranges,
                      std::size_t per_page) {
    for (const gfx::SsboBatch& r : ranges) {
        const std::size_t first = std::size_t(r.first >> kPageShift);
        const std::size_t last = page_count(std::size_t(r.first + r.count));
        const std::size_t words = std::min(last * per_page, cloud.page_stats_words);
        if (first * per_page >= words) continue;
        glClearNamedBufferSubData(cloud.page_stats.id(), GL_R32UI, GLintptr(first * per_page * 4),
                                  GLsizeiptr(words * 4 - first * per_page * 4), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, nullptr);
    }
}

}  // namespace sffd::ffd
