#include "systems/ffd/ffd_gpu.h"

#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/gpu_block.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

struct GpuDeformer::Impl {
    std::optional<gfx::GlContext> context;  // only when created headless; destroyed last (declared first)
    gfx::Program program;                                      // generic (any divisions)
    std::unordered_map<std::uint64_t, gfx::Program> specialised;  // per (l, m, n, basis)
    gfx::Buffer ubo, stats, scratch;
    struct Controls {
        gfx::Buffer buffer;
        std::size_t capacity = 0;
        std::uint64_t stamp = 0;
    };
    std::unordered_map<std::uint64_t, Controls> controls;  // per key (lattice entity)
    // Read-back slots for queue_stats(): 8 bytes each, persistently mapped (host memory, so copying the
    // counters there is not a video-to-host migration); `fence` null = free.
    struct Readback {
        gfx::Buffer buffer;
        const std::uint32_t* mapped = nullptr;
        GLsync fence = nullptr;
        std::uint64_t tag = 0;
    };
    std::vector<Readback> readbacks;
    std::size_t scratch_capacity = 0;
    std::uint64_t uploads = 0;
    std::uint64_t sync_readbacks = 0;
    GLint max_ubo = 0;  // GL_MAX_UNIFORM_BLOCK_SIZE, queried once (a glGet can stall a threaded driver)
    GLint max_shared = 0;  // GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, same
    bool software = false;  // gfx::software_rasterizer(), for GpuBernsteinKernel::automatic
    GpuBernsteinKernel kernel = GpuBernsteinKernel::automatic, last_kernel = GpuBernsteinKernel::automatic;
    ~Impl() {  // GL objects before the context
        for (Readback& r : readbacks)
            if (r.fence) glDeleteSync(r.fence);
        readbacks.clear();
        program.reset(), ubo.reset(), stats.reset(), scratch.reset();
        specialised.clear();
        controls.clear();
    }
};

GpuDeformer::GpuDeformer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
GpuDeformer::GpuDeformer(GpuDeformer&&) noexcept = default;
GpuDeformer& GpuDeformer::operator=(GpuDeformer&&) noexcept = default;
GpuDeformer::~GpuDeformer() = default;

Result<GpuDeformer> GpuDeformer::create() {
    auto impl = std::make_unique<Impl>();
    auto program = gfx::load_compute_program("ffd/deform.comp", "ffd.deform");
    if (!program) return program.error();
    impl->program = std::move(*program);
    glGetIntegerv(GL_MAX_UNIFORM_BLOCK_SIZE, &impl->max_ubo);
    glGetIntegerv(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, &impl->max_shared);
    impl->software = gfx::software_rasterizer();
    impl->ubo = gfx::Buffer::create("ffd.lattice_block");
    glNamedBufferData(impl->ubo.id(), sizeof(detail::FfdBlock), nullptr, GL_DYNAMIC_DRAW);
    impl->stats = gfx::Buffer::create("ffd.stats");
    const std::uint32_t zero[2] = {0, 0};
    glNamedBufferData(impl->stats.id(), sizeof zero, zero, GL_DYNAMIC_READ);
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

std::uint64_t GpuDeformer::upload_count() const { return m_impl->uploads; }
void GpuDeformer::set_bernstein_kernel(GpuBernsteinKernel kernel) { m_impl->kernel = kernel; }
GpuBernsteinKernel GpuDeformer::last_bernstein_kernel() const { return m_impl->last_kernel; }

void GpuDeformer::retain_keys(const std::vector<std::uint64_t>& live) {
    for (auto it = m_impl->controls.begin(); it != m_impl->controls.end();)
        it = std::find(live.begin(), live.end(), it->first) == live.end() ? m_impl->controls.erase(it) : std::next(it);
}

Status GpuDeformer::dispatch(const Lattice& lattice, std::uint64_t key, std::uint64_t stamp, const glm::dvec3& cloud_origin,
                             GLuint in, GLuint out, std::uint32_t count) {
    if (Status s = validate(lattice); !s) return s;
    Impl& m = *m_impl;
    // Same preparation as the CPU kernels (float displacements, M⁻¹, origin offset in double).
    const detail::Prepared P = detail::prepare(lattice, cloud_origin);
    const detail::FfdBlock block = detail::make_ffd_block(lattice, P, count);
    glNamedBufferSubData(m.ubo.id(), 0, sizeof block, &block);
    Impl::Controls& cp = m.controls[key];
    if (!cp.buffer) cp.buffer = gfx::Buffer::create("ffd.control_points");
    if (stamp == 0 || stamp != cp.stamp) {  // control points only when edited
        detail::upload_control_points(cp.buffer.id(), cp.capacity, lattice, P);
        cp.stamp = stamp;
        ++m.uploads;
    }
    // Bernstein: a program specialised for this lattice shape and kernel (compiled once each; constant
    // loop bounds, small arrays). B-spline reads 4 neighbours per axis whatever the size: generic program.
    GLuint program = m.program.id();
    const bool bernstein = lattice.basis == LatticeBasis::bernstein;
    const bool fits_shared = lattice.size() * 3 * sizeof(float) <= std::size_t(m.max_shared);
    const bool cp_shared = bernstein && fits_shared &&
                           (m.kernel == GpuBernsteinKernel::shared || (m.kernel == GpuBernsteinKernel::automatic && !m.software));
    const bool cp_ubo = bernstein && !cp_shared && lattice.size() * 16 <= std::size_t(m.max_ubo);
    const std::uint32_t local_size = cp_shared ? 256 : 64;  // deform.comp's FFD_LOCAL_SIZE
    if (bernstein) m.last_kernel = cp_shared ? GpuBernsteinKernel::shared : GpuBernsteinKernel::direct;
    const std::uint64_t shape = (std::uint64_t(lattice.divisions.x) << 24) | (std::uint64_t(lattice.divisions.y) << 12) |
                                std::uint64_t(lattice.divisions.z) | (std::uint64_t(lattice.basis) << 40) |
                                (std::uint64_t(cp_shared) << 44);
    auto sp = m.specialised.find(shape);
    if (bernstein && sp == m.specialised.end()) {
        const int maxb = std::max({lattice.divisions.x, lattice.divisions.y, lattice.divisions.z}) + 1;
        gfx::Defines defines = {{"FFD_L", std::to_string(lattice.divisions.x)},
                                {"FFD_M", std::to_string(lattice.divisions.y)},
                                {"FFD_N", std::to_string(lattice.divisions.z)},
                                {"FFD_MAXB", std::to_string(maxb)}};
        if (cp_shared) {
            defines.push_back({"FFD_CP_SHARED", std::to_string(lattice.size())});
            defines.push_back({"FFD_LOCAL_SIZE", std::to_string(local_size)});
        }
        if (cp_ubo) defines.push_back({"FFD_CP_UBO", std::to_string(lattice.size())});
        auto prog = gfx::load_compute_program("ffd/deform.comp", cp_shared ? "ffd.deform.shared" : "ffd.deform.specialised", defines);
        if (!prog) return prog.error();
        sp = m.specialised.emplace(shape, std::move(*prog)).first;
    }
    if (lattice.basis == LatticeBasis::bernstein) program = sp->second.id();
    glUseProgram(program);
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FFD, m.ubo.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_CONTROL_POINTS, cp.buffer.id());
    if (cp_ubo) glBindBufferRange(GL_UNIFORM_BUFFER, SFFD_UBO_FFD_CONTROL, cp.buffer.id(), 0, GLsizeiptr(lattice.size() * 16));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_IN, in);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_OUT, out);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_STATS, m.stats.id());
    // A 2D grid beyond 65,535 groups (4.19M splats): runtime/gfx/dispatch.h.
    if (Status s = gfx::dispatch_1d(count, local_size); !s) return s;
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    return {};
}

