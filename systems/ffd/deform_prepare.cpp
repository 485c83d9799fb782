// Preparing a lattice for the fast float kernels (deform_fast.cpp): the displacements, binomials, rows and
// B-spline grid the kernels read. Plain scalar code run once per lattice and call, so it is compiled once,
// not once per SIMD target as the kernels are.
#include <algorithm>
#include <cstdint>

#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd::detail {

namespace {

// Control point (i, j, k)'s x, y, z, 0 in the B-spline's zero-bordered grid ((L+3)(M+3)(N+3) points).
float* padded_point(Prepared& P, int i, int j, int k) {
    const std::size_t PM = std::size_t(P.M) + 3, PK = std::size_t(P.N) + 3;
    return &P.grid[((std::size_t(i + 1) * PM + std::size_t(j + 1)) * PK + std::size_t(k + 1)) * 4];
}

// The B-spline's cull box from the moved points' index range: control point i influences l·s in
// (i-2, i+2), so points outside the moved points' support are unchanged and skipped.
void set_cull_box(Prepared& P, const Lattice& l, const glm::ivec3& lo, const glm::ivec3& hi) {
    if (!P.any_moved) {
        for (int a = 0; a < 3; ++a) P.cull_lo[a] = 2.0f, P.cull_hi[a] = -1.0f;  // nothing inside
        return;
    }
    for (int a = 0; a < 3; ++a) {
        const float n = float(l.divisions[a]);
        P.cull_lo[a] = (float(lo[a]) - 2.0f) / n;
        P.cull_hi[a] = (float(hi[a]) + 2.0f) / n;
    }
}

// The coordinates the dense Bernstein kernel sums: those whose displacement somewhere exceeds 1e-12 of the
// lattice's size. A twist computed in double leaves its axis's coordinate off by rounding (1e-16 of the
// size): far below what a float result can show, and a third of the kernel's work. At least one.
void set_moving_coordinates(Prepared& P, const Lattice& l, const glm::dvec3& largest) {
    const double floor = 1e-12 * (glm::length(l.axes[0]) + glm::length(l.axes[1]) + glm::length(l.axes[2]));
    P.coords = 0;
    for (int a = 0; a < 3; ++a)
        if (largest[a] > floor) P.coord[P.coords++] = a;
    if (P.coords == 0)
        P.coords = 1, P.coord[0] = largest.y > largest.x ? (largest.z > largest.y ? 2 : 1)
                                                         : (largest.z > largest.x ? 2 : 0);
    for (int a = P.coords; a < 3; ++a) P.coord[a] = 0;
}

// PrepareFor::gpu_controls: ΔP in one pass over the control points in flat order, none of the CPU
// kernels' tables. The same values as the full preparation (a point that did not move keeps zeros), and
// the same moving coordinates (the GPU's Bernstein sums skip the others too).
void prepare_gpu_controls(Prepared& P, const Lattice& l) {
    const int L = P.L, M = P.M, N = P.N;
    const bool bspline = l.basis == LatticeBasis::bspline;
    if (bspline) P.grid.assign(std::size_t(L + 3) * (M + 3) * (N + 3) * 4, 0.0f);
    else P.dp4.assign(l.size() * 4, 0.0f);
    glm::ivec3 lo(1 << 30), hi(-1);
    glm::dvec3 largest(0.0);
    std::size_t c = 0;
    for (int i = 0; i <= L; ++i)
        for (int j = 0; j <= M; ++j)
            for (int k = 0; k <= N; ++k, ++c) {
                const glm::dvec3 d = l.current[c] - l.rest[c];
                if (d == glm::dvec3(0.0)) continue;
                largest = glm::max(largest, glm::abs(d));
                float* out = bspline ? padded_point(P, i, j, k) : &P.dp4[c * 4];
                out[0] = float(d.x), out[1] = float(d.y), out[2] = float(d.z);
                lo = glm::min(lo, glm::ivec3(i, j, k));
                hi = glm::max(hi, glm::ivec3(i, j, k));
                P.any_moved = true;
            }
    set_moving_coordinates(P, l, largest);
    if (bspline) set_cull_box(P, l, lo, hi);
}

}  // namespace

