// Fast float kernels (compiled with -O3 -ffp-contract=fast; the vector width follows the build: 16 lanes
// with AVX-512 (-march=native on this machine), 8 with AVX2).
//
// Bernstein (dense): W points in the W lanes of one vector; the u-basis (and the degree below it) stays in
// registers while every control point's displacement is broadcast, and the sum is factorised
// Q[i][j] = Σ_k ΔP B_k(u), R[i] = Σ_j Q B_j(t), D = Σ_i R B_i(s), the u-derivative over the rows' forward
// differences: ~8.8k multiply-adds per point for an 11³ lattice with normals and axes. Sparse: the same
// lanes, but only moved control points are summed. B-spline: one point at a time; ΔP lives in a zero-bordered
// grid stored x,y,z,0 so the four k-neighbours of one (i,j) are 16 contiguous floats (one vector load), 16
// loads per point.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd::detail {

namespace {

#if defined(__AVX512F__)
constexpr int W = 16;
#elif defined(__AVX__)
constexpr int W = 8;
#else
constexpr int W = 4;
#endif
typedef float vf __attribute__((vector_size(W * sizeof(float))));
typedef float v16 __attribute__((vector_size(64)));
typedef float v4 __attribute__((vector_size(16)));

constexpr int kMaxB = kMaxDivisions + 1;

inline vf loadv(const float* p) {
    vf v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
inline void storev(float* p, vf v) { std::memcpy(p, &v, sizeof v); }
inline vf splat(float x) { return vf{} + x; }

// Up to W points gathered from the cloud: clamped local coordinates in, displacement D and its
// derivatives G[c*3+a] = ∂D_c/∂(s,t,u)_a out.
struct Group {
    alignas(64) float s[W], t[W], u[W];
    alignas(64) float D[3][W];
    alignas(64) float G[9][W];
    std::uint32_t idx[W];
    int n = 0;
    bool contiguous = false;  // points first .. first+W-1 (full block): vector loads/stores, no gathers
    std::size_t first = 0;
};

// Writes a kernel's sums into the group: D_c = X[c], and with Full the derivatives G[c*3+a] = (Fs, Ft,
// Fu)[c].
template <bool Full>
inline void store_group(Group& g, const vf (&X)[3], const vf (&Fs)[3], const vf (&Ft)[3], const vf (&Fu)[3]) {
    for (int c = 0; c < 3; ++c) {
        storev(g.D[c], X[c]);
        if constexpr (Full) {
            storev(g.G[c * 3 + 0], Fs[c]);
            storev(g.G[c * 3 + 1], Ft[c]);
            storev(g.G[c * 3 + 2], Fu[c]);
        }
    }
}

// Load / store W consecutive vec3 (AoS) as three vectors. AVX-512: three 16-float loads and permutes.
inline void load_xyz(const glm::vec3* p, vf& x, vf& y, vf& z) {
#if defined(__AVX512F__)
    v16 a, b, c;
    std::memcpy(&a, reinterpret_cast<const float*>(p), 64);
    std::memcpy(&b, reinterpret_cast<const float*>(p) + 16, 64);
    std::memcpy(&c, reinterpret_cast<const float*>(p) + 32, 64);
    const v16 tx = __builtin_shufflevector(a, b, 0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30, 0, 0, 0, 0, 0);
    x = __builtin_shufflevector(tx, c, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 17, 20, 23, 26, 29);
    const v16 ty = __builtin_shufflevector(a, b, 1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31, 0, 0, 0, 0, 0);
    y = __builtin_shufflevector(ty, c, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 18, 21, 24, 27, 30);
    const v16 tz = __builtin_shufflevector(a, b, 2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 0, 0, 0, 0, 0, 0);
    z = __builtin_shufflevector(tz, c, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 16, 19, 22, 25, 28, 31);
#else
    alignas(64) float ax[W], ay[W], az[W];
    for (int l = 0; l < W; ++l) ax[l] = p[l].x, ay[l] = p[l].y, az[l] = p[l].z;
    x = loadv(ax), y = loadv(ay), z = loadv(az);
#endif
}
inline void store_xyz(glm::vec3* p, vf x, vf y, vf z) {
#if defined(__AVX512F__)
    const v16 ta = __builtin_shufflevector(x, y, 0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5);
    const v16 a = __builtin_shufflevector(ta, z, 0, 1, 16, 3, 4, 17, 6, 7, 18, 9, 10, 19, 12, 13, 20, 15);
    const v16 tb = __builtin_shufflevector(x, y, 21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26);
    const v16 b = __builtin_shufflevector(tb, z, 0, 21, 2, 3, 22, 5, 6, 23, 8, 9, 24, 11, 12, 25, 14, 15);
    const v16 tc = __builtin_shufflevector(x, y, 0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0);
    const v16 c = __builtin_shufflevector(tc, z, 26, 1, 2, 27, 4, 5, 28, 7, 8, 29, 10, 11, 30, 13, 14, 31);
    std::memcpy(reinterpret_cast<float*>(p), &a, 64);
    std::memcpy(reinterpret_cast<float*>(p) + 16, &b, 64);
    std::memcpy(reinterpret_cast<float*>(p) + 32, &c, 64);
#else
    alignas(64) float ax[W], ay[W], az[W];
    storev(ax, x), storev(ay, y), storev(az, z);
    for (int l = 0; l < W; ++l) p[l] = glm::vec3(ax[l], ay[l], az[l]);
#endif
}

// Bernstein basis of degree L (b[0..L]) and of degree L-1 (lower[0..L-1]), the step before it.
inline void bernstein_with_lower(vf s, int L, vf* b, vf* lower) {
    const vf one = splat(1.0f), r = one - s;
    b[0] = one;
    for (int d = 1; d < L; ++d) {  // degree d-1 -> d
        b[d] = s * b[d - 1];
        for (int i = d - 1; i >= 1; --i) b[i] = r * b[i] + s * b[i - 1];
        b[0] = r * b[0];
    }
    for (int i = 0; i < L; ++i) lower[i] = b[i];
    b[L] = s * b[L - 1];
    for (int i = L - 1; i >= 1; --i) b[i] = r * b[i] + s * b[i - 1];
    b[0] = r * b[0];
}

// Bernstein basis of degree L (b[0..L]) and its derivative (db) for W parameters at once:
// dB(L,i) = L (B(L-1,i-1) - B(L-1,i)).
inline void bernstein(vf s, int L, vf* b, vf* db) {
    vf lower[kMaxB];
    bernstein_with_lower(s, L, b, lower);
    const float fl = float(L);
    db[0] = -fl * lower[0];
    for (int i = 1; i < L; ++i) db[i] = fl * (lower[i - 1] - lower[i]);
    db[L] = fl * lower[L - 1];
}

// The u-derivative is summed over the rows' forward differences (du4: N (ΔP[k+1] − ΔP[k])) against the
// degree N-1 basis: dB(N,k)/du = N (B(N-1,k-1) − B(N-1,k)) regrouped, N terms a row instead of N+1.
// Only the NC coordinates that move (Prepared::coord) are summed: a twist leaves its axis's coordinate,
// a stretch the other two, and each coordinate is a third of the work.
template <int KC, int NC, bool Full>
void bernstein_group(const Prepared& P, Group& g) {
    const int L = P.L, M = P.M;
    const int K = KC ? KC : P.N + 1;
    constexpr int KA = KC ? KC : kMaxB;
    vf bs[kMaxB], dbs[kMaxB], bt[kMaxB], dbt[kMaxB], bu[KA], bl[KA];
    bernstein(loadv(g.s), L, bs, dbs);
    bernstein(loadv(g.t), M, bt, dbt);
    bernstein_with_lower(loadv(g.u), K - 1, bu, bl);
    vf X[NC] = {}, Fs[NC] = {}, Ft[NC] = {}, Fu[NC] = {};
    const float* dp = P.coords == 3 ? P.dp4.data() : P.dk4.data();
    const float* du = P.du4.data();
    const std::uint8_t* nz = P.row_nonzero.data();
    for (int i = 0; i <= L; ++i) {
        vf R[NC] = {}, Rt[NC] = {}, Ru[NC] = {};
        for (int j = 0; j <= M; ++j) {
            const int row = i * (M + 1) + j;
            if (!nz[row]) continue;
            const float* c = dp + std::size_t(row) * K * 4;
            const float* e = du + std::size_t(row) * (K - 1) * 4;
            vf q[NC] = {}, w[NC] = {};
#pragma GCC unroll 16
            for (int k = 0; k < K - 1; ++k)
#pragma GCC unroll 3
                for (int a = 0; a < NC; ++a) {
                    q[a] += bu[k] * c[4 * k + a];
                    if constexpr (Full) w[a] += bl[k] * e[4 * k + a];
                }
#pragma GCC unroll 3
            for (int a = 0; a < NC; ++a) q[a] += bu[K - 1] * c[4 * (K - 1) + a];
            for (int a = 0; a < NC; ++a) {
                R[a] += q[a] * bt[j];
                if constexpr (Full) Rt[a] += q[a] * dbt[j], Ru[a] += w[a] * bt[j];
            }
        }
        for (int a = 0; a < NC; ++a) {
            X[a] += R[a] * bs[i];
            if constexpr (Full) {
                Fs[a] += R[a] * dbs[i];
                Ft[a] += Rt[a] * bs[i];
                Fu[a] += Ru[a] * bs[i];
            }
        }
    }
    // The coordinates that do not move get exact zeros.
    vf Xc[3] = {}, Fsc[3] = {}, Ftc[3] = {}, Fuc[3] = {};
    for (int a = 0; a < NC; ++a) {
        const int c = P.coord[a];
        Xc[c] = X[a], Fsc[c] = Fs[a], Ftc[c] = Ft[a], Fuc[c] = Fu[a];
    }
    store_group<Full>(g, Xc, Fsc, Ftc, Fuc);
}

// Bernstein basis values B(L,i,s) and derivatives for the indices flagged in `need` only, from powers
// s^i and (1-s)^(L-i): O(L) per axis instead of O(L²) (what the sparse path needs).
inline void bernstein_some(vf s, int L, const std::uint8_t* need, const float* binom_l, const float* binom_l1,
                           vf* b, vf* db, bool full) {
    vf sp[kMaxB + 1], rp[kMaxB + 1];
    const vf r = splat(1.0f) - s;
    sp[0] = rp[0] = splat(1.0f);
    for (int i = 1; i <= L; ++i) sp[i] = sp[i - 1] * s, rp[i] = rp[i - 1] * r;
    const float fl = float(L);
    for (int i = 0; i <= L; ++i) {
        if (!need[i]) continue;
        b[i] = binom_l[i] * sp[i] * rp[L - i];
        if (full) {
            // dB = L (B(L-1,i-1) - B(L-1,i))
            const vf lo = i > 0 ? binom_l1[i - 1] * sp[i - 1] * rp[L - i] : vf{};
            const vf hi = i < L ? binom_l1[i] * sp[i] * rp[L - 1 - i] : vf{};
            db[i] = fl * (lo - hi);
        }
    }
}

template <bool Full>
void sparse_group(const Prepared& P, Group& g) {
    vf bs[kMaxB], dbs[kMaxB], bt[kMaxB], dbt[kMaxB], bu[kMaxB], dbu[kMaxB];
    bernstein_some(loadv(g.s), P.L, P.need[0].data(), P.binom[0].data(), P.binom1[0].data(), bs, dbs, Full);
    bernstein_some(loadv(g.t), P.M, P.need[1].data(), P.binom[1].data(), P.binom1[1].data(), bt, dbt, Full);
    bernstein_some(loadv(g.u), P.N, P.need[2].data(), P.binom[2].data(), P.binom1[2].data(), bu, dbu, Full);
    vf X[3] = {}, Fs[3] = {}, Ft[3] = {}, Fu[3] = {};
    for (const Prepared::Moved& m : P.moved) {
        const vf st = bs[m.i] * bt[m.j];
        const vf w = st * bu[m.k];
        for (int c = 0; c < 3; ++c) X[c] += w * m.d[c];
        if constexpr (Full) {
            const vf ws = dbs[m.i] * bt[m.j] * bu[m.k];
            const vf wt = bs[m.i] * dbt[m.j] * bu[m.k];
            const vf wu = st * dbu[m.k];
            for (int c = 0; c < 3; ++c) {
                Fs[c] += ws * m.d[c];
                Ft[c] += wt * m.d[c];
                Fu[c] += wu * m.d[c];
            }
        }
    }
    store_group<Full>(g, X, Fs, Ft, Fu);
}

__attribute__((always_inline)) inline v4 lanes4(v16 r) {
    const v4 a = __builtin_shufflevector(r, r, 0, 1, 2, 3), b = __builtin_shufflevector(r, r, 4, 5, 6, 7);
    const v4 c = __builtin_shufflevector(r, r, 8, 9, 10, 11),
             d = __builtin_shufflevector(r, r, 12, 13, 14, 15);
    return (a + b) + (c + d);
}
__attribute__((always_inline)) inline v16 expand4(const float w[4]) {
    return v16{w[0], w[0], w[0], w[0], w[1], w[1], w[1], w[1],
               w[2], w[2], w[2], w[2], w[3], w[3], w[3], w[3]};
}

typedef int vi __attribute__((vector_size(W * sizeof(int))));

// Cell index and the 4 weights (and derivatives, scaled by n) for W parameters at once.
struct AxisWeights {
    alignas(64) int c[W];
    alignas(64) float w[4][W], dw[4][W];
};
inline void bspline_axis(vf x, int n, AxisWeights& out) {
    const vf gx = x * float(n);
    vi c = __builtin_convertvector(gx, vi);
    c = c > (n - 1) ? vi{} + (n - 1) : c;
    const vf f = gx - __builtin_convertvector(c, vf);
    const vf f2 = f * f, f3 = f2 * f, r = 1.0f - f, sc = splat(float(n));
    std::memcpy(out.c, &c, sizeof c);
    storev(out.w[0], r * r * r * (1.0f / 6.0f));
    storev(out.w[1], (3.0f * f3 - 6.0f * f2 + 4.0f) * (1.0f / 6.0f));
    storev(out.w[2], (-3.0f * f3 + 3.0f * f2 + 3.0f * f + 1.0f) * (1.0f / 6.0f));
    storev(out.w[3], f3 * (1.0f / 6.0f));
    storev(out.dw[0], -0.5f * r * r * sc);
    storev(out.dw[1], (1.5f * f2 - 2.0f * f) * sc);
    storev(out.dw[2], (-1.5f * f2 + f + 0.5f) * sc);
    storev(out.dw[3], 0.5f * f2 * sc);
}

template <bool Full>
void bspline_group(const Prepared& P, Group& g) {
    const int PM = P.M + 3, PK = P.N + 3;
    AxisWeights as, at, au;
    bspline_axis(loadv(g.s), P.L, as);
    bspline_axis(loadv(g.t), P.M, at);
    bspline_axis(loadv(g.u), P.N, au);
    for (int lane = 0; lane < g.n; ++lane) {
        const int ci = as.c[lane], cj = at.c[lane], ck = au.c[lane];
        const float ws[4] = {as.w[0][lane], as.w[1][lane], as.w[2][lane], as.w[3][lane]};
        const float dws[4] = {as.dw[0][lane], as.dw[1][lane], as.dw[2][lane], as.dw[3][lane]};
        const float wt[4] = {at.w[0][lane], at.w[1][lane], at.w[2][lane], at.w[3][lane]};
        const float dwt[4] = {at.dw[0][lane], at.dw[1][lane], at.dw[2][lane], at.dw[3][lane]};
        const float wu[4] = {au.w[0][lane], au.w[1][lane], au.w[2][lane], au.w[3][lane]};
        const float dwu[4] = {au.dw[0][lane], au.dw[1][lane], au.dw[2][lane], au.dw[3][lane]};
        // Padded index = index + 1, so neighbour c-1 of cell c sits at padded c. Sum over a (s) first into
        // one accumulator per b (t), then combine: 16 FMAs per point for positions, 32 with derivatives.
        const float* base = P.grid.data() + ((std::size_t(ci) * PM + cj) * PK + ck) * 4;
#if defined(__AVX512F__)
        v16 acc[4] = {}, accs[4] = {};
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                v16 d;
                std::memcpy(&d, base + (std::size_t(a) * PM + b) * PK * 4, sizeof d);
                acc[b] += d * ws[a];
                if constexpr (Full) accs[b] += d * dws[a];
            }
        const v16 x16 = acc[0] * wt[0] + acc[1] * wt[1] + acc[2] * wt[2] + acc[3] * wt[3];
#else
        // 16 ymm registers only: three accumulators (two ymm each) with combined weights.
        v16 x16 = {}, s16 = {}, t16 = {};
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                v16 d;
                std::memcpy(&d, base + (std::size_t(a) * PM + b) * PK * 4, sizeof d);
                x16 += d * (ws[a] * wt[b]);
                if constexpr (Full) {
                    s16 += d * (dws[a] * wt[b]);
                    t16 += d * (ws[a] * dwt[b]);
                }
            }
#endif
        const v16 wu16 = expand4(wu);
        const v4 x = lanes4(x16 * wu16);
        for (int c = 0; c < 3; ++c) g.D[c][lane] = x[c];
        if constexpr (Full) {
#if defined(__AVX512F__)
            const v16 s16 = accs[0] * wt[0] + accs[1] * wt[1] + accs[2] * wt[2] + accs[3] * wt[3];
            const v16 t16 = acc[0] * dwt[0] + acc[1] * dwt[1] + acc[2] * dwt[2] + acc[3] * dwt[3];
#endif
            const v4 xs = lanes4(s16 * wu16), xt = lanes4(t16 * wu16), xu = lanes4(x16 * expand4(dwu));
            for (int c = 0; c < 3; ++c) {
                g.G[c * 3 + 0][lane] = xs[c];
                g.G[c * 3 + 1][lane] = xt[c];
                g.G[c * 3 + 2][lane] = xu[c];
            }
        }
    }
}

