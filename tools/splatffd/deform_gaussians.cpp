// deform_gaussian_file: any Gaussian format read whole (read_gaussians), deformed on the CPU, written by
// OUT's name. deform_gaussian_ply streams a 3DGS PLY through a lattice: chunks of vertex rows become
// GaussianClouds, are deformed (centres, Σ' = J Σ Jᵀ as scale + rotation, SH rotated by the polar rotation of
// J) and written back into the same columns; every other property and element is copied as read. --bench N
// re-runs the deformation of every chunk N more times and prints one JSON line:
// {"gaussians":..,"sh_degree":..,"backend":..,"median_ms":..,"min_ms":..,"runs":N,"gaussians_per_s":..,
//  "read_ms":..,"total_s":..}  (median/min: deformation only; read_ms: parse + convert of the input).
// --backend gpu: each chunk goes through the GPU deformation (systems/gaussian/gpu_deform.h) on a headless
// context, SH coefficients rotated on the GPU (ShMode::rotate_coefficients); its timings include the
// upload and read-back of the chunk, not the compilation of its programs (timed apart: the first chunk runs
// once more before it is timed). Gaussians whose GPU result was not finite are written transparent.
#include "tools/splatffd/deform_gaussians.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include "runtime/assets/ply.h"
#include "runtime/gfx/context.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_sog.h"
#include "systems/gaussian/gaussian_spz.h"
#include "systems/gaussian/gpu_deform.h"
#include "tools/splatffd/convert_gaussians.h"
#include "tools/splatffd/lattice_source.h"

namespace sffd::cli {

namespace {
using Clock = std::chrono::steady_clock;
constexpr std::size_t kChunkRows = 1 << 16;

int fail(const std::string& message) {
    std::fprintf(stderr, "splatffd deform: %s\n", message.c_str());
    return 1;
}
std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}
bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
// A 3DGS PLY by name: .ply but not PlayCanvas's .compressed.ply.
bool is_plain_ply(const std::string& path) {
    const std::string l = lower(path);
    return ends_with(l, ".ply") && !ends_with(l, ".compressed.ply");
}
double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
// A lattice that holds none of the Gaussians deformed nothing: said once, not hidden behind "deformed".
void warn_if_empty(const std::string& lattice, std::size_t inside, std::size_t count) {
    if (inside == 0 && count > 0)
        std::fprintf(stderr,
                     "splatffd deform: warning: lattice '%s' contains none of the %zu Gaussians: it deformed "
                     "nothing (is it the lattice of another cloud?)\n",
                     lattice.c_str(), count);
}
}  // namespace

