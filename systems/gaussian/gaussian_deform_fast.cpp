// W Gaussians per vector, float, branch-free across lanes (compiled -O3 -ffp-contract=fast -fno-math-errno,
// like systems/ffd/deform_fast.cpp). Each step is the GPU pass's (shaders/gaussian/deform.comp), so the CPU
// and GPU paths give the same shapes and colours to float rounding; the double-precision per-Gaussian path
// in gaussian_deform.cpp (Backend::reference) stays the exact reference both are tested against.
// Per-lane decisions (converged, singular, moved) are masks and selects; the iterative steps (Jacobi
// sweeps, Newton steps) run until every lane of the vector has converged, converged lanes frozen.
//
// Compiled once per Highway target (avx3: W = 16, avx2: 8, sse4 and neon: 4, scalar: 1) and chosen at run
// time (runtime/simd/simd.h), once per deform_shapes_fast() call: everything below down to the dispatch is
// per target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/gaussian/gaussian_deform_fast.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/cache_control.h>

#include "systems/gaussian/gaussian_deform_fast.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "runtime/simd/simd.h"
#include "systems/gaussian/sh.h"

// Target-independent: compiled once, whichever target's pass comes first.
#ifndef SFFD_GAUSSIAN_DEFORM_FAST_SHARED
#define SFFD_GAUSSIAN_DEFORM_FAST_SHARED
namespace sffd::gaussian::detail {
namespace {

// sh_rotation()'s tables in float (as the GPU pass gets them): per band the sample directions and A_l⁻¹.
struct ShTables {
    float dirs[4][7][3] = {};
    float inv[4][49] = {};
    ShTables() {
        for (int l = 1; l <= 3; ++l) {
            glm::dvec3 d[7];
            double inv_d[49];
            sh_sample_tables(l, d, inv_d);
            const int n = 2 * l + 1;
            for (int j = 0; j < n; ++j)
                for (int c = 0; c < 3; ++c) dirs[l][j][c] = float(d[j][c]);
            for (int k = 0; k < n * n; ++k) inv[l][k] = float(inv_d[k]);
        }
    }
};
const ShTables& sh_tables() {
    static const ShTables t;
    return t;
}

// Where w, x, y, z lie among a glm::quat's four floats (glm's member order, whichever it is).
static_assert(std::is_standard_layout_v<glm::quat> && sizeof(glm::quat) == 4 * sizeof(float));
static_assert(sizeof(glm::vec3) == 3 * sizeof(float) && sizeof(glm::mat3) == 9 * sizeof(float));
constexpr int kQuatSlot[4] = {
    int(offsetof(glm::quat, w) / sizeof(float)), int(offsetof(glm::quat, x) / sizeof(float)),
    int(offsetof(glm::quat, y) / sizeof(float)), int(offsetof(glm::quat, z) / sizeof(float))};

// Groups ahead whose SH rows are prefetched (measured: 2 to 8 are alike, none is about 8% slower).
constexpr int kPrefetch = 4;

}  // namespace
}  // namespace sffd::gaussian::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace sffd::gaussian::detail::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

namespace {

using D = hn::ScalableTag<float>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;
using DI = hn::RebindToSigned<D>;
constexpr int W = int(hn::MaxLanes(D()));

HWY_INLINE V S(float x) { return hn::Set(D(), x); }
HWY_INLINE V sel(M m, V a, V b) { return hn::IfThenElse(m, a, b); }
HWY_INLINE M no_lanes() { return hn::MaskFromVec(hn::Zero(D())); }
// a > b ? a : b, lane by lane (b where either is NaN, as the comparison says; hn::Max need not).
HWY_INLINE V vmax(V a, V b) { return hn::IfThenElse(hn::Gt(a, b), a, b); }
// One test of the whole mask: the iterative steps ask it after every sweep.
HWY_INLINE bool any(M m) { return !hn::AllFalse(D(), m); }
// Finite on the IEEE exponent bits (as the shader): no fast-math rewrite of isfinite can remove it.
HWY_INLINE M finite(V x) {
    const DI di;
    const auto e = hn::Set(di, 0x7f800000);
    return hn::RebindMask(D(), hn::Ne(hn::And(hn::BitCast(di, x), e), e));
}
// The mask as bits, lane l in bit l, for the lanes' scalar work.
HWY_INLINE std::uint64_t lane_bits(M m) {
    std::uint8_t b[8] = {};
    hn::StoreMaskBits(D(), m, b);
    std::uint64_t bits;
    std::memcpy(&bits, b, sizeof bits);
    return bits;
}
HWY_INLINE bool lane(std::uint64_t bits, int l) { return (bits >> l) & 1u; }

// 1/sqrt(x) for finite x > 0 (normal, not denormal): an estimate and Newton steps, about 1 ulp. A
// full-precision divide or square root of a whole vector occupies its unit for several times as many cycles,
// and the iterative steps below are made of them. AVX-512's estimate has 14 bits, one step is enough; the
// others' have 12 (SSE4, AVX2) or 8 (NEON) and take two, which leave at least AVX-512's accuracy. The
// portable target divides (its estimate is a bit trick, and a one-lane divide costs no more).
HWY_INLINE V rsqrt(V x) {
#if HWY_TARGET == HWY_SCALAR || HWY_TARGET == HWY_EMU128
    return hn::Div(S(1.0f), hn::Sqrt(x));
#else
    const V half_x = S(0.5f) * x;
    V y = hn::ApproximateReciprocalSqrt(x);
    y = y * hn::NegMulAdd(half_x, y * y, S(1.5f));
#if !(HWY_TARGET <= HWY_AVX3)
    y = y * hn::NegMulAdd(half_x, y * y, S(1.5f));
#endif
    return y;
#endif
}

// Their constructors are written out: GCC (for aarch64) gives implicit ones the translation unit's target
// options instead of the target's, and then cannot inline the vectors' constructors into them.
struct V3 {
    V x, y, z;
    HWY_INLINE V3() {}
    HWY_INLINE V3(V px, V py, V pz) : x(px), y(py), z(pz) {}
};
HWY_INLINE V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
HWY_INLINE V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
HWY_INLINE V3 operator*(V s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
// s a + b
HWY_INLINE V3 mul_add(V s, V3 a, V3 b) {
    return {hn::MulAdd(s, a.x, b.x), hn::MulAdd(s, a.y, b.y), hn::MulAdd(s, a.z, b.z)};
}
HWY_INLINE V dot(V3 a, V3 b) { return hn::MulAdd(a.z, b.z, hn::MulAdd(a.y, b.y, a.x * b.x)); }
HWY_INLINE V3 cross(V3 a, V3 b) {
    return {hn::MulSub(a.y, b.z, a.z * b.y), hn::MulSub(a.z, b.x, a.x * b.z),
            hn::MulSub(a.x, b.y, a.y * b.x)};
}
HWY_INLINE V3 sel(M m, V3 a, V3 b) { return {sel(m, a.x, b.x), sel(m, a.y, b.y), sel(m, a.z, b.z)}; }
HWY_INLINE V3 splat3(float x, float y, float z) { return {S(x), S(y), S(z)}; }
HWY_INLINE V3 normalize(V3 a) { return hn::Div(S(1.0f), hn::Sqrt(dot(a, a))) * a; }
HWY_INLINE V& coord(V3& v, int r) { return r == 0 ? v.x : r == 1 ? v.y : v.z; }

struct M3 {
    V3 c[3];  // columns
    HWY_INLINE M3() {}
    HWY_INLINE M3(V3 c0, V3 c1, V3 c2) : c{c0, c1, c2} {}
};
HWY_INLINE V3 mul(const M3& m, V3 v) { return mul_add(v.z, m.c[2], mul_add(v.y, m.c[1], v.x * m.c[0])); }
HWY_INLINE M3 transpose(const M3& m) {
    return {{m.c[0].x, m.c[1].x, m.c[2].x}, {m.c[0].y, m.c[1].y, m.c[2].y}, {m.c[0].z, m.c[1].z, m.c[2].z}};
}
HWY_INLINE M3 sel(M m, const M3& a, const M3& b) {
    return {sel(m, a.c[0], b.c[0]), sel(m, a.c[1], b.c[1]), sel(m, a.c[2], b.c[2])};
}
HWY_INLINE M3 identity() { return {splat3(1, 0, 0), splat3(0, 1, 0), splat3(0, 0, 1)}; }

// One Hestenes rotation of columns p, q: makes them orthogonal where they are not yet to float precision
// (|γ| > 1e-7 sqrt(αβ), squared; columns too small to tell are left), and adds those lanes to `rotated`.
HWY_INLINE void orthogonalise(V3& bp, V3& bq, M& rotated) {
    const V alpha = dot(bp, bp), beta = dot(bq, bq), gamma = dot(bp, bq);
    const M act = hn::And(hn::Gt(gamma * gamma, S(1e-14f) * vmax(alpha * beta, S(1e-37f))),
                          hn::Ne(gamma, hn::Zero(D())));
    if (!any(act)) return;
    rotated = hn::Or(rotated, act);
    // The angle from its double: cos 2θ = |d| / r, sin 2θ = sign(d) g / r (d = β − α, g = 2γ, r = |(d, g)|,
    // |θ| ≤ π/4), then the half angle: c = sqrt((1 + cos 2θ) / 2), s = sin 2θ / (2c). Two reciprocal square
    // roots in a row where tan θ = sign(ζ) / (|ζ| + sqrt(1 + ζ²)) takes a reciprocal, a root and another
    // reciprocal; the sweeps' chain of rotations is the kernel's longest wait.
    V d = beta - alpha, g = S(2.0f) * gamma;
    V r2 = hn::MulAdd(d, d, g * g);
    // Near rsqrt()'s range both are scaled by 2^50: exact, the angle unchanged (deform.comp divides both by
    // the larger: one division is cheap there).
    const M small = hn::Lt(r2, S(1e-30f));
    if (any(small)) {
        d = sel(small, d * S(0x1p50f), d), g = sel(small, g * S(0x1p50f), g);
        r2 = hn::MulAdd(d, d, g * g);
    }
    const V rr = rsqrt(sel(act, r2, S(1.0f)));
    const V cos2 = hn::Abs(d) * rr, sin2 = sel(hn::Lt(d, hn::Zero(D())), hn::Neg(g), g) * rr;
    const V h = hn::MulAdd(S(0.5f), cos2, S(0.5f)), rh = rsqrt(h);
    V c = h * rh, s = (S(0.5f) * sin2) * rh;
    c = sel(act, c, S(1.0f));
    s = hn::IfThenElseZero(act, s);
    const V3 np = c * bp - s * bq, nq = mul_add(s, bp, c * bq);
    bp = np;
    bq = nq;
}

// Axes (a proper rotation) and scales (descending) of A Aᵀ: one-sided Jacobi on the columns b of A, a sweep
// at a time (jacobi_sweep), then decompose_finish(). Sweeps until one rotates nothing: each pair tests its
// own columns, so no separate test of all three (deform.comp tests all three first; the criterion is the
// same, |γ| ≤ 1e-7 sqrt(αβ) for every pair). Returns whether the sweep rotated anything.
HWY_INLINE bool jacobi_sweep(V3 (&b)[3]) {
    M rotated = no_lanes();
    orthogonalise(b[0], b[1], rotated);
    orthogonalise(b[0], b[2], rotated);
    orthogonalise(b[1], b[2], rotated);
    return any(rotated);
}
HWY_INLINE void decompose_finish(V3 b0, V3 b1, V3 b2, M3& axes, V3& scale) {
    V s0 = hn::Sqrt(dot(b0, b0)), s1 = hn::Sqrt(dot(b1, b1)), s2 = hn::Sqrt(dot(b2, b2));
    auto swap_if = [](M m, V3& p, V3& q, V& sp, V& sq) {
        const V3 t = p;
        p = sel(m, q, p), q = sel(m, t, q);
        const V ts = sp;
        sp = sel(m, sq, sp), sq = sel(m, ts, sq);
    };
    swap_if(hn::Gt(s1, s0), b0, b1, s0, s1);
    swap_if(hn::Gt(s2, s1), b1, b2, s1, s2);
    swap_if(hn::Gt(s1, s0), b0, b1, s0, s1);
    // Columns that vanished (relative to the largest) are completed orthogonally.
    const V tiny = S(1e-6f) * s0;
    const M pos0 = hn::Gt(s0, hn::Zero(D())), big1 = hn::Gt(s1, tiny);
    const V3 u0 = sel(pos0, hn::Div(S(1.0f), sel(pos0, s0, S(1.0f))) * b0, splat3(1, 0, 0));
    const V3 other = sel(hn::Lt(hn::Abs(u0.x), S(0.9f)), splat3(1, 0, 0), splat3(0, 1, 0));
    V3 u1 = sel(big1, hn::Div(S(1.0f), sel(big1, s1, S(1.0f))) * b1, normalize(cross(u0, other)));
    u1 = normalize(u1 - dot(u0, u1) * u0);  // re-orthogonalise the rounding away
    axes = M3(u0, u1, cross(u0, u1));       // det = +1
    scale = {s0, s1, s2};
}

// Unit quaternion (w, x, y, z), w >= 0, of a proper rotation (Shepperd: divide by the largest of four).
HWY_INLINE void to_quat(const M3& m, V q[4]) {
    const V m00 = m.c[0].x, m01 = m.c[0].y, m02 = m.c[0].z;
    const V m10 = m.c[1].x, m11 = m.c[1].y, m12 = m.c[1].z;
    const V m20 = m.c[2].x, m21 = m.c[2].y, m22 = m.c[2].z;
    const V one = S(1.0f);
    const V tr = m00 + m11 + m22;
    const M c0 = hn::Gt(tr, hn::Zero(D()));
    const M c1 = hn::AndNot(c0, hn::And(hn::Gt(m00, m11), hn::Gt(m00, m22)));
    const M c2 = hn::AndNot(hn::Or(c0, c1), hn::Gt(m11, m22));
    const V arg = sel(c0, tr + one,
                      sel(c1, one + m00 - m11 - m22, sel(c2, one + m11 - m00 - m22, one + m22 - m00 - m11)));
    const V ra = rsqrt(arg);  // arg >= 1: the largest of the four for a rotation
    const V s = S(2.0f) * (arg * ra), inv = S(0.5f) * ra, big = S(0.25f) * s;
    const V a = (m12 - m21) * inv, b = (m20 - m02) * inv, c = (m01 - m10) * inv;
    const V d = (m10 + m01) * inv, e = (m20 + m02) * inv, f = (m21 + m12) * inv;
    const V w = sel(c0, big, sel(c1, a, sel(c2, b, c)));
    const V x = sel(c0, a, sel(c1, big, sel(c2, d, e)));
    const V y = sel(c0, b, sel(c1, d, sel(c2, big, f)));
    const V z = sel(c0, c, sel(c1, e, sel(c2, f, big)));
    const V n = rsqrt(hn::MulAdd(z, z, hn::MulAdd(y, y, hn::MulAdd(x, x, w * w))));
    const V sign = sel(hn::Lt(w, hn::Zero(D())), hn::Neg(n), n);
    q[0] = w * sign, q[1] = x * sign, q[2] = y * sign, q[3] = z * sign;
}

// Orthogonal factor of J = R U where `need` (scaled Newton, Higham: the GPU's polar_rotation): x starts
// at J (I where not needed: its own fixed point), newton_step() until no lane is active, then polar_ok()
// (false where the result is not finite).
HWY_INLINE void newton_step(M3& x, M& active) {
    const V3 c0 = cross(x.c[1], x.c[2]), c1 = cross(x.c[2], x.c[0]), c2 = cross(x.c[0], x.c[1]);
    const V inv_det = hn::Div(S(1.0f), dot(x.c[0], c0));
    const M3 inv_t(inv_det * c0, inv_det * c1, inv_det * c2);  // (X⁻¹)ᵀ: cofactors / det
    const V nx = dot(x.c[0], x.c[0]) + dot(x.c[1], x.c[1]) + dot(x.c[2], x.c[2]);
    const V ni = dot(inv_t.c[0], inv_t.c[0]) + dot(inv_t.c[1], inv_t.c[1]) + dot(inv_t.c[2], inv_t.c[2]);
    const V zeta = hn::Sqrt(hn::Sqrt(hn::Div(ni, nx))), half_zeta = S(0.5f) * zeta,
            half_inv = hn::Div(S(0.5f), zeta);
    M3 next;
    V change = hn::Zero(D());
    for (int c = 0; c < 3; ++c) {
        next.c[c] = mul_add(half_zeta, x.c[c], half_inv * inv_t.c[c]);
        const V3 d = next.c[c] - x.c[c];
        change = change + dot(d, d);
    }
    x = sel(active, next, x);
    active = hn::AndNot(hn::Le(change, S(1e-13f * 3.0f)), active);
}
HWY_INLINE M polar_ok(const M3& x, M need) {
    M ok = need;
    for (int c = 0; c < 3; ++c)
        ok = hn::And(ok, hn::And(finite(x.c[c].x), hn::And(finite(x.c[c].y), finite(x.c[c].z))));
    return ok;
}

// Band l (1..3) of the 3DGS SH basis at d (systems/gaussian/sh.h: same constants and order).
HWY_INLINE void sh_band(int l, V3 d, V* y) {
    const V x = d.x, yy_ = d.y, z = d.z;
    auto k = [](double c) { return S(float(c)); };
    if (l == 1) {
        y[0] = k(-kShC1) * yy_, y[1] = k(kShC1) * z, y[2] = k(-kShC1) * x;
        return;
    }
    const V xx = x * x, yy = yy_ * yy_, zz = z * z;
    if (l == 2) {
        y[0] = k(kShC2[0]) * x * yy_;
        y[1] = k(kShC2[1]) * yy_ * z;
        y[2] = k(kShC2[2]) * (S(2.0f) * zz - xx - yy);
        y[3] = k(kShC2[3]) * x * z;
        y[4] = k(kShC2[4]) * (xx - yy);
        return;
    }
    y[0] = k(kShC3[0]) * yy_ * (S(3.0f) * xx - yy);
    y[1] = k(kShC3[1]) * x * yy_ * z;
    y[2] = k(kShC3[2]) * yy_ * (S(4.0f) * zz - xx - yy);
    y[3] = k(kShC3[3]) * z * (S(2.0f) * zz - S(3.0f) * xx - S(3.0f) * yy);
    y[4] = k(kShC3[4]) * x * (S(4.0f) * zz - xx - yy);
    y[5] = k(kShC3[5]) * z * (xx - yy);
    y[6] = k(kShC3[6]) * x * (xx - S(3.0f) * yy);
}

// Coefficients c[k] (RGB in x, y, z) of band 1..degree rotated by r: D_l c = A_l⁻¹ [f_l(rᵀ d_j)]_j.
void rotate_sh(int degree, const M3& r, V3* c) {
    const ShTables& t = sh_tables();
    const M3 rt = transpose(r);
    for (int l = 1; l <= degree; ++l) {
        const int n = 2 * l + 1, first = l * l;
        V3 v[7];
        for (int j = 0; j < n; ++j) {
            V y[7];
            sh_band(l, mul(rt, splat3(t.dirs[l][j][0], t.dirs[l][j][1], t.dirs[l][j][2])), y);
            V3 f = y[0] * c[first];
            for (int m = 1; m < n; ++m) f = mul_add(y[m], c[first + m], f);
            v[j] = f;
        }
        for (int row = 0; row < n; ++row) {
            V3 o = S(t.inv[l][row * n]) * v[0];
            for (int j = 1; j < n; ++j) o = mul_add(S(t.inv[l][row * n + j]), v[j], o);
            c[first + row] = o;  // band l's inputs are all in v[] already
        }
    }
}

// The SH coefficients of a whole group of degree-3 Gaussians (W rows of 48 floats) to lanes and back: 48 / W
// W x W transposes in registers instead of 48 W scalar moves each way. A transpose is log2(W) stages of
// unzips (ConcatEven / ConcatOdd of row pairs): each rotates the bits of (row, lane) by one place, so
// log2(W) of them swap row and lane. With AVX-512 that is one two-source permute per row and stage, with
// SSE4 and NEON one shuffle. AVX2's unzips cross its two 128-bit halves (two instructions each): its 8 x 8
// interleaves within the halves, 32- then 64-bit, and swaps halves last (measured: about 5% of the
// kernel's time faster). One lane (the portable target): nothing to move.
HWY_INLINE void transpose_square(V (&m)[W]) {
#if HWY_TARGET == HWY_AVX2
    static_assert(W == 8);
    const D d;
    const hn::Repartition<double, D> d64;
    // Rows 2i, 2i + 1 (a, b) interleaved: (a0 b0 a1 b1 | a4 b4 a5 b5), (a2 b2 a3 b3 | a6 b6 a7 b7).
    V t[8];
    for (int i = 0; i < 4; ++i) {
        t[2 * i] = hn::InterleaveLower(d, m[2 * i], m[2 * i + 1]);
        t[2 * i + 1] = hn::InterleaveUpper(d, m[2 * i], m[2 * i + 1]);
    }
    // Pairs of those, 64 bits at a time: (a0 b0 c0 d0 | a4 b4 c4 d4), (a1 b1 c1 d1 | a5 b5 c5 d5), …
    V u[8];
    for (int h = 0; h < 8; h += 4)
        for (int k = 0; k < 2; ++k) {
            const auto lo = hn::BitCast(d64, t[h + k]), hi = hn::BitCast(d64, t[h + k + 2]);
            u[h + 2 * k] = hn::BitCast(d, hn::InterleaveLower(d64, lo, hi));
            u[h + 2 * k + 1] = hn::BitCast(d, hn::InterleaveUpper(d64, lo, hi));
        }
    // Rows a-d in the lower half, e-h in the upper.
    for (int i = 0; i < 4; ++i) {
        m[i] = hn::ConcatLowerLower(d, u[i + 4], u[i]);
        m[i + 4] = hn::ConcatUpperUpper(d, u[i + 4], u[i]);
    }
#elif HWY_TARGET != HWY_SCALAR
    const D d;
#pragma GCC unroll 4
    for (int stage = 1; stage < W; stage *= 2) {
        V t[W];
#pragma GCC unroll 16
        for (int i = 0; i < W / 2; ++i) {
            t[i] = hn::ConcatEven(d, m[2 * i + 1], m[2 * i]);
            t[i + W / 2] = hn::ConcatOdd(d, m[2 * i + 1], m[2 * i]);
        }
#pragma GCC unroll 16
        for (int i = 0; i < W; ++i) m[i] = t[i];
    }
#else
    (void)m;
#endif
}
void to_lanes(const float* rows, float (&soa)[48][W]) {
    const D d;
    for (int b = 0; b < 48 / W; ++b) {
        V m[W];
#pragma GCC unroll 16
        for (int l = 0; l < W; ++l) m[l] = hn::LoadU(d, rows + l * 48 + b * W);
        transpose_square(m);
#pragma GCC unroll 16
        for (int k = 0; k < W; ++k) hn::Store(m[k], d, soa[b * W + k]);
    }
}
void to_rows(const float (&soa)[48][W], float (*rows)[48]) {
    const D d;
    for (int b = 0; b < 48 / W; ++b) {
        V m[W];
#pragma GCC unroll 16
        for (int k = 0; k < W; ++k) m[k] = hn::Load(d, soa[b * W + k]);
        transpose_square(m);
#pragma GCC unroll 16
        for (int l = 0; l < W; ++l) hn::StoreU(m[l], d, rows[l] + b * W);
    }
}
// Copies count floats from src to dst: the 64-byte lines wholly inside dst with streaming stores (no read of
// the line before it is written, and it does not push the working set out of the caches), the partial lines
// at either end with plain stores. DeformShapes() flushes the streams before it returns.
void stream_floats(const float* src, float* dst, std::size_t count) {
    const D d;
    constexpr std::size_t kLine = 64 / sizeof(float);
    constexpr std::size_t kStep = W < int(kLine) ? std::size_t(W) : kLine;
    const auto addr = reinterpret_cast<std::uintptr_t>(dst);
    std::size_t head = addr % sizeof(float) ? count : ((64 - addr % 64) % 64) / sizeof(float);
    head = std::min(head, count);
    std::memcpy(dst, src, head * sizeof(float));
    std::size_t k = head;
    for (; k + kLine <= count; k += kLine)
        for (std::size_t v = 0; v < kLine; v += kStep) hn::Stream(hn::LoadU(d, src + k + v), d, dst + k + v);
    std::memcpy(dst + k, src + k, (count - k) * sizeof(float));
}

// Lanes whose J is near-singular: polar_decomposition's rule, in double as there (W lanes of double, in
// vectors of half as many lanes, or of one on the portable target).
HWY_INLINE M near_singular(const M3& j) {
    const D d;
    const hn::ScalableTag<double> dd;
    const hn::Rebind<float, decltype(dd)> dh;  // as many floats as dd has doubles
    constexpr int kWd = int(hn::MaxLanes(dd));
    static_assert(W % kWd == 0);
    alignas(64) float e[9][W];
    for (int c = 0; c < 3; ++c) {
        hn::Store(j.c[c].x, d, e[3 * c]);
        hn::Store(j.c[c].y, d, e[3 * c + 1]);
        hn::Store(j.c[c].z, d, e[3 * c + 2]);
    }
    alignas(64) float regular[W];
    for (int h = 0; h < W; h += kWd) {
        hn::Vec<decltype(dd)> c[3][3];
        for (int k = 0; k < 3; ++k)
            for (int r = 0; r < 3; ++r) c[k][r] = hn::PromoteTo(dd, hn::LoadU(dh, &e[3 * k + r][h]));
        auto n2 = hn::Zero(dd);
        for (int k = 0; k < 3; ++k) n2 = n2 + (c[k][0] * c[k][0] + c[k][1] * c[k][1] + c[k][2] * c[k][2]);
        const auto det = c[0][0] * (c[1][1] * c[2][2] - c[2][1] * c[1][2]) -
                         c[1][0] * (c[0][1] * c[2][2] - c[2][1] * c[0][2]) +
                         c[2][0] * (c[0][1] * c[1][2] - c[1][1] * c[0][2]);
        // False where NaN, as the reference's !(… > …).
        const auto ok = hn::Gt(hn::Abs(det), hn::Set(dd, 1e-12) * n2 * hn::Sqrt(n2));
        hn::StoreU(hn::DemoteTo(dh, hn::IfThenElseZero(ok, hn::Set(dd, 1.0))), dh, regular + h);
    }
    return hn::Eq(hn::Load(d, regular), hn::Zero(d));
}

// Lanes where x is not finite, over `count` vectors of p: the largest magnitude's bits pass the largest
// finite float's.
HWY_INLINE M not_finite_any(const float (*p)[W], int count) {
    const D d;
    const DI di;
    const auto magnitude = hn::Set(di, 0x7fffffff);
    auto top = hn::Zero(di);
    for (int k = 0; k < count; ++k)
        top = hn::Max(top, hn::And(hn::BitCast(di, hn::Load(d, p[k])), magnitude));
    return hn::RebindMask(d, hn::Gt(top, hn::Set(di, 0x7f7fffff)));
}

// A whole group's centres, scales, rotations (w, x, y, z) and Jacobians into lanes and back, with
// interleaved loads and stores (vec3 and quat rows are contiguous).
HWY_INLINE V3 load_xyz(const glm::vec3* p) {
    V3 v;
    hn::LoadInterleaved3(D(), reinterpret_cast<const float*>(p), v.x, v.y, v.z);
    return v;
}
HWY_INLINE void load_quats(const glm::quat* q, V (&out)[4]) {
    V slot[4];
    hn::LoadInterleaved4(D(), reinterpret_cast<const float*>(q), slot[0], slot[1], slot[2], slot[3]);
    for (int k = 0; k < 4; ++k) out[k] = slot[kQuatSlot[k]];
}
HWY_INLINE void store_xyz(const V3& v, glm::vec3* p) {
    hn::StoreInterleaved3(v.x, v.y, v.z, D(), reinterpret_cast<float*>(p));
}
HWY_INLINE void store_quats(const V (&q)[4], glm::quat* p) {
    V slot[4];
    for (int k = 0; k < 4; ++k) slot[kQuatSlot[k]] = q[k];
    hn::StoreInterleaved4(slot[0], slot[1], slot[2], slot[3], D(), reinterpret_cast<float*>(p));
}
// W consecutive mat3: their 3W columns deinterleaved into rows (chunk s holds columns sW .. sW + W - 1, i.e.
// column 3g + c of Gaussian g), then each row's 3W entries deinterleaved by column.
HWY_INLINE M3 load_jacobians(const glm::mat3* j) {
    const D d;
    const auto* f = reinterpret_cast<const float*>(j);
    V part[3][3];  // [chunk][row]
    for (int s = 0; s < 3; ++s) hn::LoadInterleaved3(d, f + 3 * W * s, part[s][0], part[s][1], part[s][2]);
    M3 J;
    alignas(64) float row[3 * W];
    for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) hn::Store(part[s][r], d, row + s * W);
        hn::LoadInterleaved3(d, row, coord(J.c[0], r), coord(J.c[1], r), coord(J.c[2], r));
    }
    return J;
}
// A mask as W bytes 1 (true) or 0.
HWY_INLINE void store_flags(M m, std::uint8_t* out) {
    const DI di;
    const hn::Rebind<std::uint8_t, DI> d8;
    hn::StoreU(hn::DemoteTo(d8, hn::IfThenElseZero(hn::RebindMask(di, m), hn::Set(di, 1))), d8, out);
}

