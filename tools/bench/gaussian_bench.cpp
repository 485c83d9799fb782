// 3D Gaussian benchmarks (issue 17): CPU deformation of 1M synthetic Gaussians (flat Gaussians tangent to
// a unit Fibonacci sphere, random SH) through the twisted 11³ lattice of the paper case, per SH degree;
// the lattice evaluation alone (positions + Jacobians) for comparison; 3DGS PLY import of 1M Gaussians
// (degree 3, binary little endian, written once to the temp folder) with bytes per Gaussian.
//   build/release/tools/bench/bench_gaussian --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/quaternion.hpp>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_io.h"
#include "tools/bench/paper_case.h"

namespace {

using namespace sffd;

GaussianCloud sphere_gaussians(std::size_t count, int degree) {
    GaussianCloud g;
    g.sh_degree = degree;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 n = bench::fibonacci_sphere(i, count);
        g.positions.push_back(glm::vec3(n));
        g.scales.emplace_back(0.01f, 0.01f, 0.001f);  // flat along the local z = the normal
        g.rotations.push_back(glm::quat(glm::rotation(glm::dvec3(0, 0, 1), n)));
        g.opacities.push_back(0.8f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

// CPU time of the whole process (all TBB threads): the work done, meaningful on a loaded machine where
// wall time mostly measures the other processes.
double process_cpu_s() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

Lattice twisted() {
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6 / 1.1, glm::dvec3(0.0));
    return l;
}

void BM_GaussianDeform(benchmark::State& state) {
    const GaussianCloud g = sphere_gaussians(std::size_t(state.range(0)), int(state.range(1)));
    const Lattice l = twisted();
    GaussianCloud out;
    gaussian::DeformOptions options;
    options.sh = state.range(2) ? gaussian::ShMode::rotate_view : gaussian::ShMode::rotate_coefficients;
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        auto s = gaussian::deform(l, g, out, options);
        if (!s) state.SkipWithError(s.message().c_str());
        benchmark::DoNotOptimize(out.positions.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
}
// Args: Gaussians, SH degree, SH mode (0 rotate the coefficients, 1 store the per-splat view rotation).
BENCHMARK(BM_GaussianDeform)->Args({1000000, 0, 0})->Args({1000000, 3, 0})->Args({1000000, 3, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

// What the lattice evaluation alone costs (positions + full Jacobians, the ffd fast path).
void BM_FfdPositionsAndJacobians(benchmark::State& state) {
    const GaussianCloud g = sphere_gaussians(std::size_t(state.range(0)), 0);
    const Lattice l = twisted();
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
           g.rotations.capacity() * sizeof(glm::quat) + g.opacities.capacity() * sizeof(float) + g.sh.capacity() * sizeof(float);
}

void BM_GaussianReadPly(benchmark::State& state) {
    const std::size_t n = std::size_t(state.range(0));
    const auto path = std::filesystem::temp_directory_path() / ("sffd_bench_gaussians_" + std::to_string(getpid()) + ".ply");
    if (auto s = gaussian::write_ply(path, sphere_gaussians(n, 3)); !s) {
        state.SkipWithError(s.message().c_str());
        return;
    }
    std::size_t bytes = 0;
    for (auto _ : state) {
        auto g = gaussian::read_ply(path);
        if (!g) state.SkipWithError(g.message().c_str());
        else bytes = cloud_bytes(*g);
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(n));
    state.counters["cloud_bytes_per_gaussian"] = double(bytes) / double(n);
    state.counters["file_bytes_per_gaussian"] = double(std::filesystem::file_size(path)) / double(n);
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    state.counters["process_peak_rss_mb"] = double(ru.ru_maxrss) / 1024.0;
    std::filesystem::remove(path);
}
BENCHMARK(BM_GaussianReadPly)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