using GroupFn = void (*)(const Prepared&, Group&);

template <int NC, bool Full>
GroupFn pick_bernstein(int K) {
    switch (K) {
        case 2: return bernstein_group<2, NC, Full>;
        case 3: return bernstein_group<3, NC, Full>;
        case 4: return bernstein_group<4, NC, Full>;
        case 5: return bernstein_group<5, NC, Full>;
        case 6: return bernstein_group<6, NC, Full>;
        case 7: return bernstein_group<7, NC, Full>;
        case 8: return bernstein_group<8, NC, Full>;
        case 9: return bernstein_group<9, NC, Full>;
        case 10: return bernstein_group<10, NC, Full>;
        case 11: return bernstein_group<11, NC, Full>;
        case 12: return bernstein_group<12, NC, Full>;
        default: return bernstein_group<0, NC, Full>;
    }
}
template <bool Full>
GroupFn pick_bernstein(int K, int coords) {
    return coords == 1   ? pick_bernstein<1, Full>(K)
           : coords == 2 ? pick_bernstein<2, Full>(K)
                         : pick_bernstein<3, Full>(K);
}

// Writes one group back: X' = X + D, J = I + G M⁻¹, n' = cof(J) n / |.|, axes J a. Returns inverted count.
int finish_group(const Prepared& P, const Group& g, const PointsIn& in, const PointsOut& out, bool full) {
    const bool want_n = in.normals && out.normals, want_u = in.axis_u && out.axis_u,
               want_v = in.axis_v && out.axis_v;
    alignas(64) float nx[W], ny[W], nz[W];
    auto gather = [&](const glm::vec3* src, vf& x, vf& y, vf& z) {
        if (g.contiguous) return load_xyz(src + g.first, x, y, z);
        for (int l = 0; l < W; ++l) {
            const glm::vec3 v = src[g.idx[l < g.n ? l : 0]];
            nx[l] = v.x, ny[l] = v.y, nz[l] = v.z;
        }
        x = loadv(nx), y = loadv(ny), z = loadv(nz);
    };
    auto scatter = [&](glm::vec3* dst, vf x, vf y, vf z) {
        if (g.contiguous) return store_xyz(dst + g.first, x, y, z);
        storev(nx, x), storev(ny, y), storev(nz, z);
        for (int l = 0; l < g.n; ++l) dst[g.idx[l]] = glm::vec3(nx[l], ny[l], nz[l]);
    };
    vf px, py, pz;
    gather(in.positions, px, py, pz);
    scatter(out.positions, px + loadv(g.D[0]), py + loadv(g.D[1]), pz + loadv(g.D[2]));
    if (!full) return 0;
    // J[r][c] (row r, column c) = δ + Σ_a G[r][a] M⁻¹[a][c]
    vf J[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            vf v = splat(r == c ? 1.0f : 0.0f);
            for (int a = 0; a < 3; ++a) v += loadv(g.G[r * 3 + a]) * P.minv[a * 3 + c];
            J[r][c] = v;
        }
    // Columns a, b, c of J; cofactor columns b×c, c×a, a×b.
    const vf ax = J[0][0], ay = J[1][0], az = J[2][0];
    const vf bx = J[0][1], by = J[1][1], bz = J[2][1];
    const vf cx = J[0][2], cy = J[1][2], cz = J[2][2];
    const vf bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
    const vf det = ax * bcx + ay * bcy + az * bcz;
    int inverted = 0;
    alignas(64) float detv[W];
    storev(detv, det);
    for (int l = 0; l < g.n; ++l) inverted += detv[l] < 0.0f;
    if (want_n) {
        const vf cax = cy * az - cz * ay, cay = cz * ax - cx * az, caz = cx * ay - cy * ax;
        const vf abx = ay * bz - az * by, aby = az * bx - ax * bz, abz = ax * by - ay * bx;
        vf n0, n1, n2;
        gather(in.normals, n0, n1, n2);
        const vf ox = bcx * n0 + cax * n1 + abx * n2, oy = bcy * n0 + cay * n1 + aby * n2,
                 oz = bcz * n0 + caz * n1 + abz * n2;
        const vf len2 = ox * ox + oy * oy + oz * oz;
        alignas(64) float l2[W];
        storev(l2, len2);
        for (int l = 0; l < W; ++l) l2[l] = l2[l] > 0.0f ? 1.0f / std::sqrt(l2[l]) : 1.0f;  // vectorised
        const vf inv = loadv(l2);
        scatter(out.normals, ox * inv, oy * inv, oz * inv);
    }
    auto axis = [&](const glm::vec3* src, glm::vec3* dst) {
        vf v0, v1, v2;
        gather(src, v0, v1, v2);
        scatter(dst, ax * v0 + bx * v1 + cx * v2, ay * v0 + by * v1 + cy * v2, az * v0 + bz * v1 + cz * v2);
    };
    if (want_u) axis(in.axis_u, out.axis_u);
    if (want_v) axis(in.axis_v, out.axis_v);
    if (out.jacobians) {
        alignas(64) float jv[9][W];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) storev(jv[c * 3 + r], J[r][c]);
        for (int l = 0; l < g.n; ++l) {
            glm::mat3& dst = out.jacobians[g.contiguous ? g.first + std::size_t(l) : g.idx[l]];
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r) dst[c][r] = jv[c * 3 + r][l];
        }
    }
    return inverted;
}

}  // namespace

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

