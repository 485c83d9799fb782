#include "systems/ffd/gpu_kernel.h"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <utility>
#include <vector>

#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/limits.h"
#include "runtime/scene/point_pages.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/gpu_block.h"

namespace sffd::ffd::detail {

static_assert(kPageShift == SFFD_PAGE_SHIFT, "the shaders count per page of the cloud's pages");

namespace {

// The points a shared-memory kernel copies: the lattice (Bernstein) or its zero-bordered grid (B-spline).
std::size_t shared_points(const Lattice& lattice) {
    if (lattice.basis == LatticeBasis::bernstein) return lattice.size();
    return std::size_t(lattice.divisions.x + 3) * std::size_t(lattice.divisions.y + 3) *
           std::size_t(lattice.divisions.z + 3);
}

}  // namespace

KernelChoice choose_kernel(const Lattice& lattice, GpuBernsteinKernel kernel, bool software,
                           std::size_t max_shared, std::size_t max_ubo) {
    const bool bernstein = lattice.basis == LatticeBasis::bernstein;
    const bool fits_shared =
        shared_points(lattice) * 3 * sizeof(float) + kDeformShaderSharedBytes <= max_shared;
    KernelChoice c;
    c.shared = fits_shared && (kernel == GpuBernsteinKernel::shared ||
                               (kernel == GpuBernsteinKernel::automatic && !software && bernstein));
    c.ubo = bernstein && !c.shared && lattice.size() * 16 <= max_ubo;
    c.runs = !bernstein && !c.shared && kernel != GpuBernsteinKernel::direct;
    return c;
}

Result<DeformPrograms> DeformPrograms::create(std::string shader, std::string program_label,
                                              std::string prefix) {
    DeformPrograms p;
    auto program = gfx::load_compute_program(shader, program_label);
    if (!program) return program.error();
    p.program = std::move(*program);
    p.shader = std::move(shader), p.program_label = std::move(program_label), p.prefix = std::move(prefix);
    glGetIntegerv(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, &p.max_shared);
    GLint align = 0;
    glGetIntegerv(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, &align);
    if (align > 0) p.ubo_align = align;
    p.software = gfx::software_rasterizer();
    p.ubo = gfx::Buffer::create(p.prefix + ".lattice_block");
    glNamedBufferData(p.ubo.id(), sizeof(FfdBlock), nullptr, GL_DYNAMIC_DRAW);
    return p;
}

Result<DeformPrograms::Bound> DeformPrograms::bind(const Lattice& lattice, std::uint64_t key,
                                                   std::uint64_t stamp, const glm::dvec3& cloud_origin,
                                                   std::uint32_t count, const Variant* variant) {
    if (variant && variant->id >= (1u << 16))
        return make_error(program_label + ": shader variant id past 2^16");
    // The CPU kernels' values (float displacements, M⁻¹, origin offset in double), without their tables.
    const Prepared P = prepare(lattice, cloud_origin, PrepareFor::gpu_controls);
    // A program specialised for this lattice shape, basis and kernel (compiled once each; constant loop
    // bounds, small arrays, the other basis's code left out). Bernstein's control points go into shared
    // memory on hardware GPUs when their xyz fit (each splat reads all of them), else into a UBO when they
    // fit one. The B-spline reads its grid from the SSBO, packed in runs along u by default (bspline_runs:
    // 48 loads per splat instead of 64, all served by the cache): on an NVIDIA H100 at 1M splats 0.115 ms
    // against 0.129 ms point by point and 0.134 ms copying the 26 KB grid into every group's shared memory
    // (bench_ffd_gpu, GPU time), so shared memory serves it only when asked.
    const bool bernstein = lattice.basis == LatticeBasis::bernstein;
    const KernelChoice choice = choose_kernel(lattice, kernel, software, std::size_t(std::max(max_shared, 0)),
                                              std::size_t(std::max(gfx::limits().max_uniform_block_size, 0)));
    const bool cp_shared = choice.shared, cp_ubo = choice.ubo, runs = choice.runs;
    Controls& cp = controls[key];
    if (!cp.buffer) cp.buffer = gfx::Buffer::create(prefix + ".control_points");
    if (stamp == 0 || stamp != cp.stamp || runs != cp.runs) {  // only when edited or the layout changes
        upload_control_points(cp.buffer.id(), cp.capacity, lattice, P, runs);
        cp.stamp = stamp;
        cp.runs = runs;
        ++uploads;
    }
    Bound b;
    b.block = make_ffd_block(lattice, P, count);
    b.local_size = cp_shared ? 256 : 64;
    last_kernel = cp_shared ? GpuBernsteinKernel::shared
                  : runs    ? GpuBernsteinKernel::packed
                            : GpuBernsteinKernel::direct;
    // Bernstein sums only the coordinates of ΔP that move (ffd_common.glsl, FFD_MOVE): one program per
    // set of them, compiled the first time an edit moves that set (at most 7 per shape). A lattice at rest
    // (every splat copied unchanged) keeps the program of all three.
    const bool moving = bernstein && P.any_moved && P.coords < 3;
    std::uint64_t moving_mask = 0;
    for (int a = 0; moving && a < P.coords; ++a) moving_mask |= 1u << P.coord[a];
    const std::uint64_t shape =
        (std::uint64_t(lattice.divisions.x) << 24) | (std::uint64_t(lattice.divisions.y) << 12) |
        std::uint64_t(lattice.divisions.z) | (moving_mask << 36) | (std::uint64_t(cp_shared) << 44) |
        (std::uint64_t(cp_ubo) << 45) | (std::uint64_t(!bernstein) << 46) | (std::uint64_t(runs) << 47) |
        (std::uint64_t(variant ? variant->id : 0) << 48);
    auto sp = specialised.find(shape);
    if (sp == specialised.end()) {
        const int maxb = std::max({lattice.divisions.x, lattice.divisions.y, lattice.divisions.z}) + 1;
        gfx::Defines defines = {{"FFD_L", std::to_string(lattice.divisions.x)},
                                {"FFD_M", std::to_string(lattice.divisions.y)},
                                {"FFD_N", std::to_string(lattice.divisions.z)},
                                {"FFD_MAXB", std::to_string(maxb)},
                                {"FFD_BASIS", bernstein ? "0" : "1"}};
        if (cp_shared) {
            defines.push_back({"FFD_CP_SHARED", std::to_string(shared_points(lattice))});
            defines.push_back({"FFD_LOCAL_SIZE", std::to_string(b.local_size)});
        }
        if (cp_ubo) defines.push_back({"FFD_CP_UBO", std::to_string(lattice.size())});
        if (runs) defines.push_back({"FFD_BSPLINE_RUNS", "1"});
        if (moving) {
            std::string swizzle;
            for (int a = 0; a < P.coords; ++a) swizzle += "xyz"[P.coord[a]];
            defines.push_back({"FFD_MOVE", swizzle});
            defines.push_back({"FFD_MOVE_N", std::to_string(P.coords)});
            defines.push_back({"FFD_MOVE_A", std::to_string(P.coord[0])});
            if (P.coords > 1) defines.push_back({"FFD_MOVE_B", std::to_string(P.coord[1])});
        }
        if (variant) defines.insert(defines.end(), variant->defines.begin(), variant->defines.end());
        auto prog = gfx::load_compute_program(shader,
                                              program_label +
                                                  (cp_shared ? ".shared"
                                                   : runs    ? ".packed"
                                                             : ".specialised") +
                                                  (variant ? variant->label : std::string()),
                                              defines);
        if (!prog) return prog.error();
        sp = specialised.emplace(shape, std::move(*prog)).first;
    }
    b.program = sp->second.id();
    glUseProgram(b.program);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_CONTROL_POINTS, cp.buffer.id());
    if (cp_ubo)
        glBindBufferRange(GL_UNIFORM_BUFFER, SFFD_UBO_FFD_CONTROL, cp.buffer.id(), 0,
                          GLsizeiptr(lattice.size() * 16));
    return b;
}

