// FFD CPU benchmarks on the paper's case: 59,650 splats (Fibonacci sphere, unit radius) in an 11x11x11
// lattice (divisions 10) around it, global twist (every control point rotated about the vertical axis by an
// angle proportional to its height, as ../shared/peers/blender_lattice.py does), plus 1M points.
//   build/<dir>/tools/bench/bench_ffd_deform --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
// BM_Bernstein11_Full/simd:<target> is the paper case once per SIMD target this CPU runs, side by side
// (BM_Bernstein11_Full itself runs on the best one, or on SFFD_SIMD's):
//   bench_ffd_deform --benchmark_filter='BM_Bernstein11_Full'
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/simd/simd.h"
#include "systems/ffd/deform.h"
#include "tools/bench/bench_util.h"
#include "tools/bench/fma_model.h"
#include "tools/bench/paper_case.h"

namespace {

using namespace sffd;

struct Points {
    std::vector<glm::vec3> p, n, u, v;
    std::vector<glm::vec3> op, on, ou, ov;
};

Points sphere(std::size_t count) {
    Points s;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 n = bench::fibonacci_sphere(i, count);
        const glm::dvec3 t =
            glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        s.p.push_back(glm::vec3(n));
        s.n.push_back(glm::vec3(n));
        s.u.push_back(glm::vec3(t * 0.01));
        s.v.push_back(glm::vec3(glm::cross(n, t) * 0.01));
    }
    s.op = s.p, s.on = s.n, s.ou = s.u, s.ov = s.v;
    return s;
}

Lattice twisted(LatticeBasis basis) { return bench::twisted_lattice(basis); }
// The twist leaves its axis's coordinate still (the dense Bernstein kernel then sums two of three): this one
// also moves every control point a little along all three, the cost of an arbitrary edit.
Lattice twisted_and_shifted(LatticeBasis basis) {
    Lattice l = twisted(basis);
    for (std::size_t i = 0; i < l.size(); ++i)
        l.current[i] += 0.01 * glm::dvec3(std::sin(1.7 * double(i)), std::cos(2.3 * double(i)),
                                          std::sin(0.7 * double(i)));
    return l;
}

void run(benchmark::State& state, const Lattice& l, Points& s, bool full, ffd::Backend b) {
    const ffd::PointsIn in{s.p.data(),
                           full ? s.n.data() : nullptr,
                           full ? s.u.data() : nullptr,
                           full ? s.v.data() : nullptr,
                           s.p.size(),
                           {}};
    const ffd::PointsOut out{s.op.data(), s.on.data(), s.ou.data(), s.ov.data()};
    for (auto _ : state) {
        auto r = ffd::deform(l, in, out, b);
        benchmark::DoNotOptimize(r);
        benchmark::ClobberMemory();
    }
    state.counters["points/s"] =
        benchmark::Counter(double(s.p.size()), benchmark::Counter::kIsIterationInvariantRate);
}

Points& paper_points() {
    static Points s = sphere(59650);
    return s;
}
Points& million_points() {
    static Points s = sphere(1000000);
    return s;
}

void BM_Bernstein11_Full(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bernstein), paper_points(), true, ffd::Backend::fast);
}
// The same, pinned to one SIMD target, with its speed as a fraction of that target's FMA floor on this host
// (floor_frac: by wall time against every core's floor; floor_frac_cpu: by CPU time against one core's,
// the steadier figure on a loaded machine).
void bernstein11_full_on(benchmark::State& st, const simd::Target& target) {
    const simd::ScopedTarget pin(target);
    const Lattice l = twisted(LatticeBasis::bernstein);
    Points& s = paper_points();
    (void)bench::fma_floor(target);  // measured before the timed runs
    const double cpu0 = bench::process_cpu_s();
    const auto t0 = std::chrono::steady_clock::now();
    run(st, l, s, true, ffd::Backend::fast);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double per = bench::bernstein_multiply_adds(l, true);
    bench::report_floor_fraction(st, target, per * double(s.p.size()) * double(st.iterations()), wall,
                                 bench::process_cpu_s() - cpu0);
    st.counters["madds_per_point"] = per;
}
void BM_Bernstein11_PositionsOnly(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bernstein), paper_points(), false, ffd::Backend::fast);
}
void BM_Bernstein11_Sparse27_Full(benchmark::State& st) {
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1},
                                  {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10});
    ffd::stretch(l, ffd::select_range(l, {4, 4, 8}, {6, 6, 10}), glm::dvec3(0.0, 0.0, 0.3));
    run(st, l, paper_points(), true, ffd::Backend::automatic);
}
void BM_BSpline11_Full(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bspline), paper_points(), true, ffd::Backend::fast);
}
void BM_BSpline11_PositionsOnly(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bspline), paper_points(), false, ffd::Backend::fast);
}
void BM_Bernstein11_1M_Full(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bernstein), million_points(), true, ffd::Backend::fast);
}
void BM_Bernstein11_1M_EveryCoordinate_Full(benchmark::State& st) {
    run(st, twisted_and_shifted(LatticeBasis::bernstein), million_points(), true, ffd::Backend::fast);
}
void BM_BSpline11_1M_Full(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bspline), million_points(), true, ffd::Backend::fast);
}
void BM_Bernstein11_1M_PositionsOnly(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bernstein), million_points(), false, ffd::Backend::fast);
}
void BM_BSpline11_1M_PositionsOnly(benchmark::State& st) {
    run(st, twisted(LatticeBasis::bspline), million_points(), false, ffd::Backend::fast);
}

BENCHMARK(BM_Bernstein11_Full)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
const int registered_per_target = [] {
    for (const simd::Target& t : simd::runnable())
        benchmark::RegisterBenchmark(("BM_Bernstein11_Full/simd:" + t.name).c_str(), bernstein11_full_on, t)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime()
            ->UseRealTime();
    return 0;
}();
BENCHMARK(BM_Bernstein11_PositionsOnly)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_Bernstein11_Sparse27_Full)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_BSpline11_Full)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_BSpline11_PositionsOnly)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_Bernstein11_1M_Full)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_Bernstein11_1M_PositionsOnly)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_Bernstein11_1M_EveryCoordinate_Full)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_BSpline11_1M_Full)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_BSpline11_1M_PositionsOnly)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
