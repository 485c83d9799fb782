// The 3D Gaussian benchmark case, shared by bench_gaussian (CPU deformation, import) and
// bench_gaussian_deform (CPU and GPU deformation): N flat Gaussians tangent to the unit Fibonacci sphere
// of the paper case with random SH, through the 11³ Bernstein lattice twisted by a graded 0.6/1.1 rad per
// unit height.
#pragma once

#include <cstddef>
#include <random>

#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/quaternion.hpp>

#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "tools/bench/bench_util.h"
#include "tools/bench/paper_case.h"

namespace sffd::bench {

// `count` Gaussians of SH `degree` (random coefficients, seed 1), flat along the sphere's normal.
inline GaussianCloud sphere_gaussians(std::size_t count, int degree) {
    GaussianCloud g;
    g.sh_degree = degree;
    g.positions.reserve(count), g.scales.reserve(count), g.rotations.reserve(count),
        g.opacities.reserve(count);
    g.sh.reserve(count * std::size_t(sh_coeffs(degree)) * 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 n = fibonacci_sphere(i, count);
        g.positions.push_back(glm::vec3(n));
        g.scales.emplace_back(0.01f, 0.01f, 0.001f);  // flat along the local z = the normal
        g.rotations.push_back(glm::quat(glm::rotation(glm::dvec3(0, 0, 1), n)));
        g.opacities.push_back(0.8f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

// The Gaussian benches' lattice (box [-1.1, 1.1]³, divisions 10, Bernstein, graded twist about +y).
inline Lattice twisted_gaussian_lattice() {
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1},
                                  {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6 / 1.1, glm::dvec3(0.0));
    return l;
}

// The CPU deformation benchmark loop (gaussian::deform, TBB) of `g` through the Gaussian lattice in SH
// mode `sh`: items are Gaussians, process_cpu_ms_per_run the CPU time of all threads per run.
inline void run_cpu_deform(benchmark::State& state, const GaussianCloud& g, gaussian::ShMode sh,
                           bool reference_shapes = false) {
    const Lattice l = twisted_gaussian_lattice();
    GaussianCloud out;
    gaussian::DeformOptions options;
    options.sh = sh;
    options.reference_shapes = reference_shapes;
    // One untimed run sizes `out` (hundreds of MB zeroed and faulted in on first touch): the timed runs are
    // the deformation as the editor and `deform --bench` repeat it, into an output that already exists.
    if (auto s = gaussian::deform(l, g, out, options); !s) return state.SkipWithError(s.message().c_str());
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        auto s = gaussian::deform(l, g, out, options);
        if (!s) state.SkipWithError(s.message().c_str());
        benchmark::DoNotOptimize(out.positions.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(g.size()));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
}

}  // namespace sffd::bench