int deform_gaussian_ply(const std::string& in_path, const std::string& out_path, const Lattice& lattice,
                        const std::string& lattice_path, const std::string& backend_name, int bench,
                        bool ascii) {
    const ffd::Backend backend =
        backend_name == "reference" ? ffd::Backend::reference : ffd::Backend::automatic;
    // GPU backend: a headless context and the compute deformer (declared in this order: the deformer's GL
    // objects go before the context).
    std::optional<gfx::GlContext> context;
    std::optional<gaussian::GpuGaussianDeformer> gpu;
    if (backend_name == "gpu") {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false});
        if (!c) return fail(in_path + ": --backend gpu: " + c.message());
        context.emplace(std::move(*c));
        auto d = gaussian::GpuGaussianDeformer::create();
        if (!d) return fail(in_path + ": --backend gpu: " + d.message());
        gpu.emplace(std::move(*d));
    }
    std::size_t not_finite = 0;
    // One chunk through the chosen backend; `out` may be `in` (CPU) or is replaced (GPU).
    auto run_deform = [&](const GaussianCloud& in, GaussianCloud& out) -> Result<gaussian::DeformStats> {
        if (!gpu) {
            auto st = gaussian::deform(lattice, in, out, backend, false);
            if (st && &out == &in) not_finite += st->not_finite;  // the timing copies are not counted
            return st;
        }
        gaussian::GpuDeformStats st;
        auto got = gaussian::deform_on_gpu(*gpu, {&lattice}, in, gaussian::ShMode::rotate_coefficients, &st);
        if (!got) return got.error();
        out = std::move(*got);
        not_finite += st.not_finite;
        gaussian::DeformStats ds;
        ds.inside = st.inside, ds.inverted = st.inverted, ds.degenerate = st.degenerate;
        return ds;
    };
    const auto t_start = Clock::now();
    auto reader = ply::Reader::open(in_path);
    if (!reader) return fail(reader.message());
    const ply::Header& in_header = reader->header();
    const ply::Element& ve = in_header.elements[std::size_t(in_header.find("vertex"))];
    auto layout = gaussian::ply_layout(ve, in_path);
    if (!layout) return fail(layout.message());
    ply::Header out_header = in_header;
    out_header.format = ascii ? ply::Format::ascii : ply::Format::binary_little_endian;
    auto writer = ply::Writer::create(out_path, out_header);
    if (!writer) return fail(writer.message());

    std::vector<double> rep_ms(std::size_t(bench), 0.0);
    double deform_ms = 0.0, read_ms = 0.0, compile_ms = 0.0;
    bool compiled = false;
    gaussian::DeformStats total;
    std::uint64_t row = 0;
    ply::Chunk chunk;
    GaussianCloud g, scratch;
    for (const ply::Element& e : in_header.elements) {
        if (auto s = reader->seek_element(e.name); !s) return fail(s.message());
        while (true) {
            auto t0 = Clock::now();
            auto rows = reader->read_rows(kChunkRows, chunk);
            if (!rows) return fail(rows.message());
            if (*rows == 0) break;
            if (e.name == "vertex") {
                g = GaussianCloud{};
                g.sh_degree = layout->degree;
                if (auto s = gaussian::append_from_chunk(chunk, *layout, row, in_path, g); !s)
                    return fail(s.message());
                // The same validation as every cloud read whole (read_gaussians), row numbers of the file.
                if (auto s = gaussian::validate(g, in_path, row); !s) return fail(s.message());
                read_ms += ms_since(t0);
                for (int r = 0; r < bench; ++r) {  // timing runs on a copy (the chunk is still the input)
                    t0 = Clock::now();
                    if (auto s = run_deform(g, scratch); !s) return fail(lattice_path + ": " + s.message());
                    rep_ms[std::size_t(r)] += ms_since(t0);
                }
                // The GPU's programs are specialised per lattice shape and outputs and compiled at their
                // first dispatch (seconds with a cold shader cache): that dispatch is timed apart, on a
                // copy, so the deformation time is the deformation's.
                if (gpu && !compiled) {
                    t0 = Clock::now();
                    const std::size_t counted = not_finite;
                    if (auto s = run_deform(g, scratch); !s) return fail(lattice_path + ": " + s.message());
                    not_finite = counted;
                    compile_ms = ms_since(t0);
                    compiled = true;
                }
                t0 = Clock::now();
                const std::size_t bad_before = not_finite;
                auto stats = run_deform(g, g);
                if (!stats) return fail(lattice_path + ": " + stats.message());
                deform_ms += ms_since(t0);
                total.inside += stats->inside, total.inverted += stats->inverted,
                    total.degenerate += stats->degenerate;
                gaussian::store_to_chunk(g, *layout, not_finite != bad_before,
                                         chunk);  // opacity only when some were zeroed
                row += *rows;
            }
            if (auto s = writer->write_rows(chunk); !s) return fail(s.message());
        }
    }
    if (auto s = writer->finish(); !s) return fail(s.message());
    const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    char compile_note[96] = "";
    if (compiled)
        std::snprintf(compile_note, sizeof compile_note,
                      ", GPU program set-up (shader compilation, first dispatch) %.1f ms", compile_ms);
    std::fprintf(
        stderr,
        "splatffd deform: %llu Gaussians (SH degree %d, %s), %zu inside, %zu inverted, %zu degenerate, "
        "%zu not finite (written transparent); deformation %.1f ms%s, read+convert %.1f ms, total with I/O "
        "%.2f s\n",
        static_cast<unsigned long long>(row), layout->degree, backend_name.c_str(), total.inside,
        total.inverted, total.degenerate, not_finite, deform_ms, compile_note, read_ms, total_s);
    warn_if_empty(lattice_path, total.inside, std::size_t(row));
    if (bench > 0) {
        std::sort(rep_ms.begin(), rep_ms.end());
        const double median = rep_ms.size() % 2
                                  ? rep_ms[rep_ms.size() / 2]
                                  : 0.5 * (rep_ms[rep_ms.size() / 2 - 1] + rep_ms[rep_ms.size() / 2]);
        std::printf(
            "{\"gaussians\":%llu,\"sh_degree\":%d,\"backend\":\"%s\",\"median_ms\":%.4f,\"min_ms\":%.4f,"
            "\"runs\":%d,"
            "\"gaussians_per_s\":%.4g,\"read_ms\":%.3f,\"total_s\":%.3f}\n",
            static_cast<unsigned long long>(row), layout->degree, backend_name.c_str(), median,
            rep_ms.front(), bench, median > 0 ? double(row) / (median * 1e-3) : 0.0, read_ms, total_s);
    }
    return 0;
}

