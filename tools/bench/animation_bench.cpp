// Cost of the animation phase: evaluating the built-in paper demo clip (24 tracks) on an 11x11x11 lattice,
// and a whole animation_system frame (evaluate, compare with the last pose, patch the lattice).
// Run: build/<dir>/tools/bench/bench_animation
#include <benchmark/benchmark.h>

#include "systems/animation/animation_system.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"

namespace {

sffd::Lattice demo_lattice() {
    sffd::Lattice l;
    l.divisions = {10, 10, 10};
    l.origin = glm::dvec3(-1.0);
    l.axes = {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)};
    for (int i = 0; i <= 10; ++i)
        for (int j = 0; j <= 10; ++j)
            for (int k = 0; k <= 10; ++k) l.rest.push_back(l.origin + glm::dvec3(i, j, k) * 0.2);
    l.current = l.rest;
    return l;
}

void BM_EvaluatePaperDemoPose(benchmark::State& state) {
    const sffd::Lattice lattice = demo_lattice();
    const sffd::AnimationClip clip = sffd::make_paper_demo_clip(lattice);
    std::vector<glm::dvec3> pose;
    int frame = 0;
    for (auto _ : state) {
        sffd::evaluate_pose(clip, lattice, (frame++ % sffd::paper_demo_frames) / sffd::paper_demo_fps, pose);
        benchmark::DoNotOptimize(pose.data());
    }
}
BENCHMARK(BM_EvaluatePaperDemoPose);

void BM_AnimationSystemFrame(benchmark::State& state) {
    sffd::ecs::Registry registry;
    const sffd::ecs::Entity e = registry.create();
    const sffd::Lattice& lattice = registry.emplace<sffd::Lattice>(e, demo_lattice());
    sffd::attach_clip(registry, e, sffd::make_paper_demo_clip(lattice));
    std::uint64_t frame = 0;
    for (auto _ : state) {
        const double t = double(frame % sffd::paper_demo_frames) / sffd::paper_demo_fps;
        sffd::animation_system(registry, {frame++, t, 1.0 / sffd::paper_demo_fps});
    }
}
BENCHMARK(BM_AnimationSystemFrame);

}  // namespace