// One vector of Gaussians first .. first + n - 1 (n <= W). Returns the near-singular count.
std::size_t group(const FastShapeArgs& a, std::size_t first, int n) {
    const D d;
    const GaussianCloud& in = *a.in;
    GaussianCloud& out = *a.out;
    const bool copy = &out != &in;
    const int K = sh_coeffs(in.sh_degree);
    const std::size_t stride = std::size_t(K) * 3;
    const bool full = n == W;  // a whole vector: its rows move as vectors
    // J, rotation, scale per lane; padding lanes get J = I (not moved).
    M3 J;
    V q_in[4];
    V3 s_in;
    if (full) {
        J = load_jacobians(&a.jacobians[first - a.first]);
        load_quats(&in.rotations[first], q_in);
        s_in = load_xyz(&in.scales[first]);
    } else {
        alignas(64) float jl[9][W], ql[4][W], sl[3][W];
        for (int l = 0; l < W; ++l) {
            const bool real = l < n;
            const glm::mat3 j = real ? a.jacobians[first - a.first + std::size_t(l)] : glm::mat3(1.0f);
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r) jl[c * 3 + r][l] = j[c][r];
            const glm::quat q = real ? in.rotations[first + std::size_t(l)] : glm::quat(1, 0, 0, 0);
            ql[0][l] = q.w, ql[1][l] = q.x, ql[2][l] = q.y, ql[3][l] = q.z;
            const glm::vec3 s = real ? in.scales[first + std::size_t(l)] : glm::vec3(0.0f);
            sl[0][l] = s.x, sl[1][l] = s.y, sl[2][l] = s.z;
        }
        for (int c = 0; c < 3; ++c)
            J.c[c] = {hn::Load(d, jl[c * 3]), hn::Load(d, jl[c * 3 + 1]), hn::Load(d, jl[c * 3 + 2])};
        for (int k = 0; k < 4; ++k) q_in[k] = hn::Load(d, ql[k]);
        s_in = {hn::Load(d, sl[0]), hn::Load(d, sl[1]), hn::Load(d, sl[2])};
    }
    M moved = no_lanes();
    for (int c = 0; c < 3; ++c) {
        moved = hn::Or(moved, hn::Ne(J.c[c].x, S(c == 0 ? 1.0f : 0.0f)));
        moved = hn::Or(moved, hn::Ne(J.c[c].y, S(c == 1 ? 1.0f : 0.0f)));
        moved = hn::Or(moved, hn::Ne(J.c[c].z, S(c == 2 ? 1.0f : 0.0f)));
    }
    std::size_t singular_count = 0;
    // Whole groups of degree 3 move their coefficients as W x W blocks (to_lanes, to_rows). Copied to another
    // cloud, their output rows are one run, written with streaming stores: the SH are most of a Gaussian's
    // bytes, and a plain store first reads each line it fills from memory.
    const bool whole = full && stride == 48;
    const bool stream = whole && copy;
    const float* sh_in_rows = &in.sh[first * stride];
    alignas(64) float sh_rows[W][48];
    bool rotate_coeffs = false;
    std::uint64_t rows_rotated = 0;  // lanes whose sh_rows hold rotated coefficients
    // Whole groups whose coefficients pass through the lanes are checked there (finite_shape()'s tests,
    // vector at a time); the others per Gaussian at the end.
    bool checked = false;
    M not_finite = no_lanes();
    if (any(moved)) {
        // polar_decomposition's rule, in double as there: a J singular in exact arithmetic (a flattened cell)
        // has a float determinant of rounding size, far above the 1e-12 threshold.
        const M singular = hn::And(moved, near_singular(J));
        // Input rotation (normalised; a zero quaternion reads as I) times the scales: A = J R S.
        V w = q_in[0], x = q_in[1], y = q_in[2], z = q_in[3];
        const V qn2 = hn::MulAdd(z, z, hn::MulAdd(y, y, hn::MulAdd(x, x, w * w)));
        const M qok = hn::Gt(qn2, hn::Zero(d));
        const V qinv = hn::Div(S(1.0f), hn::Sqrt(sel(qok, qn2, S(1.0f))));
        w = sel(qok, w * qinv, S(1.0f)), x = hn::IfThenElseZero(qok, x * qinv);
        y = hn::IfThenElseZero(qok, y * qinv), z = hn::IfThenElseZero(qok, z * qinv);
        const V one = S(1.0f), two = S(2.0f);
        const V3 r0 = {one - two * (y * y + z * z), two * (x * y + w * z), two * (x * z - w * y)};
        const V3 r1 = {two * (x * y - w * z), one - two * (x * x + z * z), two * (y * z + w * x)};
        const V3 r2 = {two * (x * z + w * y), two * (y * z - w * x), one - two * (x * x + y * y)};
        const M3 A(mul(J, s_in.x * r0), mul(J, s_in.y * r1), mul(J, s_in.z * r2));
        // Normalised by the largest entry so that neither tiny nor huge scales under/overflow the squares.
        V m = hn::Zero(d);
        for (int c = 0; c < 3; ++c)
            m = vmax(m, vmax(hn::Abs(A.c[c].x), vmax(hn::Abs(A.c[c].y), hn::Abs(A.c[c].z))));
        const M mpos = hn::Gt(m, hn::Zero(d));
        const V minv = hn::Div(one, sel(mpos, m, one));
        // The shape's Jacobi sweeps and the colour's Newton steps are independent chains of dependent
        // operations (each rotation needs the previous one's columns): one loop runs both, so that each
        // fills the other's waiting. Same sweeps and steps, same results, as running them one after the
        // other.
        V3 b[3] = {minv * A.c[0], minv * A.c[1], minv * A.c[2]};
        const M need = hn::AndNot(singular, moved);
        M3 R = sel(need, J, identity());
        M active = need;
        bool sweeping = true, stepping = K > 1 && any(active);
        for (int it = 0; sweeping || stepping; ++it) {
            if (sweeping) sweeping = jacobi_sweep(b) && it + 1 < 12;
            if (stepping) {
                newton_step(R, active);
                stepping = it + 1 < 20 && any(active);
            }
        }
        M3 axes;
        V3 scale;
        decompose_finish(b[0], b[1], b[2], axes, scale);
        axes = sel(mpos, axes, identity());
        scale = sel(mpos, m * scale, splat3(0, 0, 0));
        V q[4];
        to_quat(axes, q);
        // What is written for each lane: the new shape where moved, else the input's.
        const V3 s_out = sel(moved, scale, s_in);
        V q_out[4];
        for (int k = 0; k < 4; ++k) q_out[k] = sel(moved, q[k], q_in[k]);

        // Colour: the polar rotation where J is regular (coefficients rotated, or the frame stored).
        const M rotated = K > 1 ? polar_ok(R, need) : no_lanes();
        if (K == 1) R = identity();
        alignas(64) float sh_soa[48][W];
        rotate_coeffs = K > 1 && !a.view_mode && any(rotated);
        if (rotate_coeffs && whole) {
            to_lanes(sh_in_rows, sh_soa);
        } else if (rotate_coeffs) {
            if (n < W) std::memset(sh_soa, 0, sizeof sh_soa);  // padding lanes: defined values
            for (int l = 0; l < n; ++l) {
                const float* src = &in.sh[(first + std::size_t(l)) * stride];
                for (std::size_t k = 0; k < stride; ++k) sh_soa[k][l] = src[k];
            }
        }
        if (rotate_coeffs) {
            // A lane's output row is its input row where nothing was rotated: both are checked.
            const M band0_bad = whole ? not_finite_any(sh_soa, 3) : no_lanes();
            // Rotated lanes need no input test: a non-finite coefficient makes its whole band non-finite.
            const M input_bad = whole && any(hn::Not(rotated)) ? not_finite_any(sh_soa + 3, 45) : no_lanes();
            V3 c[16];
            for (int k = 0; k < K; ++k)
                c[k] = {hn::Load(d, sh_soa[3 * k]), hn::Load(d, sh_soa[3 * k + 1]),
                        hn::Load(d, sh_soa[3 * k + 2])};
            rotate_sh(in.sh_degree, R, c);
            for (int k = 1; k < K; ++k) {
                hn::Store(c[k].x, d, sh_soa[3 * k]);
                hn::Store(c[k].y, d, sh_soa[3 * k + 1]);
                hn::Store(c[k].z, d, sh_soa[3 * k + 2]);
            }
            if (whole) {
                to_rows(sh_soa, sh_rows);  // every lane, the band 0 colour included
                const M rotated_bad = not_finite_any(sh_soa + 3, 45);
                // finite_shape() of what is written.
                const V q2 = hn::MulAdd(
                    q_out[0], q_out[0],
                    hn::MulAdd(q_out[3], q_out[3], hn::MulAdd(q_out[2], q_out[2], q_out[1] * q_out[1])));
                M bad =
                    hn::Or(band0_bad, hn::Or(hn::And(rotated, rotated_bad), hn::AndNot(rotated, input_bad)));
                bad =
                    hn::Or(bad, hn::Not(hn::And(finite(s_out.x), hn::And(finite(s_out.y), finite(s_out.z)))));
                bad = hn::Or(bad, hn::Not(finite(q_out[0] + q_out[1] + q_out[2] + q_out[3])));
                not_finite = hn::Or(bad, hn::Not(hn::Lt(hn::Abs(q2 - one), S(1e-3f))));
                checked = true;
            }
            rows_rotated = lane_bits(rotated);
        }
        // Whole groups store their shapes as vectors (the input's where not moved); with their SH rows
        // streamed below and no frames to write, no lane has anything left to do one at a time.
        if (full) {
            store_xyz(s_out, &out.scales[first]);
            store_quats(q_out, &out.rotations[first]);
            singular_count += std::size_t(hn::CountTrue(d, singular));
        }
        const std::uint64_t moved_bits = lane_bits(moved), singular_bits = lane_bits(singular),
                            rotated_bits = lane_bits(rotated);
        // The lanes' new shapes and polar rotations, for the lanes' scalar work below.
        alignas(64) float out_s[3][W], out_q[4][W], rl[9][W];
        hn::Store(scale.x, d, out_s[0]), hn::Store(scale.y, d, out_s[1]), hn::Store(scale.z, d, out_s[2]);
        for (int k = 0; k < 4; ++k) hn::Store(q[k], d, out_q[k]);
        for (int c = 0; c < 3; ++c)
            hn::Store(R.c[c].x, d, rl[3 * c]), hn::Store(R.c[c].y, d, rl[3 * c + 1]),
                hn::Store(R.c[c].z, d, rl[3 * c + 2]);
        for (int l = 0; l < n && !(full && stream && !a.view_mode); ++l) {
            const std::size_t i = first + std::size_t(l);
            const float* sh_in = &in.sh[i * stride];
            float* sh_out = &out.sh[i * stride];
            if (!lane(moved_bits, l)) {  // outside the lattice or not moved by it
                if (copy) {
                    if (!full) out.scales[i] = in.scales[i], out.rotations[i] = in.rotations[i];
                    if (!stream) std::copy(sh_in, sh_in + stride, sh_out);
                }
                continue;
            }
            if (!full) {
                singular_count += lane(singular_bits, l);
                out.scales[i] = glm::vec3(out_s[0][l], out_s[1][l], out_s[2][l]);
                out.rotations[i] = glm::quat(out_q[0][l], out_q[1][l], out_q[2][l], out_q[3][l]);
            }
            if (rotate_coeffs && lane(rotated_bits, l)) {
                if (stream) continue;  // the row in sh_rows is written below
                if (whole) std::memcpy(sh_out + 3, sh_rows[l] + 3, (stride - 3) * sizeof(float));
                else
                    for (std::size_t k = 3; k < stride; ++k) sh_out[k] = sh_soa[k][l];
                if (copy) std::copy(sh_in, sh_in + 3, sh_out);
                continue;
            }
            if (copy && !stream) std::copy(sh_in, sh_in + stride, sh_out);
            if (a.view_mode && lane(rotated_bits, l)) {
                glm::mat3 p;
                for (int c = 0; c < 3; ++c)
                    p[c] = glm::vec3(rl[3 * c][l], rl[3 * c + 1][l], rl[3 * c + 2][l]);
                out.sh_frames[i] = p * (a.frames_in ? in.sh_frames[i] : glm::mat3(1.0f));
            }
        }
    } else if (copy) {
        for (int l = 0; l < n; ++l) {
            const std::size_t i = first + std::size_t(l);
            out.scales[i] = in.scales[i], out.rotations[i] = in.rotations[i];
            if (!stream) std::copy(&in.sh[i * stride], &in.sh[i * stride] + stride, &out.sh[i * stride]);
        }
    }
    // The group's output rows, whole: the rotated ones from sh_rows, the others the input's.
    const float* rows_out = sh_in_rows;
    if (stream && rotate_coeffs) {
        for (int l = 0; l < W; ++l)
            if (!lane(rows_rotated, l)) std::memcpy(sh_rows[l], sh_in_rows + l * 48, 48 * sizeof(float));
        rows_out = &sh_rows[0][0];
    }
    if (stream) stream_floats(rows_out, &out.sh[first * stride], std::size_t(W) * 48);
    if (a.not_finite) {
        // J itself too, as the shader tests it: a J that is not finite can still give a finite-looking shape.
        M bad = checked ? not_finite : no_lanes();
        for (int c = 0; c < 3; ++c)
            bad =
                hn::Or(bad, hn::Not(hn::And(finite(J.c[c].x), hn::And(finite(J.c[c].y), finite(J.c[c].z)))));
        // A whole group checked in the lanes tests its centres there too and stores its W answers at once.
        if (checked && full && !a.view_mode) {
            const V3 p = load_xyz(&out.positions[first]);
            bad = hn::Or(bad, hn::Not(hn::And(finite(p.x), hn::And(finite(p.y), finite(p.z)))));
            store_flags(bad, &a.not_finite[first - a.first]);
            return singular_count;
        }
        const std::uint64_t bad_bits = lane_bits(bad);
        for (int l = 0; l < n; ++l) {
            const std::size_t i = first + std::size_t(l);
            bool drop = lane(bad_bits, l) || !finite3(out.positions[i]);
            if (!checked) {
                const float* row = stream ? rows_out + std::size_t(l) * 48 : &out.sh[i * stride];
                drop = drop || !finite_shape(out.scales[i], out.rotations[i], row, stride);
            }
            if (a.view_mode)
                for (int c = 0; c < 3; ++c) drop = drop || !finite3(out.sh_frames[i][c]);
            a.not_finite[i - a.first] = drop;
        }
    }
    return singular_count;
}

}  // namespace

