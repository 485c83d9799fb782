// Page-bounded re-deformation (systems/ffd/deform_staleness.h): one control point dragged on a 1M-point
// cloud (the Fibonacci sphere, whose order makes its pages latitude bands, as `profile synthetic:1m`
// makes it), through ffd_system's CPU path, one drag step per iteration. Counters: pages redone per step,
// the cloud's pages, and their ratio. BM_Drag_Full is the same drag with the page record dropped before
// each step, i.e. what every drag step cost before (every page). BM_GaussianDrag_* are the same for 1M
// Gaussians.
//   build/<dir>/tools/bench/bench_page_redeform --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
// Arguments: divisions per axis, the dragged control point's index along y (x and z at the middle), the
// points' order: 0 as generated (latitude bands), 1 Morton order (runtime/scene/point_order.h, what
// `splatffd convert --order morton` writes), whose pages are compact blocks.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "runtime/scene/point_order.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "tools/bench/paper_case.h"

namespace {

using namespace sffd;

SplatCloud sphere(std::size_t count) {
    SplatCloud s;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 n = bench::fibonacci_sphere(i, count);
        const glm::dvec3 t =
            glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        s.positions.push_back(glm::vec3(n));
        s.normals.push_back(glm::vec3(n));
        s.axis_u.push_back(glm::vec3(t * 0.003));
        s.axis_v.push_back(glm::vec3(glm::cross(n, t) * 0.003));
    }
    return s;
}

// The 1M sphere in the order asked for by the benchmark's third argument.
const SplatCloud& sphere_in_order(bool morton) {
    static const SplatCloud bands = sphere(1000000);
    static const SplatCloud zorder = [] {
        SplatCloud s = bands;
        if (!permute(s, morton_order(s.positions))) std::abort();
        return s;
    }();
    return morton ? zorder : bands;
}

// Share of the lattice's volume the dragged point's support (l·t in [i-2, i+2] per axis, clipped to the
// box) covers.
double support_volume(int div, int j) {
    const auto share = [&](int i) { return (std::min(div, i + 2) - std::max(0, i - 2)) / double(div); };
    return share(div / 2) * share(j) * share(div / 2);
}

void drag(benchmark::State& state, bool full) {
    const int div = int(state.range(0)), j = int(state.range(1));
    const SplatCloud& cloud = sphere_in_order(state.range(2) != 0);
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_cpu = true;
    const ecs::Entity c = reg.create(), le = reg.create();
    reg.emplace<SplatCloud>(c, cloud);
    reg.emplace<Lattice>(
        le,
        make_lattice(glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                     glm::ivec3(div), LatticeBasis::bspline));
    reg.emplace<Deformers>(c, Deformers{{le}});
    ffd_system(reg, {});  // the first, whole deformation
    const std::size_t cp = reg.get<Lattice>(le).index(div / 2, j, div / 2);
    double step = 0.0, redone = 0.0, total = 0.0;
    std::uint64_t steps = 0;
    for (auto _ : state) {
        if (full) {
            state.PauseTiming();
            reg.get<DeformedSplats>(c).paged = {};
            state.ResumeTiming();
        }
        step += 1.0;
        Lattice& l = reg.patch<Lattice>(le);
        l.current[cp] = l.rest[cp] + glm::dvec3(0.02 * std::sin(step), 0.03 * std::cos(step), 0.01);
        ffd_system(reg, {});
        redone += double(reg.resource<FfdStats>().last_pages.redone);
        total = double(reg.resource<FfdStats>().last_pages.total);
        ++steps;
    }
    state.counters["pages_redone"] = redone / double(steps);
    state.counters["pages_total"] = total;
    state.counters["fraction"] = redone / double(steps) / total;
    // Share of the lattice's height the point's support (l·t in [j-2, j+2], clipped to the box) covers.
    state.counters["support_height"] = (std::min(div, j + 2) - std::max(0, j - 2)) / double(div);
    state.counters["support_volume"] = support_volume(div, j);
}