DeformStats run_fast(const Prepared& P, const PointsIn& in, const PointsOut& out, bool sparse) {
    const bool full = (in.normals && out.normals) || (in.axis_u && out.axis_u) || (in.axis_v && out.axis_v) ||
                      out.jacobians;
    GroupFn fn;
    if (P.basis == LatticeBasis::bspline) fn = full ? bspline_group<true> : bspline_group<false>;
    else if (sparse) fn = full ? sparse_group<true> : sparse_group<false>;
    else fn = full ? pick_bernstein<true>(P.N + 1, P.coords) : pick_bernstein<false>(P.N + 1, P.coords);
    const bool nothing_moved = P.moved.empty();
    std::atomic<std::size_t> inside_total{0}, inverted_total{0};
    const float lo = float(-kInsideSlack), hi = float(1.0 + kInsideSlack);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, in.count, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
            std::size_t n_in = 0, n_inv = 0;
            Group g;
            auto flush = [&] {
                if (g.n == 0) return;
                for (int l = g.n; l < W; ++l) g.s[l] = g.s[0], g.t[l] = g.t[0], g.u[l] = g.u[0];
                fn(P, g);
                n_inv += std::size_t(finish_group(P, g, in, out, full));
                g.n = 0;
            };
            auto one = [&](std::size_t p) {
                const glm::vec3 x = in.positions[p];
                const float s = P.stu0[0] + P.minv[0] * x.x + P.minv[1] * x.y + P.minv[2] * x.z;
                const float t = P.stu0[1] + P.minv[3] * x.x + P.minv[4] * x.y + P.minv[5] * x.z;
                const float u = P.stu0[2] + P.minv[6] * x.x + P.minv[7] * x.y + P.minv[8] * x.z;
                const bool is_inside = s >= lo && s <= hi && t >= lo && t <= hi && u >= lo && u <= hi;
                n_in += is_inside;
                // Unchanged points: outside, nothing moved, or (B-spline) outside the moved points' support.
                const bool culled = !is_inside || nothing_moved ||
                                    (P.basis == LatticeBasis::bspline &&
                                     (s <= P.cull_lo[0] || s >= P.cull_hi[0] || t <= P.cull_lo[1] ||
                                      t >= P.cull_hi[1] || u <= P.cull_lo[2] || u >= P.cull_hi[2]));
                if (culled) {
                    if (out.positions != in.positions) out.positions[p] = x;
                    if (in.normals && out.normals && out.normals != in.normals)
                        out.normals[p] = in.normals[p];
                    if (in.axis_u && out.axis_u && out.axis_u != in.axis_u) out.axis_u[p] = in.axis_u[p];
                    if (in.axis_v && out.axis_v && out.axis_v != in.axis_v) out.axis_v[p] = in.axis_v[p];
                    if (out.jacobians) out.jacobians[p] = glm::mat3(1.0f);
                    return;
                }
                g.s[g.n] = std::clamp(s, 0.0f, 1.0f);
                g.t[g.n] = std::clamp(t, 0.0f, 1.0f);
                g.u[g.n] = std::clamp(u, 0.0f, 1.0f);
                g.idx[g.n] = std::uint32_t(p);
                if (++g.n == W) flush();
            };
            std::size_t p = r.begin();
            if (!nothing_moved) {
                // Whole blocks of W points that are all inside (and not culled) go straight to the kernel
                // with vector loads; mixed blocks fall back to the per-point compaction above.
                Group blk;
                blk.contiguous = true;
                blk.n = W;
                const vf lov = splat(lo), hiv = splat(hi);
                for (; p + W <= r.end(); p += W) {
                    vf x, y, z;
                    load_xyz(in.positions + p, x, y, z);
                    const vf s = P.stu0[0] + P.minv[0] * x + P.minv[1] * y + P.minv[2] * z;
                    const vf t = P.stu0[1] + P.minv[3] * x + P.minv[4] * y + P.minv[5] * z;
                    const vf u = P.stu0[2] + P.minv[6] * x + P.minv[7] * y + P.minv[8] * z;
                    auto outside = (s < lov) | (s > hiv) | (t < lov) | (t > hiv) | (u < lov) | (u > hiv);
                    if (P.basis == LatticeBasis::bspline)
                        outside |= (s <= P.cull_lo[0]) | (s >= P.cull_hi[0]) | (t <= P.cull_lo[1]) |
                                   (t >= P.cull_hi[1]) | (u <= P.cull_lo[2]) | (u >= P.cull_hi[2]);
                    bool any_out = false;
                    for (int l = 0; l < W; ++l) any_out |= outside[l] != 0;
                    if (any_out) {
                        for (int l = 0; l < W; ++l) one(p + std::size_t(l));
                        continue;
                    }
                    const vf zero = splat(0.0f), onev = splat(1.0f);
                    storev(blk.s, s < zero ? zero : (s > onev ? onev : s));
                    storev(blk.t, t < zero ? zero : (t > onev ? onev : t));
                    storev(blk.u, u < zero ? zero : (u > onev ? onev : u));
                    blk.first = p;
                    fn(P, blk);
                    n_in += W;
                    n_inv += std::size_t(finish_group(P, blk, in, out, full));
                }
            }
            for (; p != r.end(); ++p) one(p);
            flush();
            inside_total += n_in;
            inverted_total += n_inv;
        });
    return DeformStats{inside_total.load(), inverted_total.load(), Backend::fast};
}

}  // namespace sffd::ffd::detail
