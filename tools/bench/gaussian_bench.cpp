// 3D Gaussian benchmarks: CPU deformation of 1M synthetic Gaussians (flat Gaussians tangent to
// a unit Fibonacci sphere, random SH) through the twisted 11³ lattice of the paper case, per SH degree;
// the lattice evaluation alone (positions + Jacobians) for comparison; 3DGS PLY import of 1M Gaussians
// (degree 3, binary little endian, written once to the temp folder) with bytes per Gaussian.
// Import (BM_GaussianImport): 1M Gaussians from 3DGS PLY degree 3 and 0, .splat, SPZ v3, KHR glb. Run one
// benchmark per process for a clean peak-RSS counter, e.g.
//   build/release/tools/bench/bench_gaussian --benchmark_filter='Import/1000000/3$'
// Deformation at 1M and 6M (Args: Gaussians, SH degree, SH mode), one iteration per run:
//   build/release/tools/bench/bench_gaussian --benchmark_filter='Deform/6000000/3/1'
//   --benchmark_repetitions=3 build/release/tools/bench/bench_gaussian --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <malloc.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "tools/bench/gaussian_case.h"

namespace {

using namespace sffd;

using bench::process_cpu_s;
using bench::sphere_gaussians;

void BM_GaussianDeform(benchmark::State& state) {
    const GaussianCloud g = sphere_gaussians(std::size_t(state.range(0)), int(state.range(1)));
    bench::run_cpu_deform(
        state, g, state.range(2) ? gaussian::ShMode::rotate_view : gaussian::ShMode::rotate_coefficients);
}
// Args: Gaussians, SH degree, SH mode (0 rotate the coefficients, 1 store the per-splat view rotation).
BENCHMARK(BM_GaussianDeform)
    ->ArgsProduct({{1000000, 6000000}, {0, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// What the lattice evaluation alone costs (positions + full Jacobians, the ffd fast path).
void BM_FfdPositionsAndJacobians(benchmark::State& state) {
    const GaussianCloud g = sphere_gaussians(std::size_t(state.range(0)), 0);
    const Lattice l = bench::twisted_gaussian_lattice();
    std::vector<glm::vec3> pos(g.size());
    std::vector<glm::mat3> jac(g.size());
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        ffd::PointsOut out{pos.data(), nullptr, nullptr, nullptr};
        out.jacobians = jac.data();
        auto s = ffd::deform(l, {g.positions.data(), nullptr, nullptr, nullptr, g.size(), g.origin}, out);
        if (!s) state.SkipWithError(s.message().c_str());
        benchmark::DoNotOptimize(jac.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
}
BENCHMARK(BM_FfdPositionsAndJacobians)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

std::size_t cloud_bytes(const GaussianCloud& g) {
    return g.positions.capacity() * sizeof(glm::vec3) + g.scales.capacity() * sizeof(glm::vec3) +
           g.rotations.capacity() * sizeof(glm::quat) + g.opacities.capacity() * sizeof(float) +
           g.sh.capacity() * sizeof(float) + g.sh_frames.capacity() * sizeof(glm::mat3);
}

// /proc/self/status field in kB (VmRSS, VmHWM), -1 when unreadable.
double proc_status_kb(const char* field) {
    std::FILE* f = std::fopen("/proc/self/status", "r");
    if (!f) return -1.0;
    char line[256];
    double kb = -1.0;
    const std::size_t len = std::strlen(field);
    while (std::fgets(line, sizeof line, f))
        if (std::strncmp(line, field, len) == 0 && line[len] == ':') kb = std::atof(line + len + 1);
    std::fclose(f);
    return kb;
}

// Resets VmHWM to the current RSS (Linux >= 4.0: "5" > /proc/self/clear_refs); false when not allowed.
bool reset_peak_rss() {
    std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
    if (!f) return false;
    const bool ok = std::fputs("5", f) >= 0;
    return std::fclose(f) == 0 && ok;
}

void put_u32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}

// .splat (antimatter15): pos 3 f32, scale 3 f32 (linear), RGBA u8, rotation 4 u8 (w x y z, (b-128)/128).
bool write_splat_file(const std::filesystem::path& path, const GaussianCloud& g) {
    std::string b;
    b.reserve(g.size() * 32);
    auto f32 = [&](float v) {
        char c[4];
        std::memcpy(c, &v, 4);
        b.append(c, 4);
    };
    auto u8 = [](float v) { return char(std::lround(std::clamp(v, 0.0f, 255.0f))); };
    for (std::size_t i = 0; i < g.size(); ++i) {
        for (int a = 0; a < 3; ++a) f32(g.positions[i][a]);
        for (int a = 0; a < 3; ++a) f32(g.scales[i][a]);
        for (int c = 0; c < 3; ++c)
            b += u8(255.0f * (0.5f + 0.28209479f *
                                         g.sh[i * std::size_t(sh_coeffs(g.sh_degree)) * 3 + std::size_t(c)]));
        b += u8(255.0f * g.opacities[i]);
        const glm::quat q = g.rotations[i];
        for (float v : {q.w, q.x, q.y, q.z}) b += u8(128.0f + 128.0f * v);
    }
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    const bool ok = std::fwrite(b.data(), 1, b.size(), f) == b.size();
    return std::fclose(f) == 0 && ok;
}

// SPZ v3 (one gzip stream, Niantic's layout): 24-bit fixed-point positions (12 fractional bits), u8 alpha,
// u8 colour (0.15 scale), u8 log scale (s/16 − 10), smallest-three rotations (w kept largest), u8 SH.
bool write_spz_file(const std::filesystem::path& path, const GaussianCloud& g) {
    const std::size_t n = g.size();
    const int K = sh_coeffs(g.sh_degree);
    std::string b;
    put_u32(b, 0x5053474e), put_u32(b, 3), put_u32(b, std::uint32_t(n));
    b += char(g.sh_degree), b += char(12), b += char(0), b += char(0);
    auto u8 = [](double v) { return char(std::lround(std::clamp(v, 0.0, 255.0))); };
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const int v = int(std::lround(double(g.positions[i][a]) * 4096.0));
            b += char(v & 0xff), b += char((v >> 8) & 0xff), b += char((v >> 16) & 0xff);
        }
    for (std::size_t i = 0; i < n; ++i) b += u8(255.0 * double(g.opacities[i]));
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            b += u8(255.0 * (0.5 + 0.15 * double(g.sh[i * std::size_t(K) * 3 + std::size_t(c)])));
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) b += u8((std::log(double(g.scales[i][a])) + 10.0) * 16.0);
    for (std::size_t i = 0; i < n; ++i) {
        glm::quat q = g.rotations[i];
        if (q.w < 0) q = -q;
        std::uint32_t bits = 3u << 30;  // w is the dropped (largest) component in these flat-disc rotations
        const float rest[3] = {q.x, q.y, q.z};
        for (int j = 0; j < 3; ++j) {
            const std::uint32_t mag =
                std::uint32_t(std::lround(std::min(1.0f, std::abs(rest[j]) * std::sqrt(2.0f)) * 511.0f));
            bits |= ((rest[j] < 0 ? 512u : 0u) | mag) << (10 * (2 - j));
        }
        put_u32(b, bits);
    }
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 1; k < K; ++k)
            for (int c = 0; c < 3; ++c)
                b += u8(128.0 +
                        128.0 * double(g.sh[(i * std::size_t(K) + std::size_t(k)) * 3 + std::size_t(c)]));
    gzFile f = gzopen(path.c_str(), "wb1");
    if (!f) return false;
    const bool ok = gzwrite(f, b.data(), unsigned(b.size())) == int(b.size());
    return gzclose(f) == Z_OK && ok;
}

// Import of 1M Gaussians per format (state.range(1)): 0 3DGS PLY degree 3, 1 3DGS PLY degree 0, 2 .splat,
// 3 SPZ v3 degree 3, 4 glTF KHR_gaussian_splatting .glb degree 3. The file is written once, the source
// cloud freed, then each read goes through read_gaussians() (the by-extension entry point). Counters:
// cloud_bytes_per_gaussian (the GaussianCloud's arrays), file_bytes_per_gaussian, and
// import_peak_bytes_per_gaussian: the peak RSS during the reads above the RSS before them (VmHWM reset
// through /proc/self/clear_refs), i.e. the result plus the reader's transient buffers.
void BM_GaussianImport(benchmark::State& state) {
    const std::size_t n = std::size_t(state.range(0));
    const int format = int(state.range(1));
    static const char* const names[] = {"ply_deg3", "ply_deg0", "splat", "spz_deg3", "glb_deg3"};
    static const char* const exts[] = {".ply", ".ply", ".splat", ".spz", ".glb"};
    state.SetLabel(names[format]);
    const auto path = std::filesystem::temp_directory_path() /
                      ("sffd_bench_import_" + std::to_string(getpid()) + exts[format]);
    {
        const GaussianCloud g = sphere_gaussians(n, format == 1 || format == 2 ? 0 : 3);
        bool ok = true;
        std::string why;
        if (format <= 1) {
            if (auto s = gaussian::write_ply(path, g); !s) ok = false, why = s.message();
        } else if (format == 2) {
            ok = write_splat_file(path, g);
        } else if (format == 3) {
            ok = write_spz_file(path, g);
        } else if (auto s = gaussian::write_glb(path, g); !s) {
            ok = false, why = s.message();
        }
        if (!ok) {
            state.SkipWithError(("cannot write " + path.string() + " " + why).c_str());
            return;
        }
    }
    malloc_trim(0);
    const double rss0_kb = proc_status_kb("VmRSS");
    const bool peak_ok = reset_peak_rss();
    std::size_t bytes = 0;
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        auto g = gaussian::read_gaussians(path);
        if (!g) {
            state.SkipWithError(g.message().c_str());
            break;
        }
        if (g->size() != n) state.SkipWithError("wrong count");
        bytes = cloud_bytes(*g);
    }
    const double hwm_kb = proc_status_kb("VmHWM");
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(n));
    state.counters["process_cpu_ms_per_read"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
    state.counters["cloud_bytes_per_gaussian"] = double(bytes) / double(n);
    state.counters["file_bytes_per_gaussian"] = double(std::filesystem::file_size(path)) / double(n);
    if (peak_ok && rss0_kb > 0 && hwm_kb > 0)
        state.counters["import_peak_bytes_per_gaussian"] = (hwm_kb - rss0_kb) * 1024.0 / double(n);
    std::filesystem::remove(path);
}
BENCHMARK(BM_GaussianImport)
    ->ArgsProduct({{1000000}, {0, 1, 2, 3, 4}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

// Export of 1M Gaussians of SH degree 3 per format (state.range(1)): 0 3DGS PLY, 1 glTF
// KHR_gaussian_splatting .glb, 2 SPZ v3, 3 PlayCanvas compressed PLY; each write is the command's (a
// temporary file renamed). Counter: MB_per_s of the file written.
//   build/release/tools/bench/bench_gaussian --benchmark_filter='Export'
void BM_GaussianExport(benchmark::State& state) {
    const std::size_t n = std::size_t(state.range(0));
    const int format = int(state.range(1));
    static const char* const names[] = {"ply_deg3", "glb_deg3", "spz_deg3", "compressed_ply_deg3"};
    static const char* const exts[] = {".ply", ".glb", ".spz", ".compressed.ply"};
    state.SetLabel(names[format]);
    const auto path = std::filesystem::temp_directory_path() /
                      ("sffd_bench_export_" + std::to_string(getpid()) + exts[format]);
    const GaussianCloud g = sphere_gaussians(n, 3);
    for (auto _ : state) {
        const Status s = format == 0   ? gaussian::write_ply(path, g)
                         : format == 1 ? gaussian::write_glb(path, g)
                         : format == 2 ? gaussian::write_spz(path, g)
                                       : gaussian::write_compressed_ply(path, g);
        if (!s) {
            state.SkipWithError(s.message().c_str());
            break;
        }
    }
    const double mb = double(std::filesystem::file_size(path)) / 1e6;
    state.counters["MB_per_s"] =
        benchmark::Counter(mb * double(state.iterations()), benchmark::Counter::kIsRate);
    std::filesystem::remove(path);
}
BENCHMARK(BM_GaussianExport)
    ->ArgsProduct({{1000000}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace
