// Fast float kernels, compiled once per SIMD target (Highway: avx3 16 float lanes, avx2 8, sse4 and neon 4,
// scalar 1) with -O3 -ffp-contract=fast; run_fast dispatches once per call to the best target the CPU runs
// (or the pinned one, runtime/simd/simd.h), the whole parallel loop included.
//
// Bernstein (dense): W points in the W lanes of one vector; the u-basis (and the degree below it) stays in
// registers while every control point's displacement is broadcast, and the sum is factorised
// Q[i][j] = Σ_k ΔP B_k(u), R[i] = Σ_j Q B_j(t), D = Σ_i R B_i(s), the u-derivative over the rows' forward
// differences: ~8.8k multiply-adds per point for an 11³ lattice with normals and axes. Sparse: the same
// lanes, but only moved control points are summed. B-spline: one point at a time; ΔP lives in a zero-bordered
// grid stored x,y,z,0 so the four k-neighbours of one (i,j) are 16 contiguous floats (one AVX-512 vector,
// two AVX2 or four SSE4 ones), 16 such rows per point.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/ffd/deform_fast.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/simd/simd.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"

HWY_BEFORE_NAMESPACE();
namespace sffd::ffd::detail::HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;
using DI = hn::RebindToSigned<DF>;
constexpr int W = int(HWY_LANES(float));  // points per group: the target's float lanes (1 on scalar)

constexpr int kMaxB = kMaxDivisions + 1;

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
HWY_INLINE void store_group(Group& g, const VF (&X)[3], const VF (&Fs)[3], const VF (&Ft)[3],
                            const VF (&Fu)[3]) {
    const DF d;
    for (int c = 0; c < 3; ++c) {
        hn::Store(X[c], d, g.D[c]);
        if constexpr (Full) {
            hn::Store(Fs[c], d, g.G[c * 3 + 0]);
            hn::Store(Ft[c], d, g.G[c * 3 + 1]);
            hn::Store(Fu[c], d, g.G[c * 3 + 2]);
        }
    }
}

// Local coordinates (s, t, u) = stu0 + M⁻¹ x, the same multiply-adds in the block path and the per-point
// path (a point's inside test must not depend on which of the two sees it).
template <class D>
HWY_INLINE void local_coords(D d, const Prepared& P, hn::Vec<D> x, hn::Vec<D> y, hn::Vec<D> z, hn::Vec<D>& s,
                             hn::Vec<D>& t, hn::Vec<D>& u) {
    const float* m = P.minv;
    s = hn::MulAdd(hn::Set(d, m[2]), z,
                   hn::MulAdd(hn::Set(d, m[1]), y, hn::MulAdd(hn::Set(d, m[0]), x, hn::Set(d, P.stu0[0]))));
    t = hn::MulAdd(hn::Set(d, m[5]), z,
                   hn::MulAdd(hn::Set(d, m[4]), y, hn::MulAdd(hn::Set(d, m[3]), x, hn::Set(d, P.stu0[1]))));
    u = hn::MulAdd(hn::Set(d, m[8]), z,
                   hn::MulAdd(hn::Set(d, m[7]), y, hn::MulAdd(hn::Set(d, m[6]), x, hn::Set(d, P.stu0[2]))));
}

// Bernstein basis of degree L (b[0..L]) and of degree L-1 (lower[0..L-1]), the step before it.
HWY_INLINE void bernstein_with_lower(DF d, VF s, int L, VF* b, VF* lower) {
    const VF one = hn::Set(d, 1.0f), r = hn::Sub(one, s);
    b[0] = one;
    for (int e = 1; e < L; ++e) {  // degree e-1 -> e
        b[e] = hn::Mul(s, b[e - 1]);
        for (int i = e - 1; i >= 1; --i) b[i] = hn::MulAdd(r, b[i], hn::Mul(s, b[i - 1]));
        b[0] = hn::Mul(r, b[0]);
    }
    for (int i = 0; i < L; ++i) lower[i] = b[i];
    b[L] = hn::Mul(s, b[L - 1]);
    for (int i = L - 1; i >= 1; --i) b[i] = hn::MulAdd(r, b[i], hn::Mul(s, b[i - 1]));
    b[0] = hn::Mul(r, b[0]);
}

// Bernstein basis of degree L (b[0..L]) and its derivative (db) for W parameters at once:
// dB(L,i) = L (B(L-1,i-1) - B(L-1,i)).
HWY_INLINE void bernstein(DF d, VF s, int L, VF* b, VF* db) {
    VF lower[kMaxB];
    bernstein_with_lower(d, s, L, b, lower);
    const VF fl = hn::Set(d, float(L));
    db[0] = hn::Neg(hn::Mul(fl, lower[0]));
    for (int i = 1; i < L; ++i) db[i] = hn::Mul(fl, hn::Sub(lower[i - 1], lower[i]));
    db[L] = hn::Mul(fl, lower[L - 1]);
}

// The u-derivative is summed over the rows' forward differences (du4: N (ΔP[k+1] − ΔP[k])) against the
// degree N-1 basis: dB(N,k)/du = N (B(N-1,k-1) − B(N-1,k)) regrouped, N terms a row instead of N+1.
// Only the NC coordinates that move (Prepared::coord) are summed: a twist leaves its axis's coordinate,
// a stretch the other two, and each coordinate is a third of the work.
template <int KC, int NC, bool Full>
void bernstein_group(const Prepared& P, Group& g) {
    const DF d;
    const int L = P.L, M = P.M;
    const int K = KC ? KC : P.N + 1;
    constexpr int KA = KC ? KC : kMaxB;
    VF bs[kMaxB], dbs[kMaxB], bt[kMaxB], dbt[kMaxB], bu[KA], bl[KA];
    bernstein(d, hn::Load(d, g.s), L, bs, dbs);
    bernstein(d, hn::Load(d, g.t), M, bt, dbt);
    bernstein_with_lower(d, hn::Load(d, g.u), K - 1, bu, bl);
    const VF zero = hn::Zero(d);
    VF X[NC], Fs[NC], Ft[NC], Fu[NC];
    for (int a = 0; a < NC; ++a) X[a] = Fs[a] = Ft[a] = Fu[a] = zero;
    const float* dp = P.coords == 3 ? P.dp4.data() : P.dk4.data();
    const float* du = P.du4.data();
    const std::uint8_t* nz = P.row_nonzero.data();
    for (int i = 0; i <= L; ++i) {
        VF R[NC], Rt[NC], Ru[NC];
        for (int a = 0; a < NC; ++a) R[a] = Rt[a] = Ru[a] = zero;
        for (int j = 0; j <= M; ++j) {
            const int row = i * (M + 1) + j;
            if (!nz[row]) continue;
            const float* c = dp + std::size_t(row) * K * 4;
            const float* e = du + std::size_t(row) * (K - 1) * 4;
            VF q[NC], w[NC];
            for (int a = 0; a < NC; ++a) q[a] = w[a] = zero;
#pragma GCC unroll 16
            for (int k = 0; k < K - 1; ++k)
#pragma GCC unroll 3
                for (int a = 0; a < NC; ++a) {
                    q[a] = hn::MulAdd(bu[k], hn::Set(d, c[4 * k + a]), q[a]);
                    if constexpr (Full) w[a] = hn::MulAdd(bl[k], hn::Set(d, e[4 * k + a]), w[a]);
                }
#pragma GCC unroll 3
            for (int a = 0; a < NC; ++a) q[a] = hn::MulAdd(bu[K - 1], hn::Set(d, c[4 * (K - 1) + a]), q[a]);
            for (int a = 0; a < NC; ++a) {
                R[a] = hn::MulAdd(q[a], bt[j], R[a]);
                if constexpr (Full) {
                    Rt[a] = hn::MulAdd(q[a], dbt[j], Rt[a]);
                    Ru[a] = hn::MulAdd(w[a], bt[j], Ru[a]);
                }
            }
        }
        for (int a = 0; a < NC; ++a) {
            X[a] = hn::MulAdd(R[a], bs[i], X[a]);
            if constexpr (Full) {
                Fs[a] = hn::MulAdd(R[a], dbs[i], Fs[a]);
                Ft[a] = hn::MulAdd(Rt[a], bs[i], Ft[a]);
                Fu[a] = hn::MulAdd(Ru[a], bs[i], Fu[a]);
            }
        }
    }
    // The coordinates that do not move get exact zeros.
    VF Xc[3] = {zero, zero, zero}, Fsc[3] = {zero, zero, zero}, Ftc[3] = {zero, zero, zero},
       Fuc[3] = {zero, zero, zero};
    for (int a = 0; a < NC; ++a) {
        const int c = P.coord[a];
        Xc[c] = X[a], Fsc[c] = Fs[a], Ftc[c] = Ft[a], Fuc[c] = Fu[a];
    }
    store_group<Full>(g, Xc, Fsc, Ftc, Fuc);
}

// Bernstein basis values B(L,i,s) and derivatives for the indices flagged in `need` only, from powers
// s^i and (1-s)^(L-i): O(L) per axis instead of O(L²) (what the sparse path needs).
HWY_INLINE void bernstein_some(DF d, VF s, int L, const std::uint8_t* need, const float* binom_l,
                               const float* binom_l1, VF* b, VF* db, bool full) {
    VF sp[kMaxB + 1], rp[kMaxB + 1];
    const VF one = hn::Set(d, 1.0f), r = hn::Sub(one, s), zero = hn::Zero(d);
    sp[0] = rp[0] = one;
    for (int i = 1; i <= L; ++i) sp[i] = hn::Mul(sp[i - 1], s), rp[i] = hn::Mul(rp[i - 1], r);
    const VF fl = hn::Set(d, float(L));
    for (int i = 0; i <= L; ++i) {
        if (!need[i]) continue;
        b[i] = hn::Mul(hn::Mul(hn::Set(d, binom_l[i]), sp[i]), rp[L - i]);
        if (full) {
            // dB = L (B(L-1,i-1) - B(L-1,i))
            const VF lo = i > 0 ? hn::Mul(hn::Mul(hn::Set(d, binom_l1[i - 1]), sp[i - 1]), rp[L - i]) : zero;
            const VF hi = i < L ? hn::Mul(hn::Mul(hn::Set(d, binom_l1[i]), sp[i]), rp[L - 1 - i]) : zero;
            db[i] = hn::Mul(fl, hn::Sub(lo, hi));
        }
    }
}

template <bool Full>
void sparse_group(const Prepared& P, Group& g) {
    const DF d;
    VF bs[kMaxB], dbs[kMaxB], bt[kMaxB], dbt[kMaxB], bu[kMaxB], dbu[kMaxB];
    bernstein_some(d, hn::Load(d, g.s), P.L, P.need[0].data(), P.binom[0].data(), P.binom1[0].data(), bs, dbs,
                   Full);
    bernstein_some(d, hn::Load(d, g.t), P.M, P.need[1].data(), P.binom[1].data(), P.binom1[1].data(), bt, dbt,
                   Full);
    bernstein_some(d, hn::Load(d, g.u), P.N, P.need[2].data(), P.binom[2].data(), P.binom1[2].data(), bu, dbu,
                   Full);
    // Twelve named sums, not arrays: GCC keeps arrays of three 64-byte vectors in memory here, a store of
    // every sum per moved point.
    const VF zero = hn::Zero(d);
    VF x0 = zero, x1 = zero, x2 = zero, s0 = zero, s1 = zero, s2 = zero;
    VF t0 = zero, t1 = zero, t2 = zero, u0 = zero, u1 = zero, u2 = zero;
    for (const Prepared::Moved& m : P.moved) {
        const VF st = hn::Mul(bs[m.i], bt[m.j]);
        const VF w = hn::Mul(st, bu[m.k]);
        const VF d0 = hn::Set(d, m.d[0]), d1 = hn::Set(d, m.d[1]), d2 = hn::Set(d, m.d[2]);
        x0 = hn::MulAdd(w, d0, x0), x1 = hn::MulAdd(w, d1, x1), x2 = hn::MulAdd(w, d2, x2);
        if constexpr (Full) {
            const VF ws = hn::Mul(hn::Mul(dbs[m.i], bt[m.j]), bu[m.k]);
            const VF wt = hn::Mul(hn::Mul(bs[m.i], dbt[m.j]), bu[m.k]);
            const VF wu = hn::Mul(st, dbu[m.k]);
            s0 = hn::MulAdd(ws, d0, s0), s1 = hn::MulAdd(ws, d1, s1), s2 = hn::MulAdd(ws, d2, s2);
            t0 = hn::MulAdd(wt, d0, t0), t1 = hn::MulAdd(wt, d1, t1), t2 = hn::MulAdd(wt, d2, t2);
            u0 = hn::MulAdd(wu, d0, u0), u1 = hn::MulAdd(wu, d1, u1), u2 = hn::MulAdd(wu, d2, u2);
        }
    }
    const VF X[3] = {x0, x1, x2}, Fs[3] = {s0, s1, s2}, Ft[3] = {t0, t1, t2}, Fu[3] = {u0, u1, u2};
    store_group<Full>(g, X, Fs, Ft, Fu);
}

// Cell index and the 4 weights (and, with Full, derivatives scaled by n) for W parameters at once. Along
// s and t weight k of lane l is w[k*W + l] (each is broadcast on its own); along u (PerPoint) it is
// w[l*4 + k], so one point's four u-weights are one 4-float load.
struct AxisWeights {
    alignas(64) std::int32_t c[W];
    alignas(64) float w[W * 4], dw[W * 4];
};
template <bool Full, bool PerPoint>
HWY_INLINE void bspline_axis(DF d, VF x, int n, AxisWeights& out) {
    auto store4 = [d](VF v0, VF v1, VF v2, VF v3, float* to) {
        if constexpr (PerPoint) {
            hn::StoreInterleaved4(v0, v1, v2, v3, d, to);
        } else {
            hn::Store(v0, d, to), hn::Store(v1, d, to + W), hn::Store(v2, d, to + 2 * W);
            hn::Store(v3, d, to + 3 * W);
        }
    };
    const DI di;
    const VF gx = hn::Mul(x, hn::Set(d, float(n)));
    const auto c = hn::Min(hn::ConvertTo(di, gx), hn::Set(di, n - 1));
    const VF f = hn::Sub(gx, hn::ConvertTo(d, c));
    const VF f2 = hn::Mul(f, f), f3 = hn::Mul(f2, f), r = hn::Sub(hn::Set(d, 1.0f), f);
    const VF sc = hn::Set(d, float(n)), sixth = hn::Set(d, 1.0f / 6.0f);
    hn::Store(c, di, out.c);
    const VF w0 = hn::Mul(hn::Mul(hn::Mul(r, r), r), sixth);
    const VF w1 =
        hn::Mul(hn::MulAdd(hn::Set(d, 3.0f), f3, hn::MulAdd(hn::Set(d, -6.0f), f2, hn::Set(d, 4.0f))), sixth);
    const VF w2 = hn::Mul(
        hn::MulAdd(hn::Set(d, -3.0f), f3,
                   hn::MulAdd(hn::Set(d, 3.0f), f2, hn::MulAdd(hn::Set(d, 3.0f), f, hn::Set(d, 1.0f)))),
        sixth);
    const VF w3 = hn::Mul(f3, sixth);
    store4(w0, w1, w2, w3, out.w);
    if constexpr (!Full) return;
    const VF dw0 = hn::Mul(hn::Mul(hn::Mul(hn::Set(d, -0.5f), r), r), sc);
    const VF dw1 = hn::Mul(hn::MulAdd(hn::Set(d, 1.5f), f2, hn::Mul(hn::Set(d, -2.0f), f)), sc);
    const VF dw2 = hn::Mul(hn::MulAdd(hn::Set(d, -1.5f), f2, hn::Add(f, hn::Set(d, 0.5f))), sc);
    const VF dw3 = hn::Mul(hn::Mul(hn::Set(d, 0.5f), f2), sc);
    store4(dw0, dw1, dw2, dw3, out.dw);
}

// One B-spline grid row: the 4 k-neighbours' x,y,z,0, 16 floats, as kRowVecs vectors of kRowLanes.
using DR = hn::CappedTag<float, 16>;
using VR = hn::Vec<DR>;
constexpr int kRowLanes = int(hn::MaxLanes(DR()));
constexpr int kRowVecs = 16 / kRowLanes;
static_assert(kRowLanes == 1 || kRowLanes % 4 == 0, "a row vector holds whole x,y,z,0 points, or one float");

// Lane l of row vector v holds a coordinate of neighbour (v * kRowLanes + l) / 4. Where a vector spans
// several neighbours (avx2, avx3) these table indices spread a point's four u-weights, one LoadDup128, over
// the lanes; where it holds one neighbour (sse4, neon) or one float (scalar), a broadcast does.
struct RowSpread {
    static constexpr bool kTable = kRowLanes > 4;
    using Idx = decltype(hn::SetTableIndices(DR(), static_cast<const std::int32_t*>(nullptr)));
    Idx idx[kTable ? kRowVecs : 1];
    RowSpread() {
        if constexpr (kTable) {
            alignas(64) std::int32_t lanes[kRowLanes];
            for (int v = 0; v < kRowVecs; ++v) {
                for (int l = 0; l < kRowLanes; ++l) lanes[l] = (v * kRowLanes + l) / 4 % 4;
                idx[v] = hn::SetTableIndices(DR(), lanes);
            }
        }
    }
    // The u-weight of each lane of row vector v, from the point's four weights w4.
    HWY_INLINE VR weights(const float* w4, int v) const {
        const DR d;
        if constexpr (kTable) return hn::TableLookupLanes(hn::LoadDup128(d, w4), idx[v]);
        else return hn::Set(d, w4[v * kRowLanes / 4]);
    }
};

// Folds a vector of 4-float groups to one group (lane c: the sum of the groups' lane c) and stores it.
template <class D>
HWY_INLINE void store_folded4(D d, hn::Vec<D> v, float* out4) {
#if HWY_TARGET != HWY_SCALAR  // (one-lane vectors have no halves; row_sum does not fold them)
    if constexpr (hn::MaxLanes(D()) > 4) {
        const hn::Half<D> dh;
        store_folded4(dh, hn::Add(hn::LowerHalf(dh, v), hn::UpperHalf(dh, v)), out4);
        return;
    }
#endif
    hn::StoreU(v, d, out4);
}

// out4[c] = Σ_k w4[k] row[4k + c]: the sum over the four u-neighbours of an accumulated row.
HWY_INLINE void row_sum(const VR (&row)[kRowVecs], const float* w4, const RowSpread& spread, float* out4) {
    const DR d;
    if constexpr (kRowLanes >= 4) {
        VR sum = hn::Mul(row[0], spread.weights(w4, 0));
        for (int v = 1; v < kRowVecs; ++v) sum = hn::MulAdd(row[v], spread.weights(w4, v), sum);
        store_folded4(d, sum, out4);
    } else {  // one float a vector: row[4k + c]
        for (int c = 0; c < 4; ++c) {
            VR sum = hn::Mul(row[c], hn::Set(d, w4[0]));
            for (int k = 1; k < 4; ++k) sum = hn::MulAdd(row[4 * k + c], hn::Set(d, w4[k]), sum);
            out4[c] = hn::GetLane(sum);
        }
    }
}

template <bool Full>
void bspline_group(const Prepared& P, Group& g) {
    const DF d;
    const DR dr;
    const int PM = P.M + 3, PK = P.N + 3;
    AxisWeights as, at, au;
    bspline_axis<Full, false>(d, hn::Load(d, g.s), P.L, as);
    bspline_axis<Full, false>(d, hn::Load(d, g.t), P.M, at);
    bspline_axis<Full, true>(d, hn::Load(d, g.u), P.N, au);
    const RowSpread spread;
    const VR zero = hn::Zero(dr);
    for (int lane = 0; lane < g.n; ++lane) {
        const int ci = as.c[lane], cj = at.c[lane], ck = au.c[lane];
        // Weight k along s or t of this lane (the derivatives' only with Full: not stored otherwise).
        auto ws = [&](int k) { return as.w[k * W + lane]; };
        auto wt = [&](int k) { return at.w[k * W + lane]; };
        auto dws = [&](int k) { return as.dw[k * W + lane]; };
        auto dwt = [&](int k) { return at.dw[k * W + lane]; };
        // Padded index = index + 1, so neighbour c-1 of cell c sits at padded c.
        const float* base = P.grid.data() + ((std::size_t(ci) * PM + cj) * PK + ck) * 4;
        auto row = [&](int a, int b, int v) {
            return hn::LoadU(dr, base + (std::size_t(a) * PM + b) * PK * 4 + v * kRowLanes);
        };
        VR x16[kRowVecs], s16[kRowVecs], t16[kRowVecs];
        if constexpr (kRowVecs == 1) {
            // A row is one vector: sum over a (s) first into one accumulator per b (t), then combine: 16
            // multiply-adds per point for positions, 32 with derivatives.
            VR acc[4] = {zero, zero, zero, zero}, accs[4] = {zero, zero, zero, zero};
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) {
                    const VR v = row(a, b, 0);
                    acc[b] = hn::MulAdd(v, hn::Set(dr, ws(a)), acc[b]);
                    if constexpr (Full) accs[b] = hn::MulAdd(v, hn::Set(dr, dws(a)), accs[b]);
                }
            auto along_t = [&](const VR(&v)[4], auto w) {
                VR sum = hn::Mul(v[0], hn::Set(dr, w(0)));
                for (int b = 1; b < 4; ++b) sum = hn::MulAdd(v[b], hn::Set(dr, w(b)), sum);
                return sum;
            };
            x16[0] = along_t(acc, wt);
            if constexpr (Full) s16[0] = along_t(accs, wt), t16[0] = along_t(acc, dwt);
        } else {
            // A row is several vectors (AVX2: 16 registers): three accumulators with combined weights.
            for (int v = 0; v < kRowVecs; ++v) x16[v] = s16[v] = t16[v] = zero;
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) {
                    const VR w = hn::Set(dr, ws(a) * wt(b));
                    for (int v = 0; v < kRowVecs; ++v) {
                        const VR dv = row(a, b, v);
                        x16[v] = hn::MulAdd(dv, w, x16[v]);
                        if constexpr (Full) {
                            s16[v] = hn::MulAdd(dv, hn::Set(dr, dws(a) * wt(b)), s16[v]);
                            t16[v] = hn::MulAdd(dv, hn::Set(dr, ws(a) * dwt(b)), t16[v]);
                        }
                    }
                }
        }
        alignas(16) float x[4];
        row_sum(x16, au.w + lane * 4, spread, x);
        for (int c = 0; c < 3; ++c) g.D[c][lane] = x[c];
        if constexpr (Full) {
            alignas(16) float xs[4], xt[4], xu[4];
            row_sum(s16, au.w + lane * 4, spread, xs);
            row_sum(t16, au.w + lane * 4, spread, xt);
            row_sum(x16, au.dw + lane * 4, spread, xu);
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

// Writes one group back: X' = X + D, J = I + G M⁻¹, n' = cof(J) n / |.|, axes J a (D and G first scaled by
// the points' weights when there are any). Returns inverted count.
int finish_group(const Prepared& P, Group& g, const PointsIn& in, const PointsOut& out, bool full) {
    const DF d;
    const bool want_n = in.normals && out.normals, want_u = in.axis_u && out.axis_u,
               want_v = in.axis_v && out.axis_v;
    alignas(64) float nx[W], ny[W], nz[W];
    auto gather = [&](const glm::vec3* src, VF& x, VF& y, VF& z) {
        if (g.contiguous)
            return hn::LoadInterleaved3(d, reinterpret_cast<const float*>(src + g.first), x, y, z);
        for (int l = 0; l < W; ++l) {
            const glm::vec3 v = src[g.idx[l < g.n ? l : 0]];
            nx[l] = v.x, ny[l] = v.y, nz[l] = v.z;
        }
        x = hn::Load(d, nx), y = hn::Load(d, ny), z = hn::Load(d, nz);
    };
    auto scatter = [&](glm::vec3* dst, VF x, VF y, VF z) {
        if (g.contiguous) return hn::StoreInterleaved3(x, y, z, d, reinterpret_cast<float*>(dst + g.first));
        hn::Store(x, d, nx), hn::Store(y, d, ny), hn::Store(z, d, nz);
        for (int l = 0; l < g.n; ++l) dst[g.idx[l]] = glm::vec3(nx[l], ny[l], nz[l]);
    };
    if (in.weights) {
        // Weighted points (PointsIn::weights): D and its derivatives G scaled by w, so X' = X + w D and
        // J_w = I + w G M⁻¹ = I + w (J - I); w = 1 leaves both bit for bit as the unweighted code has them.
        VF w;
        if (g.contiguous) w = hn::LoadU(d, in.weights + g.first);
        else {
            for (int l = 0; l < W; ++l) nx[l] = in.weights[g.idx[l < g.n ? l : 0]];
            w = hn::Load(d, nx);
        }
        for (int c = 0; c < 3; ++c) hn::Store(hn::Mul(hn::Load(d, g.D[c]), w), d, g.D[c]);
        if (full)
            for (int k = 0; k < 9; ++k) hn::Store(hn::Mul(hn::Load(d, g.G[k]), w), d, g.G[k]);
    }
    VF px, py, pz;
    gather(in.positions, px, py, pz);
    scatter(out.positions, hn::Add(px, hn::Load(d, g.D[0])), hn::Add(py, hn::Load(d, g.D[1])),
            hn::Add(pz, hn::Load(d, g.D[2])));
    if (!full) return 0;
    // J[r][c] (row r, column c) = δ + Σ_a G[r][a] M⁻¹[a][c]
    VF J[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            VF v = hn::Set(d, r == c ? 1.0f : 0.0f);
            for (int a = 0; a < 3; ++a)
                v = hn::MulAdd(hn::Load(d, g.G[r * 3 + a]), hn::Set(d, P.minv[a * 3 + c]), v);
            J[r][c] = v;
        }
    // Columns a, b, c of J; cofactor columns b×c, c×a, a×b.
    const VF ax = J[0][0], ay = J[1][0], az = J[2][0];
    const VF bx = J[0][1], by = J[1][1], bz = J[2][1];
    const VF cx = J[0][2], cy = J[1][2], cz = J[2][2];
    auto cross = [](VF p, VF q, VF r, VF s) { return hn::MulSub(p, q, hn::Mul(r, s)); };  // p q − r s
    const VF bcx = cross(by, cz, bz, cy), bcy = cross(bz, cx, bx, cz), bcz = cross(bx, cy, by, cx);
    const VF det = hn::MulAdd(az, bcz, hn::MulAdd(ay, bcy, hn::Mul(ax, bcx)));
    const int inverted =
        int(hn::CountTrue(d, hn::And(hn::Lt(det, hn::Zero(d)), hn::FirstN(d, std::size_t(g.n)))));
    if (want_n) {
        const VF cax = cross(cy, az, cz, ay), cay = cross(cz, ax, cx, az), caz = cross(cx, ay, cy, ax);
        const VF abx = cross(ay, bz, az, by), aby = cross(az, bx, ax, bz), abz = cross(ax, by, ay, bx);
        VF n0, n1, n2;
        gather(in.normals, n0, n1, n2);
        const VF ox = hn::MulAdd(abx, n2, hn::MulAdd(cax, n1, hn::Mul(bcx, n0)));
        const VF oy = hn::MulAdd(aby, n2, hn::MulAdd(cay, n1, hn::Mul(bcy, n0)));
        const VF oz = hn::MulAdd(abz, n2, hn::MulAdd(caz, n1, hn::Mul(bcz, n0)));
        const VF len2 = hn::MulAdd(oz, oz, hn::MulAdd(oy, oy, hn::Mul(ox, ox)));
        // A zero (or NaN) length leaves the cofactor product as it is, as the reference does.
        const VF one = hn::Set(d, 1.0f);
        const VF inv = hn::IfThenElse(hn::Gt(len2, hn::Zero(d)), hn::Div(one, hn::Sqrt(len2)), one);
        scatter(out.normals, hn::Mul(ox, inv), hn::Mul(oy, inv), hn::Mul(oz, inv));
    }
    auto axis = [&](const glm::vec3* src, glm::vec3* dst) {
        VF v0, v1, v2;
        gather(src, v0, v1, v2);
        scatter(dst, hn::MulAdd(cx, v2, hn::MulAdd(bx, v1, hn::Mul(ax, v0))),
                hn::MulAdd(cy, v2, hn::MulAdd(by, v1, hn::Mul(ay, v0))),
                hn::MulAdd(cz, v2, hn::MulAdd(bz, v1, hn::Mul(az, v0))));
    };
    if (want_u) axis(in.axis_u, out.axis_u);
    if (want_v) axis(in.axis_v, out.axis_v);
    if (out.jacobians) {
        alignas(64) float jv[9][W];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) hn::Store(J[r][c], d, jv[c * 3 + r]);
        for (int l = 0; l < g.n; ++l) {
            glm::mat3& dst = out.jacobians[g.contiguous ? g.first + std::size_t(l) : g.idx[l]];
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r) dst[c][r] = jv[c * 3 + r][l];
        }
    }
    return inverted;
}

}  // namespace

DeformStats RunFast(const Prepared& P, const PointsIn& in, const PointsOut& out, bool sparse) {
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
                if constexpr (W > 1)  // the unused lanes compute the first point again
                    for (int l = g.n; l < W; ++l) g.s[l] = g.s[0], g.t[l] = g.t[0], g.u[l] = g.u[0];
                fn(P, g);
                n_inv += std::size_t(finish_group(P, g, in, out, full));
                g.n = 0;
            };
            // One point through one lane: the block path's arithmetic, so both decide alike. NaN coordinates
            // fail every comparison: outside, unchanged (as in the reference).
            auto one = [&](std::size_t p) {
                const hn::CappedTag<float, 1> d1;
                const glm::vec3 x = in.positions[p];
                hn::Vec<decltype(d1)> sv, tv, uv;
                local_coords(d1, P, hn::Set(d1, x.x), hn::Set(d1, x.y), hn::Set(d1, x.z), sv, tv, uv);
                const float s = hn::GetLane(sv), t = hn::GetLane(tv), u = hn::GetLane(uv);
                const bool is_inside = s >= lo && s <= hi && t >= lo && t <= hi && u >= lo && u <= hi;
                n_in += is_inside;
                // Unchanged points: outside, nothing moved, or (B-spline) outside the moved points' support.
                // A weight of 0 (or NaN: it fails the comparison) is a point at rest too.
                const bool culled = !is_inside || nothing_moved || (in.weights && !(in.weights[p] > 0.0f)) ||
                                    (P.basis == LatticeBasis::bspline &&
                                     !(s > P.cull_lo[0] && s < P.cull_hi[0] && t > P.cull_lo[1] &&
                                       t < P.cull_hi[1] && u > P.cull_lo[2] && u < P.cull_hi[2]));
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
                // with vector loads; mixed blocks, and blocks with a NaN coordinate (which fails every
                // comparison, so `keep` is false there), fall back to the per-point compaction above.
                const DF d;
                Group blk;
                blk.contiguous = true;
                blk.n = W;
                const VF lov = hn::Set(d, lo), hiv = hn::Set(d, hi), zero = hn::Zero(d),
                         onev = hn::Set(d, 1.0f);
                auto within = [&](VF v, VF a, VF b) { return hn::And(hn::Ge(v, a), hn::Le(v, b)); };
                auto strictly_within = [&](VF v, float a, float b) {
                    return hn::And(hn::Gt(v, hn::Set(d, a)), hn::Lt(v, hn::Set(d, b)));
                };
                for (; p + W <= r.end(); p += W) {
                    VF x, y, z, s, t, u;
                    hn::LoadInterleaved3(d, reinterpret_cast<const float*>(in.positions + p), x, y, z);
                    local_coords(d, P, x, y, z, s, t, u);
                    auto keep =
                        hn::And(within(s, lov, hiv), hn::And(within(t, lov, hiv), within(u, lov, hiv)));
                    if (P.basis == LatticeBasis::bspline)
                        keep =
                            hn::And(keep, hn::And(strictly_within(s, P.cull_lo[0], P.cull_hi[0]),
                                                  hn::And(strictly_within(t, P.cull_lo[1], P.cull_hi[1]),
                                                          strictly_within(u, P.cull_lo[2], P.cull_hi[2]))));
                    if (in.weights) keep = hn::And(keep, hn::Gt(hn::LoadU(d, in.weights + p), zero));
                    if (!hn::AllTrue(d, keep)) {
                        for (int l = 0; l < W; ++l) one(p + std::size_t(l));
                        continue;
                    }
                    hn::Store(hn::Min(hn::Max(s, zero), onev), d, blk.s);
                    hn::Store(hn::Min(hn::Max(t, zero), onev), d, blk.t);
                    hn::Store(hn::Min(hn::Max(u, zero), onev), d, blk.u);
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

}  // namespace sffd::ffd::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

namespace sffd::ffd::detail {

HWY_EXPORT(RunFast);

DeformStats run_fast(const Prepared& P, const PointsIn& in, const PointsOut& out, bool sparse) {
    simd::honour_environment();
    return HWY_DYNAMIC_DISPATCH(RunFast)(P, in, out, sparse);
}

}  // namespace sffd::ffd::detail

#endif  // HWY_ONCE
