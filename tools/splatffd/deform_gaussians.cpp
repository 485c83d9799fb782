// deform_gaussian_file: any Gaussian format read whole (read_gaussians), deformed on the CPU, written by
// OUT's name. A 3DGS PLY into a 3DGS PLY is streamed by ffd::stream_deform (systems/ffd/stream_deform.h);
// report_gaussian_stream prints what it did. --bench N there prints one JSON line:
// {"gaussians":..,"sh_degree":..,"backend":..,"median_ms":..,"min_ms":..,"runs":N,"gaussians_per_s":..,
//  "read_ms":..,"total_s":..}  (median/min: deformation only; read_ms: parse + convert of the input).
#include "tools/splatffd/deform_gaussians.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include "runtime/assets/formats/surface/ply.h"
#include "systems/ffd/components.h"
#include "systems/ffd/stream_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "tools/splatffd/convert_gaussians.h"
#include "tools/splatffd/lattice_source.h"

namespace sffd::cli {

namespace {
using Clock = std::chrono::steady_clock;

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

int report_gaussian_stream(const ffd::StreamDeformResult& r, const std::string& lattice_path,
                           const std::string& backend_name, int bench) {
    char compile_note[96] = "";
    if (r.set_up_ms >= 0.0)
        std::snprintf(compile_note, sizeof compile_note,
                      ", GPU program set-up (shader compilation, first dispatch) %.1f ms", r.set_up_ms);
    const std::size_t inside = r.inside.empty() ? 0 : r.inside[0];
    std::fprintf(
        stderr,
        "splatffd deform: %llu Gaussians (SH degree %d, %s), %zu inside, %zu inverted, %zu degenerate, "
        "%zu not finite (written transparent); deformation %.1f ms%s, read+convert %.1f ms, total with I/O "
        "%.2f s\n",
        static_cast<unsigned long long>(r.points), r.sh_degree, backend_name.c_str(), inside, r.inverted,
        r.degenerate, r.not_finite, r.deform_ms, compile_note, r.read_ms, r.total_s);
    warn_if_empty(lattice_path, inside, std::size_t(r.points));
    if (bench > 0) {
        std::vector<double> rep_ms = r.timing_ms;
        std::sort(rep_ms.begin(), rep_ms.end());
        const double median = rep_ms.size() % 2
                                  ? rep_ms[rep_ms.size() / 2]
                                  : 0.5 * (rep_ms[rep_ms.size() / 2 - 1] + rep_ms[rep_ms.size() / 2]);
        std::printf(
            "{\"gaussians\":%llu,\"sh_degree\":%d,\"backend\":\"%s\",\"median_ms\":%.4f,\"min_ms\":%.4f,"
            "\"runs\":%d,"
            "\"gaussians_per_s\":%.4g,\"read_ms\":%.3f,\"total_s\":%.3f}\n",
            static_cast<unsigned long long>(r.points), r.sh_degree, backend_name.c_str(), median,
            rep_ms.front(), bench, median > 0 ? double(r.points) / (median * 1e-3) : 0.0, r.read_ms,
            r.total_s);
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
                          const std::string& out, bool ascii, const float* weights) {
    if (!is_gaussian_output(out))
        return fail(out +
                    ": deformed Gaussians are written as .ply (3DGS), .compressed.ply (PlayCanvas), .spz, "
                    ".glb (KHR_gaussian_splatting), .sog or a SOG folder's meta.json");
    const auto t0 = Clock::now();
    std::size_t inverted = 0, not_finite = 0;
    std::vector<std::size_t> inside;
    gaussian::DeformOptions options;
    options.weights = weights;
    for (const Lattice& l : lattices) {
        auto stats = gaussian::deform(l, cloud, cloud, options);
        if (!stats) return fail(what + ": " + stats.message());
        inverted += stats->inverted;
        not_finite += stats->not_finite;
        inside.push_back(stats->inside);
    }
    gaussian::bake_sh_frames(cloud);
    const double ms = ms_since(t0);
    const std::string l = lower(out);
    Status s = ends_with(l, ".compressed.ply") ? gaussian::write_compressed_ply(out, cloud)
               : ends_with(l, ".ply")
                   ? gaussian::write_ply(
                         out, cloud, ascii ? ply::Format::ascii : ply::Format::binary_little_endian,
                         weights ? std::span<const float>(weights, cloud.size()) : std::span<const float>())
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
