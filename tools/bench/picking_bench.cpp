// Picking benchmarks: ray-pick latency and the Embree refresh after a deformation, on the built-in
// `sphere` scene (59,650 splats, 11x11x11 Bernstein lattice).
//
//   build/<dir>/tools/bench/bench_picking --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// BM_RefreshAfterDeformation: the cloud's deformed splats alternate between rest and a stretched copy
// (swapped in, so no deformation math is timed) and refresh() rebuilds: buffer fill (world transform, ellipse
// axes), rtcUpdateGeometryBuffer, rtcCommitGeometry, one rtcCommitScene (BVH build). BM_RefreshNewGeometry
// times the same with a geometry created from scratch (entity replaced). BM_PickScreen / BM_PickRay time
// one pick on an up-to-date scene; BM_PickAfterLatticeEdit the first pick after a lattice edit when the
// deformed splats are GPU-only (picking's own CPU deformation + refresh + pick). BM_GaussianRefresh /
// BM_GaussianPickRay: the same for N flat 3D Gaussians on the unit sphere (59,650 and 1M).
#include <benchmark/benchmark.h>

#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/quaternion.hpp>

#include <cmath>
#include <ctime>
#include <numbers>
#include <random>

#include <stdexcept>

#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/picking_system.h"
#include "systems/splat_render/camera_math.h"

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

// The built-in `sphere` scene (59,650 splats, 11x11x11 Bernstein lattice, its camera) at 1280x720. The
// deformed output is given as DeformedSplats (as ffd_system's CPU path writes it) alternating between
// the rest splats and a copy stretched by 1.5 along y, so refresh timings contain no deformation math.
struct Scene {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
    DeformedSplats rest, stretched;
    ScreenView view;

    Scene() {
        reg.set_resource<SceneHooks>();  // assets' own formats only
        const Status st = load_scene(reg, "sphere");
        if (!st) throw std::runtime_error(st.message());
        reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud&) { cloud = e; });
        reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice&) { lattice = e; });
        const SplatCloud& c = reg.get<SplatCloud>(cloud);
        if (c.size() != kSplats) throw std::runtime_error("sphere scene: unexpected splat count");
        rest.origin = c.origin;
        rest.positions = c.positions;
        rest.normals = c.normals;
        rest.axis_u = c.axis_u;
        rest.axis_v = c.axis_v;
        rest.cpu_valid = true;
        stretched = rest;
        for (auto* v : {&stretched.positions, &stretched.axis_u, &stretched.axis_v})
            for (glm::vec3& p : *v) p.y *= 1.5f;
        reg.emplace<DeformedSplats>(cloud, rest);
        view = make_screen_view(render::scene_camera(reg, 1280.0 / 720.0), {1280, 720});
    }
    void swap_deformation() {
        DeformedSplats& d = reg.patch<DeformedSplats>(cloud);
        std::swap(d.positions, stretched.positions);
        std::swap(d.axis_u, stretched.axis_u);
        std::swap(d.axis_v, stretched.axis_v);
        ++d.version;
    }
};

// Times PickingState::refresh after `change` (untimed) altered the scene, starting from a refreshed
// state; the process CPU time per refresh becomes the counter process_cpu_ms.
template <class Change>
void time_refresh(benchmark::State& st, Scene& s, PickingState& state, Change&& change) {
    state.refresh(s.reg);
    double cpu = 0.0;
    for (auto _ : st) {
        st.PauseTiming();
        change();
        st.ResumeTiming();
        const double t0 = process_cpu_seconds();
        benchmark::DoNotOptimize(state.refresh(s.reg));
        cpu += process_cpu_seconds() - t0;
    }
    st.counters["process_cpu_ms"] = 1e3 * cpu / double(st.iterations());
}

void BM_RefreshAfterDeformation(benchmark::State& st) {
    Scene s;
    PickingState state;
    time_refresh(st, s, state, [&] { s.swap_deformation(); });
    st.counters["splats"] = double(kSplats);
    st.counters["commits"] = double(state.stats().surface_commits);
}
BENCHMARK(BM_RefreshAfterDeformation)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RefreshNewGeometry(benchmark::State& st) {
    Scene s;
    PickingState state;
    time_refresh(st, s, state, [&] {
        SplatCloud copy = s.reg.get<SplatCloud>(s.cloud);
        DeformedSplats out = s.reg.get<DeformedSplats>(s.cloud);
        s.reg.destroy(s.cloud);
        s.cloud = s.reg.create();
        s.reg.emplace<SplatCloud>(s.cloud, std::move(copy));
        s.reg.emplace<DeformedSplats>(s.cloud, std::move(out));
    });
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

// A full screen pick (control-point tolerance pass over 1,331 points + surface ray + control ray) at
// random pixels of the scene camera's 1280x720 view.
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
        PickQuery q = query_from_ray({{u(rng), u(rng), 4.0}, {0.0, 0.0, -1.0}});  // the sphere has radius 1
        q.control_points = false;
        benchmark::DoNotOptimize(pick(s.reg, state, q));
    }
}
BENCHMARK(BM_PickRay)->Unit(benchmark::kMicrosecond);

