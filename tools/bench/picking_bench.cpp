// Picking benchmarks: ray-pick latency and the Embree refresh after a deformation, on a sphere of 59,650
// splats (the built-in `sphere` scene's size) inside a 5x5x5 Bernstein lattice.
//
//   build/<dir>/tools/bench/bench_picking --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// BM_RefreshAfterDeformation: the cloud's splats alternate between rest and a stretched copy (swapped in,
// so no deformation math is timed) and refresh() rebuilds: buffer fill (world transform, ellipse axes),
// rtcUpdateGeometryBuffer, rtcCommitGeometry, one rtcCommitScene (BVH build). BM_RefreshNewGeometry
// times the same with a geometry created from scratch (entity replaced). BM_Pick* time one full pick on
// an up-to-date scene.
#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <numbers>
#include <random>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/picking_system.h"

namespace {

using namespace sffd;
using namespace sffd::picking;

constexpr std::size_t kSplats = 59650;

// CPU seconds of the whole process (every Embree/TBB worker thread): on a loaded machine this is steadier
// than wall time and says how much work a refresh is, whatever the core count.
double process_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Fibonacci sphere of radius 1: near-uniform splats, radius chosen so neighbours overlap.
SplatCloud fibonacci_sphere(std::size_t n) {
    SplatCloud c;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const float r = float(1.2 * std::sqrt(4.0 / double(n)));
    for (std::size_t i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
        const double rad = std::sqrt(1.0 - y * y);
        const double phi = golden * double(i);
        const glm::vec3 p(float(std::cos(phi) * rad), float(y), float(std::sin(phi) * rad));
        const glm::vec3 t = glm::normalize(glm::cross(std::abs(p.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0), p));
        c.positions.push_back(p);
        c.normals.push_back(p);
        c.axis_u.push_back(r * t);
        c.axis_v.push_back(r * glm::cross(p, t));
        c.colors.push_back(0xffffffffu);
    }
    return c;
}

Lattice box_lattice(int d) {
    Lattice l;
    l.origin = glm::dvec3(-1.1);
    l.axes = {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)};
    l.divisions = glm::ivec3(d);
    for (int i = 0; i <= d; ++i)
        for (int j = 0; j <= d; ++j)
            for (int k = 0; k <= d; ++k)
                l.rest.push_back(l.origin + glm::dvec3(i, j, k) * (2.2 / d));
    l.current = l.rest;
    return l;
}

struct Scene {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
    std::vector<glm::vec3> stretched_positions, stretched_u, stretched_v;
    Camera camera;
    ScreenView view;

    Scene() {
        cloud = reg.create();
        SplatCloud c = fibonacci_sphere(kSplats);
        // A stand-in deformation: stretch along y by 1.5 (axes stretch with it).
        for (std::size_t i = 0; i < c.size(); ++i) {
            stretched_positions.push_back(c.positions[i] * glm::vec3(1, 1.5f, 1));
            stretched_u.push_back(c.axis_u[i] * glm::vec3(1, 1.5f, 1));
            stretched_v.push_back(c.axis_v[i] * glm::vec3(1, 1.5f, 1));
        }
        reg.emplace<SplatCloud>(cloud, std::move(c));
        lattice = reg.create();
        reg.emplace<Lattice>(lattice, box_lattice(4));
        camera.eye = {0.0, 0.0, 4.0};
        camera.fov_y_degrees = 45.0f;
        view = make_screen_view(camera, {1280, 720});
    }
    void swap_deformation() {
        SplatCloud& c = reg.patch<SplatCloud>(cloud);
        std::swap(c.positions, stretched_positions);
        std::swap(c.axis_u, stretched_u);
        std::swap(c.axis_v, stretched_v);
    }
};

void BM_RefreshAfterDeformation(benchmark::State& st) {
    Scene s;
    PickingState state;
    state.refresh(s.reg);
    double cpu = 0.0;
    for (auto _ : st) {
        st.PauseTiming();
        s.swap_deformation();
        st.ResumeTiming();
        const double t0 = process_cpu_seconds();
        benchmark::DoNotOptimize(state.refresh(s.reg));
        cpu += process_cpu_seconds() - t0;
    }
    st.counters["process_cpu_ms"] = 1e3 * cpu / double(st.iterations());
    st.counters["splats"] = double(kSplats);
    st.counters["commits"] = double(state.stats().surface_commits);
}
BENCHMARK(BM_RefreshAfterDeformation)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RefreshNewGeometry(benchmark::State& st) {
    Scene s;
    PickingState state;
    state.refresh(s.reg);
    double cpu = 0.0;
    for (auto _ : st) {
        st.PauseTiming();
        SplatCloud copy = s.reg.get<SplatCloud>(s.cloud);
        s.reg.destroy(s.cloud);
        s.cloud = s.reg.create();
        s.reg.emplace<SplatCloud>(s.cloud, std::move(copy));
        st.ResumeTiming();
        const double t0 = process_cpu_seconds();
        benchmark::DoNotOptimize(state.refresh(s.reg));
        cpu += process_cpu_seconds() - t0;
    }
    st.counters["process_cpu_ms"] = 1e3 * cpu / double(st.iterations());
}
BENCHMARK(BM_RefreshNewGeometry)->Unit(benchmark::kMillisecond)->UseRealTime();

// Nothing changed: the O(1) stamp check.
void BM_RefreshUnchanged(benchmark::State& st) {
    Scene s;
    PickingState state;
    state.refresh(s.reg);
    for (auto _ : st) benchmark::DoNotOptimize(state.refresh(s.reg));
}
BENCHMARK(BM_RefreshUnchanged);

// A full screen pick (control-point tolerance pass over 125 points + surface ray + control ray) at
// random pixels of a 1280x720 view; about half the pixels hit the sphere.
void BM_PickScreen(benchmark::State& st) {
    Scene s;
    PickingState state;
    state.refresh(s.reg);
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> x(0.0, 1280.0), y(0.0, 720.0);
    std::size_t hits = 0;
    for (auto _ : st) {
        const PickHit h = pick(s.reg, state, query_at_pixel(s.view, {x(rng), y(rng)}));
        hits += h ? 1 : 0;
        benchmark::DoNotOptimize(h);
    }
    st.counters["hit_rate"] = double(hits) / double(st.iterations());
}
BENCHMARK(BM_PickScreen)->Unit(benchmark::kMicrosecond);

// An explicit ray at the sphere (always a surface hit): Embree traversal + ellipse filter only.
void BM_PickRay(benchmark::State& st) {
    Scene s;
    PickingState state;
    state.refresh(s.reg);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-0.6, 0.6);
    for (auto _ : st) {
        PickQuery q = query_from_ray({{u(rng), u(rng), 4.0}, {0.0, 0.0, -1.0}});
        q.control_points = false;
        benchmark::DoNotOptimize(pick(s.reg, state, q));
    }
}
BENCHMARK(BM_PickRay)->Unit(benchmark::kMicrosecond);

}  // namespace
