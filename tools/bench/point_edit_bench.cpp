// Point operations on a 1M-point cloud (systems/point_edit): delete the selection, separate it into a new
// entity, and undo each, one operation per iteration (the set-up that selects the points is not timed).
// Argument: the share of the points selected, in percent (every k-th point, so every page is touched).
// Counters: step_bytes (the undo step's memory) and bytes_per_point (of the changed points).
//   build/<dir>/tools/bench/bench_point_edit --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/point_edit/point_edit.h"

namespace {

using namespace sffd;
constexpr std::size_t kPoints = 1'000'000;

template <class Cloud>
Cloud make_cloud();
template <>
SplatCloud make_cloud<SplatCloud>() {
    SplatCloud c;
    c.positions.resize(kPoints, glm::vec3(0.5f)), c.normals.resize(kPoints, glm::vec3(0, 0, 1));
    c.axis_u.resize(kPoints, glm::vec3(0.01f, 0, 0)), c.axis_v.resize(kPoints, glm::vec3(0, 0.01f, 0));
    c.colors.resize(kPoints, 0xff8040ffu);
    for (std::size_t i = 0; i < kPoints; ++i) c.positions[i].x = float(i) * 1e-6f;
    return c;
}
template <>
GaussianCloud make_cloud<GaussianCloud>() {
    GaussianCloud c;
    c.sh_degree = 3;
    c.positions.resize(kPoints, glm::vec3(0.5f)), c.scales.resize(kPoints, glm::vec3(0.01f));
    c.rotations.resize(kPoints, glm::quat(1, 0, 0, 0)), c.opacities.resize(kPoints, 0.8f);
    c.sh.resize(kPoints * 48, 0.1f);
    for (std::size_t i = 0; i < kPoints; ++i) c.positions[i].x = float(i) * 1e-6f;
    return c;
}

template <class Cloud>
ecs::Entity setup(ecs::Registry& reg) {
    const ecs::Entity e = reg.create();
    reg.emplace<Cloud>(e, make_cloud<Cloud>());
    reg.emplace<PointFlags>(e).bits.assign(kPoints, 0);
    reg.emplace<Name>(e, Name{"bench"});
    return e;
}

void select_every(ecs::Registry& reg, ecs::Entity e, std::int64_t percent) {
    auto& bits = reg.patch<PointFlags>(e).bits;
    const std::size_t step = std::size_t(100 / percent);
    for (std::size_t i = 0; i < kPoints; ++i) bits[i] = (i % step == 0) ? kPointSelected : 0;
}

void report(benchmark::State& state, const point_edit::PointEditStep& s) {
    state.counters["step_bytes"] = double(s.bytes());
    state.counters["bytes_per_point"] = double(s.bytes()) / double(std::max<std::size_t>(1, s.points.size()));
    state.counters["changed"] = double(s.points.size());
}

template <class Cloud, bool Separate>
void BM_Apply(benchmark::State& state) {
    ecs::Registry reg;
    const ecs::Entity e = setup<Cloud>(reg);
    point_edit::PointEditStep last;
    for (auto _ : state) {
        state.PauseTiming();
        if (last.created && reg.valid(last.created)) reg.destroy(last.created);
        select_every(reg, e, state.range(0));
        state.ResumeTiming();
        last = Separate ? point_edit::separate_selected(reg, e) : point_edit::delete_selected(reg, e);
        benchmark::DoNotOptimize(last.points.size());
    }
    report(state, last);
}

template <class Cloud, bool Separate>
void BM_Undo(benchmark::State& state) {
    ecs::Registry reg;
    const ecs::Entity e = setup<Cloud>(reg);
    point_edit::PointEditStep step;
    for (auto _ : state) {
        state.PauseTiming();
        select_every(reg, e, state.range(0));
        step = Separate ? point_edit::separate_selected(reg, e) : point_edit::delete_selected(reg, e);
        state.ResumeTiming();
        point_edit::undo(reg, step);
        benchmark::DoNotOptimize(step.created);
    }
    report(state, step);
}

template <class Cloud>
void BM_RedoSeparate(benchmark::State& state) {
    ecs::Registry reg;
    const ecs::Entity e = setup<Cloud>(reg);
    select_every(reg, e, state.range(0));
    point_edit::PointEditStep step = point_edit::separate_selected(reg, e);
    for (auto _ : state) {
        state.PauseTiming();
        point_edit::undo(reg, step);
        state.ResumeTiming();
        point_edit::redo(reg, step);
    }
    report(state, step);
}

#define SFFD_POINT_EDIT_BENCH(fn) BENCHMARK(fn)->Arg(1)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)
SFFD_POINT_EDIT_BENCH((BM_Apply<SplatCloud, false>))->Name("BM_Delete/surface");
SFFD_POINT_EDIT_BENCH((BM_Apply<GaussianCloud, false>))->Name("BM_Delete/gaussian");
SFFD_POINT_EDIT_BENCH((BM_Apply<SplatCloud, true>))->Name("BM_Separate/surface");
SFFD_POINT_EDIT_BENCH((BM_Apply<GaussianCloud, true>))->Name("BM_Separate/gaussian");
SFFD_POINT_EDIT_BENCH((BM_Undo<SplatCloud, false>))->Name("BM_UndoDelete/surface");
SFFD_POINT_EDIT_BENCH((BM_Undo<GaussianCloud, false>))->Name("BM_UndoDelete/gaussian");
SFFD_POINT_EDIT_BENCH((BM_Undo<SplatCloud, true>))->Name("BM_UndoSeparate/surface");
SFFD_POINT_EDIT_BENCH((BM_Undo<GaussianCloud, true>))->Name("BM_UndoSeparate/gaussian");
SFFD_POINT_EDIT_BENCH((BM_RedoSeparate<SplatCloud>))->Name("BM_RedoSeparate/surface");
SFFD_POINT_EDIT_BENCH((BM_RedoSeparate<GaussianCloud>))->Name("BM_RedoSeparate/gaussian");

}  // namespace