DeformStats GpuDeformer::read_stats() {
    std::uint32_t v[2] = {0, 0};
    glGetNamedBufferSubData(m_impl->stats.id(), 0, sizeof v, v);
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
    glClearNamedBufferData(m_impl->stats.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
}

bool GpuDeformer::queue_stats(std::uint64_t tag) {
    Impl& m = *m_impl;
    auto slot = std::find_if(m.readbacks.begin(), m.readbacks.end(), [](const Impl::Readback& r) { return !r.fence; });
    if (slot == m.readbacks.end()) {
        Impl::Readback r;
        r.buffer = gfx::Buffer::create("ffd.stats_readback");
        const GLbitfield flags = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
        glNamedBufferStorage(r.buffer.id(), 2 * sizeof(std::uint32_t), nullptr, flags);
        r.mapped = static_cast<const std::uint32_t*>(glMapNamedBufferRange(r.buffer.id(), 0, 2 * sizeof(std::uint32_t), flags));
        if (!r.mapped) return false;  // the GL error callback has reported why; these statistics are lost
        m.readbacks.push_back(std::move(r));
        slot = m.readbacks.end() - 1;
    }
    glCopyNamedBufferSubData(m.stats.id(), slot->buffer.id(), 0, 0, 2 * sizeof(std::uint32_t));
    slot->fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    slot->tag = tag;
    return slot->fence != nullptr;
}

std::vector<GpuDeformer::TaggedStats> GpuDeformer::poll_stats() {
    std::vector<TaggedStats> done;
    for (Impl::Readback& r : m_impl->readbacks) {
        if (!r.fence) continue;
        // Zero timeout: asks, never waits. The flush bit makes sure the fence reaches the GPU.
        const GLenum state = glClientWaitSync(r.fence, GL_SYNC_FLUSH_COMMANDS_BIT, 0);
        if (state != GL_ALREADY_SIGNALED && state != GL_CONDITION_SATISFIED) continue;
        glDeleteSync(r.fence);
        r.fence = nullptr;
        DeformStats s;
        s.inverted = r.mapped[0];
        s.inside = r.mapped[1];
        s.backend = Backend::fast;
        done.push_back({r.tag, s});
    }
    return done;
}

std::size_t GpuDeformer::pending_stats() const {
    return std::size_t(std::count_if(m_impl->readbacks.begin(), m_impl->readbacks.end(),
                                     [](const Impl::Readback& r) { return r.fence != nullptr; }));
}

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
        glNamedBufferSubData(m.scratch.id(), 0, GLsizeiptr(splats.size() * sizeof(gpu::GpuSplat)), splats.data());
    reset_stats();
    if (Status s = dispatch(lattice, ~std::uint64_t(0), 0, in.origin, m.scratch.id(), m.scratch.id(), std::uint32_t(in.count)); !s)
        return s.error();
    if (!splats.empty())
        glGetNamedBufferSubData(m.scratch.id(), 0, GLsizeiptr(splats.size() * sizeof(gpu::GpuSplat)), splats.data()), ++m.sync_readbacks;
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

}  // namespace sffd::ffd
