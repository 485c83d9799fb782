#include "systems/gaussian/gpu_deform.h"

#include "runtime/gfx/residency.h"

#include <algorithm>
#include <string>
#include <unordered_map>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "runtime/gfx/ssbo_batch.h"
#include "runtime/scene/point_pages.h"
#include "shaders/common/bindings.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/gpu_kernel.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

namespace {

constexpr std::size_t kStats = GpuGaussianDeformer::kCounters;

// Makes `buffer` hold at least `bytes` (contents undefined when it grows).
void ensure(gfx::Buffer& buffer, const char* label, std::size_t bytes) {
    gfx::reserve_buffer(buffer, label, bytes);
}

}  // namespace

struct GpuGaussianDeformer::Impl {
    ffd::detail::DeformPrograms
        programs;  // the lattice set-up of ffd::GpuDeformer (systems/ffd/gpu_kernel.h)
    gfx::Buffer stats, sh_tables;
    ffd::detail::StatsReadbacks readbacks;  // queue_stats(): kStats counters a page
    std::uint64_t sync_readbacks = 0;
};

GpuGaussianDeformer::GpuGaussianDeformer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
GpuGaussianDeformer::GpuGaussianDeformer(GpuGaussianDeformer&&) noexcept = default;
GpuGaussianDeformer& GpuGaussianDeformer::operator=(GpuGaussianDeformer&&) noexcept = default;
GpuGaussianDeformer::~GpuGaussianDeformer() = default;

Result<GpuGaussianDeformer> GpuGaussianDeformer::create() {
    auto impl = std::make_unique<Impl>();
    auto programs =
        ffd::detail::DeformPrograms::create("gaussian/deform.comp", "gaussian.deform", "gaussian.deform");
    if (!programs) return programs.error();
    impl->programs = std::move(*programs);
    // Bound where a program declares a buffer it does not use (the counters are the cloud's own).
    impl->stats = gfx::Buffer::create("gaussian.deform.unused");
    const std::uint32_t zero[kStats] = {};
    glNamedBufferData(impl->stats.id(), sizeof zero, zero, GL_DYNAMIC_COPY);
    // deform.comp's sh_tab[]: the CPU rotation's sample directions and inverse evaluation matrices.
    std::vector<float> tables;
    for (int band = 1; band <= 3; ++band) {
        glm::dvec3 dirs[7];
        double inv[49];
        sh_sample_tables(band, dirs, inv);
        for (int j = 0; j < 2 * band + 1; ++j)
            tables.insert(tables.end(), {float(dirs[j].x), float(dirs[j].y), float(dirs[j].z)});
    }
    for (int band = 1; band <= 3; ++band) {
        glm::dvec3 dirs[7];
        double inv[49];
        sh_sample_tables(band, dirs, inv);
        for (int k = 0; k < (2 * band + 1) * (2 * band + 1); ++k) tables.push_back(float(inv[k]));
    }
    impl->sh_tables = gfx::Buffer::create("gaussian.deform.sh_tables");
    glNamedBufferStorage(impl->sh_tables.id(), GLsizeiptr(tables.size() * sizeof(float)), tables.data(), 0);
    return GpuGaussianDeformer(std::move(impl));
}

void GpuGaussianDeformer::set_bernstein_kernel(ffd::GpuBernsteinKernel kernel) {
    m_impl->programs.kernel = kernel;
}
ffd::GpuBernsteinKernel GpuGaussianDeformer::last_bernstein_kernel() const {
    return m_impl->programs.last_kernel;
}
std::uint64_t GpuGaussianDeformer::upload_count() const { return m_impl->programs.uploads; }
std::uint64_t GpuGaussianDeformer::sync_readbacks() const { return m_impl->sync_readbacks; }
void GpuGaussianDeformer::retain_keys(const std::vector<std::uint64_t>& live) {
    m_impl->programs.retain_keys(live);
}

GpuDeformStats GpuGaussianDeformer::read_stats(const GpuGaussians& cloud) {
    std::uint32_t v[kStats] = {};
    if (cloud.page_stats)
        ffd::detail::read_page_counters(cloud.page_stats.id(), cloud.page_stats_words, kStats, v);
    ++m_impl->sync_readbacks;
    GpuDeformStats s;
    s.inverted = v[0], s.inside = v[1], s.not_finite = v[2], s.degenerate = v[3];
    return s;
}