std::size_t DeformShapes(const FastShapeArgs& a, std::size_t begin, std::size_t end) {
    std::size_t singular = 0;
    const std::size_t stride = std::size_t(sh_coeffs(a.in->sh_degree)) * 3;
    const float* sh = a.in->sh.data();
    const std::size_t last = a.first + end;  // one past the range's last Gaussian
    for (std::size_t b = begin; b < end; b += W) {
        // The SH rows (most of a Gaussian's bytes) of the group kPrefetch groups ahead are asked for now:
        // the hardware's stream prefetch alone leaves each group waiting for its first rows.
        const std::size_t ahead = a.first + b + std::size_t(kPrefetch * W);
        if (ahead < last) {
            const char* p = reinterpret_cast<const char*>(sh + ahead * stride);
            const std::size_t bytes = std::min<std::size_t>(W, last - ahead) * stride * sizeof(float);
            for (std::size_t o = 0; o < bytes; o += 64) hwy::Prefetch(p + o);
        }
        singular += group(a, a.first + b, int(std::min<std::size_t>(W, end - b)));
    }
    hwy::FlushStream();  // streamed rows are visible to whichever thread reads them next
    return singular;
}

int LaneWidth() { return W; }

}  // namespace sffd::gaussian::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sffd::gaussian::detail {

HWY_EXPORT(DeformShapes);
HWY_EXPORT(LaneWidth);

int shape_lane_width() {
    simd::honour_environment();
    return HWY_DYNAMIC_DISPATCH(LaneWidth)();
}

std::size_t deform_shapes_fast(const FastShapeArgs& a, std::size_t begin, std::size_t end) {
    simd::honour_environment();
    return HWY_DYNAMIC_DISPATCH(DeformShapes)(a, begin, end);
}

}  // namespace sffd::gaussian::detail
#endif  // HWY_ONCE
