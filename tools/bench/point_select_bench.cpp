// Point selection on 1M points (systems/point_select), through its public API as the editor calls it:
// a unit sphere of 1,000,000 surface splats or 3D Gaussians (Fibonacci spiral, discs tangent to it, about
// the spacing of their neighbours) seen whole from z = 3.5 at 1280x720 (the sphere about 650 px across).
//   BM_BrushDab   one dab of the brush tool: select_region(circle_region(c, 40 px)) in add mode, visible
//                 only; the dab moves along the stroke (a new centre every iteration), the selection grows
//                 as a stroke's does
//   BM_Box        a rectangle selection (set mode, visible only) over the middle of the sphere, 400x300 px
//                 (about 66,000 points); two boxes alternate so every call changes the selection
//   BM_BoxFirst   the same box with a fresh PointSelectState each time (the first tool use after the cloud
//                 changed: its block bounds and footprint radii are rebuilt inside the timed call)
// The state (PointSelectState) is kept between iterations as the editor keeps it, except in BM_BoxFirst.
// Counters: changed (points the last brush dab added), selected (the selection's size at the end).
// Targets: a brush dab <= 100 ms, a box <= 200 ms.
//   build/release/tools/bench/bench_point_select --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/picking/screen_view.h"
#include "systems/point_select/point_select.h"

namespace {

using namespace sffd;
namespace ps = sffd::point_select;

constexpr std::size_t kPoints = 1'000'000;
constexpr int kWidth = 1280, kHeight = 720;

// Splats on the unit sphere, each disc as wide as the spiral's spacing.
SplatCloud sphere_splats() {
    SplatCloud c;
    c.positions.reserve(kPoints), c.normals.reserve(kPoints);
    c.axis_u.reserve(kPoints), c.axis_v.reserve(kPoints);
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    const float r = float(std::sqrt(4.0 / double(kPoints)));  // disc area ~ the sphere's share a point
    for (std::size_t k = 0; k < kPoints; ++k) {
        const double z = 1.0 - 2.0 * (double(k) + 0.5) / double(kPoints), rho = std::sqrt(1.0 - z * z);
        const double phi = golden * double(k);
        const glm::vec3 p(float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z));
        const glm::vec3 t =
            glm::normalize(glm::cross(std::abs(p.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0), p));
        c.positions.push_back(p), c.normals.push_back(p);
        c.axis_u.push_back(t * r), c.axis_v.push_back(glm::cross(p, t) * r);
        c.colors.push_back(0xff808080u);
    }
    return c;
}

// The same points as flat Gaussians: 2 sigma along the surface = the disc radius, thin along the normal.
GaussianCloud sphere_gaussians() {
    const SplatCloud s = sphere_splats();
    GaussianCloud g;
    g.sh_degree = 0;
    g.positions = s.positions;
    g.scales.reserve(kPoints), g.rotations.reserve(kPoints), g.opacities.assign(kPoints, 0.9f);
    g.sh.reserve(kPoints * 3);
    for (std::size_t i = 0; i < kPoints; ++i) {
        const float sigma = glm::length(s.axis_u[i]) * 0.5f;
        g.scales.emplace_back(sigma, sigma, sigma * 0.05f);
        // Local z along the normal: the columns of the rotation are u, v, n.
        const glm::mat3 m(glm::normalize(s.axis_u[i]), glm::normalize(s.axis_v[i]), s.normals[i]);
        g.rotations.push_back(glm::normalize(glm::quat_cast(m)));
        g.sh.insert(g.sh.end(), {0.2f, 0.2f, 0.2f});
    }
    return g;
}

picking::ScreenView front_view() {
    Camera c;
    c.eye = {0.0, 0.0, 3.5};
    c.target = {0.0, 0.0, 0.0};
    c.up = {0.0, 1.0, 0.0};
    c.fov_y_degrees = 35.0f;
    c.near_plane = 0.1f;
    c.far_plane = 100.0f;
    return picking::make_screen_view(c, {kWidth, kHeight});
}