bool GpuGaussianDeformer::queue_stats(std::uint64_t tag, GLuint page_stats, std::size_t words) {
    return m_impl->readbacks.queue(page_stats, words, tag, "gaussian.deform.stats_readback");
}

std::vector<GpuGaussianDeformer::TaggedStats> GpuGaussianDeformer::poll_stats() {
    std::vector<TaggedStats> done;
    m_impl->readbacks.poll([&](std::uint64_t tag, const std::uint32_t* counters, std::size_t words) {
        std::uint32_t v[kStats];
        ffd::detail::sum_page_counters(counters, words, kStats, v);
        TaggedStats t;
        t.tag = tag;
        t.stats.inverted = v[0], t.stats.inside = v[1], t.stats.not_finite = v[2], t.stats.degenerate = v[3];
        done.push_back(t);
    });
    return done;
}

Status GpuGaussianDeformer::dispatch(const Lattice& lattice, std::uint64_t key, std::uint64_t stamp,
                                     const glm::dvec3& cloud_origin, const Buffers& b, std::uint32_t count,
                                     std::span<const gfx::SsboBatch> ranges) {
    if (Status s = ffd::validate(lattice); !s) return s;
    if (!b.stats) return make_error("gaussian::GpuGaussianDeformer: no per-page counters to count into");
    if (b.sh_out && (b.sh_degree < 1 || b.sh_degree > 3))  // degree 0 has no coefficient to rotate
        return make_error("gaussian::GpuGaussianDeformer: rotated SH coefficients need degree 1..3");
    Impl& m = *m_impl;
    // The ffd pass's lattice set-up and kernel choice (systems/ffd/gpu_kernel.h): block UBO, control points
    // when edited, Bernstein programs specialised per lattice shape; then this shader's own buffers.
    // The program is also specialised by what the dispatch writes (frames, coefficients): the code of
    // outputs it does not write is left out. Branching on uniforms instead, 1M Gaussians of SH degree 0
    // (the profile's synthetic scenes) took 1.9-2.1 s on llvmpipe, against 1.0-1.4 s specialised.
    const bool with_sh = b.sh_out && b.sh_in;
    ffd::detail::DeformPrograms::Variant variant;
    variant.id = 1u | (b.frames ? 2u : 0u) | (with_sh ? 4u : 0u) | (b.weights ? 8u : 0u);
    variant.defines = {{"GAUSS_FRAMES", b.frames ? "1" : "0"}, {"GAUSS_SH", with_sh ? "1" : "0"}};
    if (b.weights) variant.defines.push_back({"FFD_WEIGHTS", "1"});  // weighted clouds only
    variant.label =
        std::string(b.frames ? ".frames" : "") + (with_sh ? ".sh" : "") + (b.weights ? ".weighted" : "");
    auto bound = m.programs.bind(lattice, key, stamp, cloud_origin, count, &variant);
    if (!bound) return bound.error();
    // Each uniform only where the program has it (explicit locations: no name lookup, a glGet that can
    // stall a threaded driver, on the frame's path).
    const GLuint program = bound->program;
    if (b.frames) glProgramUniform1ui(program, 0, b.compose_frames ? 1u : 0u);
    if (with_sh) glProgramUniform1i(program, 1, b.sh_degree);
    // Unused bindings still get a buffer (a small stand-in): nothing reads or writes them.
    if (!b.frames) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_FRAMES, m.stats.id());
    if (!with_sh) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_SH, m.stats.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DEFORMED_SH, m.stats.id());
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_SH_TABLES, m.sh_tables.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_STATS, b.stats);
    // Write-after-read across frames: the last frame's projection read the deformed buffers overwritten here.
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "gaussian.deform.reuse");
    // Clouds whose Gaussians, frames or SH exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE run in element ranges
    // (every buffer here is indexed by the Gaussian's own index); in place, each batch touches only its
    // range.
    const std::uint64_t gaussian = sizeof(gpu::GpuGaussian), frame = 3 * 4 * sizeof(float);
    const std::uint64_t sh = with_sh ? std::uint64_t(sh_coeffs(b.sh_degree)) * 3 * sizeof(float) : 0;
    const std::uint64_t strides[] = {gaussian, b.frames ? frame : 0, sh};
    const auto bind_batch = [&](const gfx::SsboBatch& batch) {
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_IN, b.in, batch, gaussian);
        gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_DEFORMED, b.out, batch, gaussian);
        if (b.frames) gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_FRAMES, b.frames, batch, frame);
        if (with_sh) {
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_SH, b.sh_in, batch, sh);
            gfx::bind_ssbo_range(SFFD_GAUSS_SSBO_DEFORMED_SH, b.sh_out, batch, sh);
        }
        if (b.weights) gfx::bind_ssbo_range(SFFD_SSBO_WEIGHTS, b.weights, batch, sizeof(float));
    };
    if (Status s = m.programs.dispatch_batches(*bound, count, strides, bind_batch, ranges); !s) return s;
    gfx::memory_barrier(
        GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT,
        "gaussian.deform");
    return {};
}