Status DeformPrograms::dispatch_batches(const Bound& bound, std::uint32_t count,
                                        std::span<const std::uint64_t> strides,
                                        const std::function<void(const gfx::SsboBatch&)>& bind_batch,
                                        std::span<const gfx::SsboBatch> ranges) {
    const gfx::SsboBatch whole{0, count};
    if (ranges.empty()) ranges = std::span<const gfx::SsboBatch>(&whole, 1);
    // A range starts on a page, a multiple of every offset alignment (2^16 elements of at least 4 bytes),
    // so its batches, shifted to it, stay aligned.
    std::vector<gfx::SsboBatch> batches;
    for (const gfx::SsboBatch& r : ranges) {
        auto cut = gfx::ssbo_batches(r.count, strides);
        if (!cut) return cut.error();
        for (gfx::SsboBatch b : *cut) batches.push_back({r.first + b.first, b.count});
    }
    if (batches.empty()) return {};
    // Rewriting one block's count between batches would write into storage the previous batch's dispatch
    // reads: an update the driver must order behind that dispatch, which on an NVIDIA H200 made the CPU
    // wait for it (orphan_upload). So each batch gets its own block, all in one upload.
    const std::size_t align = std::size_t(std::max(ubo_align, 1));
    const std::size_t stride = (sizeof(FfdBlock) + align - 1) / align * align;
    std::vector<std::byte> blocks(stride * batches.size());
    for (std::size_t i = 0; i < batches.size(); ++i) {
        FfdBlock block = bound.block;
        block.count[0] = std::uint32_t(batches[i].count);
        block.count[2] = std::uint32_t(batches[i].first);
        std::memcpy(blocks.data() + i * stride, &block, sizeof block);
    }
    orphan_upload(ubo.id(), blocks.size(), blocks.data());
    for (std::size_t i = 0; i < batches.size(); ++i) {
        const gfx::SsboBatch& batch = batches[i];
        glBindBufferRange(GL_UNIFORM_BUFFER, SFFD_UBO_FFD, ubo.id(), GLintptr(i * stride),
                          GLsizeiptr(sizeof(FfdBlock)));
        bind_batch(batch);
        // A 2D grid beyond 65,535 groups (4.19M points at 64 wide): runtime/gfx/dispatch.h.
        if (Status s = gfx::dispatch_1d(batch.count, bound.local_size); !s) return s;
    }
    return {};
}