bool is_gaussian_output(const std::string& out) {
    const std::string l = lower(out);
    return ends_with(l, ".ply") || ends_with(l, ".glb") || ends_with(l, ".spz") || ends_with(l, ".sog") ||
           std::filesystem::path(out).filename() == "meta.json";
}

bool deform_reads_gaussians_whole(const std::string& in, const std::string& out) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(std::filesystem::path(in) / "meta.json", ec)) return true;  // SOG
    if (!is_gaussian_file(in)) return false;
    if (!is_plain_ply(in) || !is_plain_ply(out)) return true;
    // A .ply IN by content: PlayCanvas's compressed layout is read whole, 3DGS streamed.
    auto r = ply::Reader::open(in);
    return r && gaussian::is_compressed_ply(r->header());
}

int deform_gaussian_file(const std::string& in, const std::string& out,
                         const std::function<Result<LatticeChain>(const GaussianCloud&)>& chain_for,
                         const std::string& backend, int bench, bool ascii) {
    if (bench > 0) return fail("--bench works on a 3DGS PLY deformed into a 3DGS PLY (streamed) only");
    if (backend == "gpu")
        return fail(in +
                    ": Gaussians read whole are deformed on the CPU; --backend gpu streams 3DGS PLY only");
    auto g = gaussian::read_gaussians(in);
    if (!g) return fail(g.message());
    auto chain = chain_for(*g);
    if (!chain) return fail(chain.message());
    std::string names;
    for (const std::string& n : chain->names) names += (names.empty() ? "'" : ", '") + n + "'";
    return deform_gaussian_cloud(std::move(*g), chain->lattices, chain->names,
                                 std::to_string(chain->lattices.size()) + " lattice(s) " + names, out, ascii);
}

int deform_gaussian_cloud(GaussianCloud cloud, const std::vector<Lattice>& lattices,
                          const std::vector<std::string>& names, const std::string& what,
                          const std::string& out, bool ascii) {
    if (!is_gaussian_output(out))
        return fail(out +
                    ": deformed Gaussians are written as .ply (3DGS), .compressed.ply (PlayCanvas), .spz, "
                    ".glb (KHR_gaussian_splatting), .sog or a SOG folder's meta.json");
    const auto t0 = Clock::now();
    std::size_t inverted = 0, not_finite = 0;
    std::vector<std::size_t> inside;
    for (const Lattice& l : lattices) {
        auto stats = gaussian::deform(l, cloud, cloud);
        if (!stats) return fail(what + ": " + stats.message());
        inverted += stats->inverted;
        not_finite += stats->not_finite;
        inside.push_back(stats->inside);
    }
    gaussian::bake_sh_frames(cloud);
    const double ms = ms_since(t0);
    const std::string l = lower(out);
    Status s =
        ends_with(l, ".compressed.ply") ? gaussian::write_compressed_ply(out, cloud)
        : ends_with(l, ".ply")
            ? gaussian::write_ply(out, cloud, ascii ? ply::Format::ascii : ply::Format::binary_little_endian)
        : ends_with(l, ".glb") ? gaussian::write_glb(out, cloud)
        : ends_with(l, ".spz") ? gaussian::write_spz(out, cloud)
                               : gaussian::write_sog(out, cloud);
    if (!s) return fail(s.message());
    std::fprintf(stderr,
                 "%s: %zu Gaussians deformed by %s on the CPU in %.1f ms (%zu inverted, %zu not finite)\n",
                 out.c_str(), cloud.size(), what.c_str(), ms, inverted, not_finite);
    for (std::size_t i = 0; i < inside.size(); ++i)
        warn_if_empty(i < names.size() ? names[i] : what, inside[i], cloud.size());
    return 0;
}

}  // namespace sffd::cli