Status GpuGaussianDeformer::deform(GpuGaussians& dst, const glm::dvec3& origin,
                                   const std::vector<const Lattice*>& lattices,
                                   const std::vector<std::uint64_t>& keys,
                                   const std::vector<std::uint64_t>& stamps, ShMode sh, const GpuRedo& redo,
                                   std::size_t* pages_redone) {
    if (!dst.rest)
        return make_error("gaussian::GpuGaussianDeformer::deform(): the cloud's rest buffer is not uploaded");
    if (keys.size() != lattices.size() || stamps.size() != lattices.size())
        return make_error("gaussian::GpuGaussianDeformer::deform(): one key and one stamp per lattice");
    const std::uint32_t n = dst.count;
    const std::size_t np = page_count(n);
    const bool view_dependent = dst.sh_degree > 0;
    const bool with_frames = view_dependent && sh == ShMode::rotate_view;
    const bool with_sh = view_dependent && sh == ShMode::rotate_coefficients;
    if (with_sh && !dst.sh)
        return make_error("gaussian::GpuGaussianDeformer::deform(): the cloud's SH buffer is not uploaded");
    const ShSource source = with_frames ? ShSource::frames : with_sh ? ShSource::rotated : ShSource::authored;
    const std::size_t sh_bytes = std::size_t(n) * std::size_t(sh_coeffs(dst.sh_degree)) * 3 * sizeof(float);
    // Page-wise only on top of this pass's own last output, with every lattice valid: a skipped lattice
    // would leave the pages not redone disagreeing with the redone ones.
    bool paged = redo.page_wise && dst.state == gfx::Residency::deformed_gpu && dst.sh_source == source &&
                 std::all_of(lattices.begin(), lattices.end(),
                             [](const Lattice* l) { return ffd::validate(*l).ok(); });
    paged = ffd::resident_page_stats(dst, np, kStats) && paged;
    ensure(dst.deformed, "gaussians.deformed", std::size_t(n) * sizeof(gpu::GpuGaussian));
    if (with_frames) ensure(dst.frames, "gaussians.frames", std::size_t(n) * 3 * sizeof(float) * 4);
    if (with_sh) ensure(dst.deformed_sh, "gaussians.deformed_sh", sh_bytes);
    const std::vector<gfx::SsboBatch> whole{{0, n}};
    const std::vector<gfx::SsboBatch> ranges = paged ? ffd::page_runs(redo.pages, n) : whole;
    if (pages_redone) *pages_redone = paged ? redo.pages.size() : np;
    if (ranges.empty()) return {};  // no page to redo
    ffd::clear_page_stats(dst, ranges, kStats);
    // The first lattice reads `rest` (and `sh`), the next ones deform `deformed` (and `deformed_sh`) in
    // place; with no lattice (or when every one fails) the outputs start as copies of the inputs and the
    // frames as identity.
    Buffers b;
    b.in = dst.rest.id();
    b.out = dst.deformed.id();
    b.frames = with_frames ? dst.frames.id() : 0;
    b.sh_in = with_sh ? dst.sh.id() : 0;
    b.sh_out = with_sh ? dst.deformed_sh.id() : 0;
    b.sh_degree = dst.sh_degree;
    b.weights = dst.weights ? dst.weights.id() : 0;
    b.stats = dst.page_stats.id();
    Status first_error;
    bool failed = false;
    const Buffers first = b;
    auto run = [&](std::span<const gfx::SsboBatch> over) {
        b = first;
        for (std::size_t d = 0; d < lattices.size(); ++d) {
            if (Status s = dispatch(*lattices[d], keys[d], stamps[d], origin, b, n, over); !s) {
                if (first_error) first_error = s;
                failed = true;
                continue;
            }
            b.in = dst.deformed.id();
            b.compose_frames = true;
            if (with_sh) b.sh_in = dst.deformed_sh.id();
        }
    };
    run(ranges);
    if (paged && failed) {  // the pages left alone would disagree with the redone ones: redo them all
        ffd::clear_page_stats(dst, whole, kStats);
        if (pages_redone) *pages_redone = np;
        run(whole);
    }
    if (b.in == dst.rest.id() && n > 0) {
        glCopyNamedBufferSubData(dst.rest.id(), dst.deformed.id(), 0, 0,
                                 GLsizeiptr(std::size_t(n) * sizeof(gpu::GpuGaussian)));
        if (with_sh) glCopyNamedBufferSubData(dst.sh.id(), dst.deformed_sh.id(), 0, 0, GLsizeiptr(sh_bytes));
        if (with_frames) {
            std::vector<float> identity(std::size_t(n) * 12, 0.0f);
            for (std::size_t i = 0; i < n; ++i)
                identity[i * 12] = identity[i * 12 + 5] = identity[i * 12 + 10] = 1.0f;
            glNamedBufferSubData(dst.frames.id(), 0, GLsizeiptr(identity.size() * sizeof(float)),
                                 identity.data());
        }
    }
    dst.sh_source = source;
    gfx::set_deformed(dst, gfx::Residency::deformed_gpu);
    return first_error;
}