// The same drag on 1M Gaussians (SH degree 0) on the sphere, in the same order, through
// gaussian_deform_system's CPU path.
void drag_gaussians(benchmark::State& state, bool full) {
    const int div = int(state.range(0)), j = int(state.range(1));
    static const auto gaussians = [](const SplatCloud& s) {
        GaussianCloud g;
        g.positions = s.positions;
        g.scales.assign(s.size(), glm::vec3(0.003f, 0.003f, 0.0005f));
        g.rotations.assign(s.size(), glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
        g.opacities.assign(s.size(), 0.8f);
        g.sh.assign(s.size() * 3, 0.2f);
        return g;
    };
    static const GaussianCloud bands = gaussians(sphere_in_order(false));
    static const GaussianCloud zorder = [] {
        GaussianCloud g = bands;
        if (!permute(g, morton_order(g.positions))) std::abort();
        return g;
    }();
    const GaussianCloud& cloud = state.range(2) != 0 ? zorder : bands;
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_cpu = true;
    const ecs::Entity c = reg.create(), le = reg.create();
    reg.emplace<GaussianCloud>(c, cloud);
    reg.emplace<Lattice>(
        le,
        make_lattice(glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                     glm::ivec3(div), LatticeBasis::bspline));
    reg.emplace<Deformers>(c, Deformers{{le}});
    gaussian_deform_system(reg, {});
    const std::size_t cp = reg.get<Lattice>(le).index(div / 2, j, div / 2);
    double step = 0.0, redone = 0.0, total = 0.0;
    std::uint64_t steps = 0;
    for (auto _ : state) {
        if (full) {
            state.PauseTiming();
            reg.get<DeformedGaussians>(c).paged = {};
            state.ResumeTiming();
        }
        step += 1.0;
        Lattice& l = reg.patch<Lattice>(le);
        l.current[cp] = l.rest[cp] + glm::dvec3(0.02 * std::sin(step), 0.03 * std::cos(step), 0.01);
        gaussian_deform_system(reg, {});
        redone += double(reg.resource<GaussianDeformStats>().last_pages.redone);
        total = double(reg.resource<GaussianDeformStats>().last_pages.total);
        ++steps;
    }
    state.counters["pages_redone"] = redone / double(steps);
    state.counters["pages_total"] = total;
    state.counters["fraction"] = redone / double(steps) / total;
    state.counters["support_volume"] = support_volume(div, j);
}

void BM_Drag_Pages(benchmark::State& state) { drag(state, false); }
void BM_GaussianDrag_Pages(benchmark::State& state) { drag_gaussians(state, false); }
void BM_GaussianDrag_Full(benchmark::State& state) { drag_gaussians(state, true); }
void BM_Drag_Full(benchmark::State& state) { drag(state, true); }

// 21^3 lattice: points 2 (support below y = -0.66, 1/5 of the height) and 10 (the middle); 11^3: points
// 1 and 5 (the middle, 2/5 of the height). Each in band order (0) and Morton order (1).
BENCHMARK(BM_Drag_Pages)
    ->Args({20, 2, 0})
    ->Args({20, 10, 0})
    ->Args({10, 1, 0})
    ->Args({10, 5, 0})
    ->Args({20, 2, 1})
    ->Args({20, 10, 1})
    ->Args({10, 1, 1})
    ->Args({10, 5, 1})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Drag_Full)->Args({20, 2, 0})->Args({10, 5, 0})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GaussianDrag_Pages)
    ->Args({20, 2, 0})
    ->Args({20, 10, 0})
    ->Args({20, 2, 1})
    ->Args({20, 10, 1})
    ->Args({10, 1, 1})
    ->Args({10, 5, 1})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GaussianDrag_Full)->Args({20, 2, 0})->Unit(benchmark::kMillisecond);

}  // namespace