// The editor's case: the deformed output lives on the GPU only (no CPU DeformedSplats), a control point
// moved, then one click. Picking deforms the 59,650 splats on the CPU (ffd::deform, automatic backend),
// refreshes the scene and casts: the latency of the first pick after an edit.
void BM_PickAfterLatticeEdit(benchmark::State& st) {
    Scene s;
    s.reg.remove<DeformedSplats>(s.cloud);
    PickingState state;
    state.refresh(s.reg);
    const PickQuery q = query_at_pixel(s.view, {640.0, 360.0});
    double sign = 1.0;
    double cpu = 0.0;
    for (auto _ : st) {
        st.PauseTiming();
        Lattice& l = s.reg.patch<Lattice>(s.lattice);
        l.current[l.index(5, 10, 5)].y += 0.2 * sign;
        sign = -sign;
        st.ResumeTiming();
        const double t0 = process_cpu_seconds();
        benchmark::DoNotOptimize(pick(s.reg, state, q));
        cpu += process_cpu_seconds() - t0;
    }
    st.counters["process_cpu_ms"] = 1e3 * cpu / double(st.iterations());
    st.counters["cpu_deformations"] = double(state.stats().cpu_deformations);
}
BENCHMARK(BM_PickAfterLatticeEdit)->Unit(benchmark::kMillisecond)->UseRealTime();

// 3D Gaussians: N flat Gaussians tangent to the unit sphere (Fibonacci points, in-plane σ 0.7 of
// the mean spacing, 0.1 of that along the normal, opacity 0.95: what `convert --gaussians` makes of a
// surface), picked as Embree user-geometry ellipsoids. Refresh: the cloud alternates between rest and a
// copy stretched 1.5x along y (swapped in, no deformation maths timed); ellipsoid setup + BVH build.
struct GaussianScene {
    ecs::Registry reg;
    ecs::Entity cloud;
    std::vector<glm::vec3> other;
    explicit GaussianScene(std::size_t n) {
        GaussianCloud g;
        const double spacing = std::sqrt(4.0 * std::numbers::pi / double(n));
        const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
        for (std::size_t i = 0; i < n; ++i) {
            const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(n), r = std::sqrt(1.0 - z * z);
            const glm::dvec3 p(r * std::cos(golden * double(i)), r * std::sin(golden * double(i)), z);
            g.positions.emplace_back(p);
            g.scales.emplace_back(0.7 * spacing, 0.7 * spacing, 0.07 * spacing);
            g.rotations.push_back(glm::quat(glm::rotation(glm::vec3(0, 0, 1), glm::vec3(p))));
            g.opacities.push_back(0.95f);
            for (int c = 0; c < 3; ++c) g.sh.push_back(0.2f);
        }
        other = g.positions;
        for (glm::vec3& p : other) p.y *= 1.5f;
        cloud = reg.create();
        reg.emplace<GaussianCloud>(cloud, std::move(g));
    }
    void swap_positions() { std::swap(reg.patch<GaussianCloud>(cloud).positions, other); }
};

void BM_GaussianRefresh(benchmark::State& st) {
    GaussianScene s(std::size_t(st.range(0)));
    PickingState state;
    state.refresh(s.reg);
    double cpu = 0.0;
    for (auto _ : st) {
        st.PauseTiming();
        s.swap_positions();
        st.ResumeTiming();
        const double t0 = process_cpu_seconds();
        benchmark::DoNotOptimize(state.refresh(s.reg));
        cpu += process_cpu_seconds() - t0;
    }
    st.counters["process_cpu_ms"] = 1e3 * cpu / double(st.iterations());
}
BENCHMARK(BM_GaussianRefresh)->Arg(59650)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

// One explicit ray at the Gaussian sphere (always a hit): traversal + ellipsoid intersection callbacks.
void BM_GaussianPickRay(benchmark::State& st) {
    GaussianScene s(std::size_t(st.range(0)));
    PickingState state;
    state.refresh(s.reg);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-0.6, 0.6);
    std::size_t hits = 0;
    for (auto _ : st) {
        PickQuery q = query_from_ray({{u(rng), u(rng), 4.0}, {0.0, 0.0, -1.0}});
        q.control_points = false;
        const PickHit h = pick(s.reg, state, q);
        hits += h.kind == PickKind::gaussian;
        benchmark::DoNotOptimize(h);
    }
    if (hits != std::size_t(st.iterations())) st.SkipWithError("a ray at the sphere missed");
}
BENCHMARK(BM_GaussianPickRay)->Arg(59650)->Arg(1000000)->Unit(benchmark::kMicrosecond);

}  // namespace