Result<GaussianCloud> read_back(const GpuGaussians& src, const glm::dvec3& origin) {
    const GLuint buffer = src.draw_buffer();
    if (!buffer) return make_error("gaussian::read_back(): nothing uploaded");
    const std::size_t n = src.count;
    std::vector<gpu::GpuGaussian> rows(n);
    if (n) glGetNamedBufferSubData(buffer, 0, GLsizeiptr(n * sizeof(gpu::GpuGaussian)), rows.data());
    GaussianCloud g;
    g.origin = origin;
    g.sh_degree = src.sh_degree;
    g.positions.resize(n), g.scales.resize(n), g.rotations.resize(n), g.opacities.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const gpu::GpuGaussian& r = rows[i];
        g.positions[i] = {r.pos_opacity[0], r.pos_opacity[1], r.pos_opacity[2]};
        g.opacities[i] = r.pos_opacity[3];
        g.rotations[i] = glm::quat(r.rotation[0], r.rotation[1], r.rotation[2], r.rotation[3]);
        g.scales[i] = {r.scale[0], r.scale[1], r.scale[2]};
    }
    g.sh.resize(n * std::size_t(sh_coeffs(src.sh_degree)) * 3);
    if (!g.sh.empty() && src.sh_buffer())
        glGetNamedBufferSubData(src.sh_buffer(), 0, GLsizeiptr(g.sh.size() * sizeof(float)), g.sh.data());
    if (src.has_frames() && src.frames && n) {
        std::vector<glm::vec4> cols(n * 3);
        glGetNamedBufferSubData(src.frames.id(), 0, GLsizeiptr(cols.size() * sizeof(glm::vec4)), cols.data());
        g.sh_frames.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            g.sh_frames[i] =
                glm::mat3(glm::vec3(cols[3 * i]), glm::vec3(cols[3 * i + 1]), glm::vec3(cols[3 * i + 2]));
    }
    return g;
}

Result<GaussianCloud> deform_on_gpu(GpuGaussianDeformer& deformer,
                                    const std::vector<const Lattice*>& lattices, const GaussianCloud& cloud,
                                    ShMode sh, GpuDeformStats* stats, std::span<const float> weights) {
    GpuGaussians scratch;
    if (Status s = upload_rest(scratch, cloud, 1); !s) return s.error();
    ffd::resident_weights(scratch, weights, 1);
    // Stamp 0: always upload (the keys are this call's own, past the range of entity bits).
    std::vector<std::uint64_t> keys(lattices.size()), stamps(lattices.size(), 0);
    for (std::size_t d = 0; d < keys.size(); ++d) keys[d] = ~std::uint64_t(0) - d;
    if (Status s = deformer.deform(scratch, cloud.origin, lattices, keys, stamps, sh); !s) return s.error();
    if (stats) *stats = deformer.read_stats(scratch);
    return read_back(scratch, cloud.origin);
}

}  // namespace sffd::gaussian
