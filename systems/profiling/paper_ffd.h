// The seed paper's experiment (Beddiaf & Babahenini, section IV), reproduced as a measurement baseline.
//
// paper_ffd_naive() is the paper's CPU algorithm as the paper describes it: for every vertex, the triple
// sum over all (l+1)(m+1)(n+1) control points (1331 for 11^3) with each Bernstein polynomial evaluated
// per term from its definition (binomial coefficient times two powers), for the position (eq. 6) and for
// the three Jacobian columns (eqs. 11-19), then the deformed normal from the Jacobian. One thread, no
// factorisation, no caching, every frame. It is deliberately slow: it is what the paper's 0.02 FPS
// measured. The math follows ../shared/notes/ffd-math.md, not the paper's misprinted equations (5) and
// (11)-(22): derivative basis dB(l,i,s) = l (B(l-1,i-1,s) - B(l-1,i,s)), world Jacobian J = [Fs Ft Fu] M^-1,
// normal N' ~ cof(J) N. The engine's real deformers live in systems/ffd (owned by the FFD engineer).
//
// The four cases (paper figs. 3-6 and 8-11): local/global x stretch/twist (paper eqs. 23, 24). The paper
// does not say which control points form the "local" subset, nor the displacement or angle; the choices
// here are written in paper_ffd.cpp and in systems/profiling/README.md.
#pragma once

#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"
#include "systems/ffd/components.h"

namespace sffd::profiling {

struct PaperCase {
    const char* name;
    bool local;  // a subset of control points (else all of them)
    bool twist;  // rotation about an axis (else translation)
};
inline constexpr PaperCase paper_cases[4] = {
    {"local stretch", true, false},
    {"local twist", true, true},
    {"global stretch", false, false},
    {"global twist", false, true},
};

// Bounding lattice of the cloud (world space), padded by 2% per side so every point is strictly
// inside, with `divisions` cells per axis (the paper: 10, i.e. 11^3 control points), Bernstein basis.
Lattice paper_lattice(const SplatCloud& cloud, int divisions = 10);

// Sets lattice.current = the case applied to lattice.rest with strength `amount` (0 = rest, 1 = full:
// stretch by 30% of the U edge, twist by 60 degrees about the U direction through the selection's
// centroid). Local selection: i, j in the middle 5 layers, k in the top 3 layers.
void apply_paper_case(Lattice& lattice, const PaperCase& c, double amount);
// Control points the case moves.
std::vector<std::size_t> paper_case_selection(const Lattice& lattice, const PaperCase& c);

// Deforms points [begin, end) of the cloud: world X = cloud.origin + positions[i]; outputs are relative
// to cloud.origin again. Points outside the lattice are copied unchanged. out_* are resized to
// cloud.size() if smaller.
void paper_ffd_naive(const Lattice& lattice, const SplatCloud& cloud, std::vector<glm::vec3>& out_positions,
                     std::vector<glm::vec3>& out_normals, std::size_t begin = 0,
                     std::size_t end = static_cast<std::size_t>(-1));

// The paper's figures, for the table (section IV): CPU 0.02 FPS (~50 s per frame), GPU up to 5 FPS
// (~0.2 s), "almost 250 times" faster.
inline constexpr double paper_cpu_fps = 0.02;
inline constexpr double paper_gpu_fps = 5.0;
inline constexpr double paper_speedup = 250.0;

}  // namespace sffd::profiling