Prepared prepare(const Lattice& l, const glm::dvec3& cloud_origin, PrepareFor use) {
    Prepared P;
    P.L = l.divisions.x, P.M = l.divisions.y, P.N = l.divisions.z;
    P.basis = l.basis;
    const glm::dmat3 minv = inverse_axes(l);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) P.minv[r * 3 + c] = float(minv[c][r]);
    const glm::dvec3 stu0 = minv * (cloud_origin - l.origin);
    for (int a = 0; a < 3; ++a) P.stu0[a] = float(stu0[a]);
    if (use == PrepareFor::gpu_controls) {
        prepare_gpu_controls(P, l);
        return P;
    }
    const int L = P.L, M = P.M, N = P.N;
    glm::ivec3 lo(1 << 30), hi(-1);
    P.moved.reserve(l.size());  // a global edit moves every point: one allocation, not a dozen regrowths
    glm::dvec3 largest(0.0);    // per coordinate, the largest |ΔP|
    for_each_moved(l, [&](int i, int j, int k, const glm::dvec3& d) {
        largest = glm::max(largest, glm::abs(d));
        P.moved.push_back({i, j, k, {float(d.x), float(d.y), float(d.z)}});
        lo = glm::min(lo, glm::ivec3(i, j, k));
        hi = glm::max(hi, glm::ivec3(i, j, k));
    });
    P.any_moved = !P.moved.empty();
    set_moving_coordinates(P, l, largest);
    for (int a = 0; a < 3; ++a) {
        const int n = l.divisions[a];
        P.need[a].assign(std::size_t(n) + 1, 0);
        P.binom[a].resize(std::size_t(n) + 1);
        P.binom1[a].resize(std::size_t(n) + 1);
        double c = 1.0, c1 = 1.0;  // C(n,i), C(n-1,i)
        for (int i = 0; i <= n; ++i) {
            P.binom[a][i] = float(c);
            P.binom1[a][i] = float(i <= n - 1 ? c1 : 0.0);
            c = c * double(n - i) / double(i + 1);
            c1 = c1 * double(n - 1 - i) / double(i + 1);
        }
    }
    for (const auto& m : P.moved) P.need[0][m.i] = P.need[1][m.j] = P.need[2][m.k] = 1;
    if (l.basis == LatticeBasis::bernstein) {
        P.dp4.assign(l.size() * 4, 0.0f);
        if (P.coords < 3) P.dk4.assign(l.size() * 4, 0.0f);
        P.row_nonzero.assign(std::size_t(L + 1) * (M + 1), 0);
        for (const auto& m : P.moved) {
            float* d = &P.dp4[l.index(m.i, m.j, m.k) * 4];
            d[0] = m.d[0], d[1] = m.d[1], d[2] = m.d[2];
            if (P.coords < 3) {
                float* kd = &P.dk4[l.index(m.i, m.j, m.k) * 4];
                for (int a = 0; a < P.coords; ++a) kd[a] = m.d[P.coord[a]];
            }
            P.row_nonzero[std::size_t(m.i) * (M + 1) + m.j] = 1;
        }
        // The differences from the double displacements (not the rounded floats).
        P.du4.assign(std::size_t(L + 1) * (M + 1) * N * 4, 0.0f);
        for (int i = 0; i <= L; ++i)
            for (int j = 0; j <= M; ++j) {
                if (!P.row_nonzero[std::size_t(i) * (M + 1) + j]) continue;
                float* row = &P.du4[(std::size_t(i) * (M + 1) + j) * N * 4];
                for (int k = 0; k < N; ++k) {
                    const std::size_t a = l.index(i, j, k), b = l.index(i, j, k + 1);
                    const glm::dvec3 d =
                        double(N) * ((l.current[b] - l.rest[b]) - (l.current[a] - l.rest[a]));
                    for (int s = 0; s < P.coords; ++s) row[k * 4 + s] = float(d[P.coord[s]]);
                }
            }
    } else {
        P.grid.assign(std::size_t(L + 3) * (M + 3) * (N + 3) * 4, 0.0f);
        for (const auto& m : P.moved) {
            float* d = padded_point(P, m.i, m.j, m.k);
            d[0] = m.d[0], d[1] = m.d[1], d[2] = m.d[2];
        }
        set_cull_box(P, l, lo, hi);
    }
    return P;
}

}  // namespace sffd::ffd::detail