void DeformPrograms::retain_keys(const std::vector<std::uint64_t>& live) {
    for (auto it = controls.begin(); it != controls.end();)
        it =
            std::find(live.begin(), live.end(), it->first) == live.end() ? controls.erase(it) : std::next(it);
}

void sum_page_counters(const std::uint32_t* counters, std::size_t words, std::size_t per_page,
                       std::uint32_t* out) {
    std::fill(out, out + per_page, 0u);
    for (std::size_t w = 0; w < words; ++w) out[w % per_page] += counters[w];
}

void read_page_counters(GLuint buffer, std::size_t words, std::size_t per_page, std::uint32_t* out) {
    std::vector<std::uint32_t> v(words);
    if (words) glGetNamedBufferSubData(buffer, 0, GLsizeiptr(words * sizeof(std::uint32_t)), v.data());
    sum_page_counters(v.data(), words, per_page, out);
}

StatsReadbacks::~StatsReadbacks() {
    for (Slot& r : m_slots)
        if (r.fence) glDeleteSync(r.fence);
}

bool StatsReadbacks::queue(GLuint stats, std::size_t words, std::uint64_t tag, const std::string& label) {
    const std::size_t bytes = std::max<std::size_t>(words, 1) * sizeof(std::uint32_t);
    // A free slot that holds the words, else a free one made larger (a larger cloud), else a new one.
    auto free_slot = [&](bool fits) {
        return std::find_if(m_slots.begin(), m_slots.end(),
                            [&](const Slot& r) { return !r.fence && (!fits || r.capacity >= words); });
    };
    auto slot = free_slot(true);
    if (slot == m_slots.end()) slot = free_slot(false);
    if (slot == m_slots.end() && m_slots.size() >= kMaxSlots) return false;
    if (slot == m_slots.end()) slot = m_slots.insert(m_slots.end(), Slot{});
    if (slot->capacity < words || !slot->buffer) {
        slot->buffer = gfx::Buffer::create(label);  // the old storage (and its mapping) released
        const GLbitfield flags = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
        glNamedBufferStorage(slot->buffer.id(), GLsizeiptr(bytes), nullptr, flags);
        slot->mapped = static_cast<const std::uint32_t*>(
            glMapNamedBufferRange(slot->buffer.id(), 0, GLsizeiptr(bytes), flags));
        slot->capacity = slot->mapped ? std::max<std::size_t>(words, 1) : 0;
        if (!slot->mapped) return false;  // the GL error callback has reported why; these statistics are lost
    }
    if (words)
        glCopyNamedBufferSubData(stats, slot->buffer.id(), 0, 0, GLsizeiptr(words * sizeof(std::uint32_t)));
    slot->fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    slot->tag = tag;
    slot->words = words;
    return slot->fence != nullptr;
}

bool StatsReadbacks::signalled(Slot& r, bool flush) {
    // Zero timeout: asks, never waits.
    const GLenum state = glClientWaitSync(r.fence, flush ? GL_SYNC_FLUSH_COMMANDS_BIT : 0, 0);
    if (state != GL_ALREADY_SIGNALED && state != GL_CONDITION_SATISFIED) return false;
    glDeleteSync(r.fence);
    r.fence = nullptr;
    return true;
}

std::size_t StatsReadbacks::pending() const {
    return std::size_t(
        std::count_if(m_slots.begin(), m_slots.end(), [](const Slot& r) { return r.fence != nullptr; }));
}

}  // namespace sffd::ffd::detail
