// 3DGS PLY streamed through one lattice: centres, Σ' = J Σ Jᵀ as scale + rotation and SH rotated by the
// polar rotation of J, by the engine's Gaussian deformation (gaussian::deform; --backend gpu: the compute
// deformer on a headless context, SH coefficients rotated on the GPU, ShMode::rotate_coefficients). Every
// other property and element is copied as read. GPU timings include the upload and read-back of a chunk,
// not the compilation of its programs (timed apart: the first chunk runs once more before it is timed).
// Gaussians whose GPU result was not finite are written transparent.
#include "systems/ffd/stream_deform_gaussian.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/gfx/context.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gpu_deform.h"

namespace sffd::ffd::detail {

namespace {
using Clock = std::chrono::steady_clock;
constexpr std::size_t kChunkRows = 1 << 16;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

Result<StreamDeformResult> stream_gaussians(const StreamDeformRequest& req, ply::Reader& reader,
                                            const StreamProgress& progress) {
    const std::string& in_path = req.input;
    const Lattice& lattice = req.lattices[0];
    const std::string& label = req.lattice_label.empty() ? in_path : req.lattice_label;
    const Backend backend = req.backend == StreamBackend::reference ? Backend::reference : Backend::automatic;
    const std::size_t chunk_rows = req.chunk_rows > 0 ? req.chunk_rows : kChunkRows;
    // GPU backend: a headless context and the compute deformer (declared in this order: the deformer's GL
    // objects go before the context).
    std::optional<gfx::GlContext> context;
    std::optional<gaussian::GpuGaussianDeformer> gpu;
    if (req.backend == StreamBackend::gpu) {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false});
        if (!c) return make_error(in_path + ": --backend gpu: " + c.message());
        context.emplace(std::move(*c));
        auto d = gaussian::GpuGaussianDeformer::create();
        if (!d) return make_error(in_path + ": --backend gpu: " + d.message());
        gpu.emplace(std::move(*d));
    }
    StreamDeformResult result;
    result.kind = StreamKind::gaussians;
    std::size_t not_finite = 0;
    // The chunk's per-Gaussian weights (a vertex property `weight`, kept in the output as read), or none.
    std::vector<float> weights;
    // One chunk through the chosen backend; `out` may be `in` (CPU) or is replaced (GPU).
    auto run_deform = [&](const GaussianCloud& in, GaussianCloud& out) -> Result<gaussian::DeformStats> {
        if (!gpu) {
            gaussian::DeformOptions options{backend, false, gaussian::ShMode::rotate_coefficients};
            options.weights = weights.empty() ? nullptr : weights.data();
            auto st = gaussian::deform(lattice, in, out, options);
            if (st && &out == &in) not_finite += st->not_finite;  // the timing copies are not counted
            return st;
        }
        gaussian::GpuDeformStats st;
        auto got = gaussian::deform_on_gpu(*gpu, {&lattice}, in, gaussian::ShMode::rotate_coefficients, &st,
                                           weights);
        if (!got) return got.error();
        out = std::move(*got);
        not_finite += st.not_finite;
        gaussian::DeformStats ds;
        ds.inside = st.inside, ds.inverted = st.inverted, ds.degenerate = st.degenerate;
        return ds;
    };
    const auto t_start = Clock::now();
    const ply::Header& in_header = reader.header();
    const ply::Element& ve = in_header.elements[std::size_t(in_header.find("vertex"))];
    auto layout = gaussian::ply_layout(ve, in_path);
    if (!layout) return layout.error();
    result.sh_degree = layout->degree;
    const int weight_col = assets::ply_weight_property(ve);
    const bool weighted = weight_col >= 0;
    ply::Header out_header = in_header;
    out_header.format = req.ascii ? ply::Format::ascii : ply::Format::binary_little_endian;
    auto writer = ply::Writer::create(req.output, out_header);
    if (!writer) return writer.error();

    result.timing_ms.assign(std::size_t(std::max(req.timing_runs, 0)), 0.0);
    bool compiled = false;
    gaussian::DeformStats total;
    std::uint64_t row = 0;
    ply::Chunk chunk;
    GaussianCloud g, scratch;
    for (const ply::Element& e : in_header.elements) {
        if (auto s = reader.seek_element(e.name); !s) return s.error();
        while (true) {
            auto t0 = Clock::now();
            auto rows = reader.read_rows(chunk_rows, chunk);
            if (!rows) return rows.error();
            if (*rows == 0) break;
            if (e.name == "vertex") {
                g = GaussianCloud{};
                g.sh_degree = layout->degree;
                if (auto s = gaussian::append_from_chunk(chunk, *layout, row, in_path, g); !s)
                    return s.error();
                // The same validation as every cloud read whole (read_gaussians), row numbers of the file.
                if (auto s = gaussian::validate(g, in_path, row); !s) return s.error();
                weights.clear();
                if (weighted) {
                    const std::vector<double>& w = chunk.columns[std::size_t(weight_col)].values;
                    if (Status s = assets::check_ply_weights(w, chunk.rows, row, in_path); !s)
                        return s.error();
                    weights.assign(w.begin(), w.begin() + std::ptrdiff_t(chunk.rows));
                }
                result.read_ms += ms_since(t0);
                for (std::size_t r = 0; r < result.timing_ms.size();
                     ++r) {  // on a copy: g is still the input
                    t0 = Clock::now();
                    if (auto s = run_deform(g, scratch); !s) return make_error(label + ": " + s.message());
                    result.timing_ms[r] += ms_since(t0);
                }
                // The GPU's programs are specialised per lattice shape and outputs and compiled at their
                // first dispatch (seconds with a cold shader cache): that dispatch is timed apart, on a
                // copy, so the deformation time is the deformation's.
                if (gpu && !compiled) {
                    t0 = Clock::now();
                    const std::size_t counted = not_finite;
                    if (auto s = run_deform(g, scratch); !s) return make_error(label + ": " + s.message());
                    not_finite = counted;
                    result.set_up_ms = ms_since(t0);
                    compiled = true;
                }
                t0 = Clock::now();
                const std::size_t bad_before = not_finite;
                auto stats = run_deform(g, g);
                if (!stats) return make_error(label + ": " + stats.message());
                result.deform_ms += ms_since(t0);
                total.inside += stats->inside, total.inverted += stats->inverted,
                    total.degenerate += stats->degenerate;
                // Opacity is written back only when some were zeroed (the rest keep the file's bits).
                gaussian::store_to_chunk(g, *layout, not_finite != bad_before, chunk);
                row += *rows;
                if (progress) progress(row, ve.count);
            }
            if (auto s = writer->write_rows(chunk); !s) return s.error();
        }
    }
    if (auto s = writer->finish(); !s) return s.error();
    result.total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    result.points = row;
    result.inverted = total.inverted;
    result.degenerate = total.degenerate;
    result.not_finite = not_finite;
    result.inside = {total.inside};
    return result;
}

}  // namespace sffd::ffd::detail
