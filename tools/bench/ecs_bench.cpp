// View iteration over 1M entities with two components: the cost the ECS's storage layout is judged by.
#include <benchmark/benchmark.h>

#include "runtime/ecs/registry.h"

namespace {
struct Position {
    float x, y, z;
};
struct Velocity {
    float x, y, z;
};

void BM_ViewIterate1M(benchmark::State& state) {
    sffd::ecs::Registry reg;
    const int n = static_cast<int>(state.range(0));
    for (int i = 0; i < n; ++i) {
        auto e = reg.create();
        reg.emplace<Position>(e, float(i), 0.f, 0.f);
        reg.emplace<Velocity>(e, 1.f, 2.f, 3.f);
    }
    for (auto _ : state) {
        reg.view<Position, const Velocity>().each([](Position& p, const Velocity& v) {
            p.x += v.x;
            p.y += v.y;
            p.z += v.z;
        });
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ViewIterate1M)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
}  // namespace