template <class Cloud>
Cloud make_cloud();
template <>
SplatCloud make_cloud<SplatCloud>() {
    return sphere_splats();
}
template <>
GaussianCloud make_cloud<GaussianCloud>() {
    return sphere_gaussians();
}

// One cloud per kind, made once (a million points take a while to generate).
template <class Cloud>
const Cloud& cloud_of() {
    static const Cloud c = make_cloud<Cloud>();
    return c;
}

template <class Cloud>
ecs::Entity setup(ecs::Registry& reg) {
    const ecs::Entity e = reg.create();
    reg.emplace<Name>(e, Name{"bench"});
    reg.emplace<Transform>(e, Transform{});
    reg.emplace<Cloud>(e, cloud_of<Cloud>());
    reg.emplace<PointFlags>(e).bits.assign(kPoints, 0);
    return e;
}

const ps::ScreenOptions kVisibleAdd{.mode = ps::Mode::add, .visible_only = true};
const ps::ScreenOptions kVisibleSet{.mode = ps::Mode::set, .visible_only = true};

template <class Cloud>
void BM_BrushDab(benchmark::State& state) {
    ecs::Registry reg;
    const ecs::Entity e = setup<Cloud>(reg);
    ps::PointSelectState select;
    const picking::ScreenView view = front_view();
    // A stroke across the sphere's middle, 5 px between dabs, back and forth.
    std::size_t dab = 0, candidates = 0;
    for (auto _ : state) {
        const double t = double(dab++ % 100) / 99.0;
        const glm::dvec2 centre(kWidth * 0.5 + (t - 0.5) * 500.0, kHeight * 0.5 + 20.0 * std::sin(6.0 * t));
        const ps::SelectionDelta d =
            ps::select_region(reg, select, e, view, ps::circle_region(centre, 40.0), kVisibleAdd);
        candidates = d.changed();
        benchmark::DoNotOptimize(candidates);
    }
    state.counters["changed"] = double(candidates);
    state.counters["selected"] = double(ps::selected_count(reg, e));
}

template <class Cloud, bool First>
void BM_Box(benchmark::State& state) {
    ecs::Registry reg;
    const ecs::Entity e = setup<Cloud>(reg);
    ps::PointSelectState kept;
    const picking::ScreenView view = front_view();
    const glm::dvec2 c(kWidth * 0.5, kHeight * 0.5);
    const ps::ScreenRegion boxes[2] = {ps::rect_region(c - glm::dvec2(200, 150), c + glm::dvec2(200, 150)),
                                       ps::rect_region(c - glm::dvec2(190, 160), c + glm::dvec2(210, 140))};
    std::size_t i = 0;
    for (auto _ : state) {
        if (First) {
            state.PauseTiming();
            kept = ps::PointSelectState{};
            state.ResumeTiming();
        }
        const ps::SelectionDelta d = ps::select_region(reg, kept, e, view, boxes[i++ % 2], kVisibleSet);
        benchmark::DoNotOptimize(d.pages.size());
    }
    state.counters["selected"] = double(ps::selected_count(reg, e));
}

BENCHMARK(BM_BrushDab<SplatCloud>)->Name("BM_BrushDab/surface")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BrushDab<GaussianCloud>)->Name("BM_BrushDab/gaussian")->Unit(benchmark::kMillisecond);
BENCHMARK((BM_Box<SplatCloud, false>))->Name("BM_Box/surface")->Unit(benchmark::kMillisecond);
BENCHMARK((BM_Box<GaussianCloud, false>))->Name("BM_Box/gaussian")->Unit(benchmark::kMillisecond);
BENCHMARK((BM_Box<SplatCloud, true>))->Name("BM_BoxFirst/surface")->Unit(benchmark::kMillisecond);
BENCHMARK((BM_Box<GaussianCloud, true>))->Name("BM_BoxFirst/gaussian")->Unit(benchmark::kMillisecond);

}  // namespace
