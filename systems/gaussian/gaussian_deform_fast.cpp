// W Gaussians per vector, float, branch-free across lanes (compiled -O3 -ffp-contract=fast -fno-math-errno,
// like systems/ffd/deform_fast.cpp). Each step is the GPU pass's (shaders/gaussian/deform.comp), so the CPU
// and GPU paths give the same shapes and colours to float rounding; the double-precision per-Gaussian path
// in gaussian_deform.cpp (Backend::reference) stays the exact reference both are tested against.
// Per-lane decisions (converged, singular, moved) are masks and selects; the iterative steps (Jacobi
// sweeps, Newton steps) run until every lane of the vector has converged, converged lanes frozen.
#include "systems/gaussian/gaussian_deform_fast.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "systems/gaussian/sh.h"

namespace sffd::gaussian::detail {

namespace {

#if defined(__AVX512F__)
constexpr int W = 16;
#elif defined(__AVX__)
constexpr int W = 8;
#else
constexpr int W = 4;
#endif
typedef float vf __attribute__((vector_size(W * sizeof(float))));
typedef int vm __attribute__((vector_size(W * sizeof(int))));  // lane masks: -1 true, 0 false

inline vf splat(float x) { return vf{} + x; }
inline vf sel(vm m, vf a, vf b) { return m ? a : b; }
// Lane loops the vectoriser turns into single instructions (no errno with -fno-math-errno).
inline vf vsqrt(vf x) {
    for (int l = 0; l < W; ++l) x[l] = std::sqrt(x[l]);
    return x;
}
inline vf vabs(vf x) {
    for (int l = 0; l < W; ++l) x[l] = std::fabs(x[l]);
    return x;
}
inline vf vmax(vf a, vf b) { return a > b ? a : b; }
// 1/sqrt(x) and 1/x for finite x > 0 (normal, not denormal): the 14-bit estimate and one Newton step,
// about 1 ulp. A full-precision divide or square root of 16 lanes occupies its unit for several times as
// many cycles, and the iterative steps below are made of them.
#if defined(__AVX512F__)
inline vf rsqrt(vf x) {
    const vf y = (vf)_mm512_maskz_rsqrt14_ps(0xffff, (__m512)x);
    return y * (1.5f - (0.5f * x) * (y * y));
}
inline vf rcp(vf x) {
    const vf y = (vf)_mm512_maskz_rcp14_ps(0xffff, (__m512)x);
    return y + y * (1.0f - x * y);
}
#else
inline vf rsqrt(vf x) { return 1.0f / vsqrt(x); }
inline vf rcp(vf x) { return 1.0f / x; }
#endif
// One test of the whole mask: the iterative steps ask it after every sweep, and a loop over the lanes
// compiles to a compare and branch per lane.
inline bool any(vm m) {
#if defined(__AVX512F__)
    return _mm512_test_epi32_mask((__m512i)m, (__m512i)m) != 0;
#else
    for (int l = 0; l < W; ++l)
        if (m[l]) return true;
    return false;
#endif
}
// Finite on the IEEE exponent bits (as the shader): no fast-math rewrite of isfinite can remove it.
inline vm finite(vf x) { return ((vm)x & 0x7f800000) != 0x7f800000; }

struct V3 {
    vf x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(vf s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline vf dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline V3 sel(vm m, V3 a, V3 b) { return {sel(m, a.x, b.x), sel(m, a.y, b.y), sel(m, a.z, b.z)}; }
inline V3 splat3(float x, float y, float z) { return {splat(x), splat(y), splat(z)}; }
inline V3 normalize(V3 a) { return (1.0f / vsqrt(dot(a, a))) * a; }

struct M3 {
    V3 c[3];  // columns
};
inline V3 mul(const M3& m, V3 v) { return v.x * m.c[0] + v.y * m.c[1] + v.z * m.c[2]; }
inline M3 transpose(const M3& m) {
    return {{{m.c[0].x, m.c[1].x, m.c[2].x}, {m.c[0].y, m.c[1].y, m.c[2].y}, {m.c[0].z, m.c[1].z, m.c[2].z}}};
}
inline M3 sel(vm m, const M3& a, const M3& b) {
    return {{sel(m, a.c[0], b.c[0]), sel(m, a.c[1], b.c[1]), sel(m, a.c[2], b.c[2])}};
}
inline M3 identity() { return {{splat3(1, 0, 0), splat3(0, 1, 0), splat3(0, 0, 1)}}; }

// One Hestenes rotation of columns p, q: makes them orthogonal where they are not yet to float precision
// (|γ| > 1e-7 sqrt(αβ), squared; columns too small to tell are left), and adds those lanes to `rotated`.
inline void orthogonalise(V3& bp, V3& bq, vm& rotated) {
    const vf alpha = dot(bp, bp), beta = dot(bq, bq), gamma = dot(bp, bq);
    const vm act = (gamma * gamma > 1e-14f * vmax(alpha * beta, splat(1e-37f))) & (gamma != 0.0f);
    if (!any(act)) return;
    rotated |= act;
    // The angle from its double: cos 2θ = |d| / r, sin 2θ = sign(d) g / r (d = β − α, g = 2γ, r = |(d, g)|,
    // |θ| ≤ π/4), then the half angle: c = sqrt((1 + cos 2θ) / 2), s = sin 2θ / (2c). Two reciprocal square
    // roots in a row where tan θ = sign(ζ) / (|ζ| + sqrt(1 + ζ²)) takes a reciprocal, a root and another
    // reciprocal; the sweeps' chain of rotations is the kernel's longest wait.
    vf d = beta - alpha, g = 2.0f * gamma;
    vf r2 = d * d + g * g;
    // Near rsqrt()'s range both are scaled by 2^50: exact, the angle unchanged (deform.comp divides both by
    // the larger: one division is cheap there).
    const vm small = r2 < 1e-30f;
    if (any(small)) {
        d = sel(small, d * 0x1p50f, d), g = sel(small, g * 0x1p50f, g);
        r2 = d * d + g * g;
    }
    const vf rr = rsqrt(sel(act, r2, splat(1.0f)));
    const vf cos2 = vabs(d) * rr, sin2 = sel(d < 0.0f, -g, g) * rr;
    const vf h = 0.5f + 0.5f * cos2, rh = rsqrt(h);
    vf c = h * rh, s = (0.5f * sin2) * rh;
    c = sel(act, c, splat(1.0f));
    s = sel(act, s, splat(0.0f));
    const V3 np = c * bp - s * bq, nq = s * bp + c * bq;
    bp = np;
    bq = nq;
}

// Axes (a proper rotation) and scales (descending) of A Aᵀ: one-sided Jacobi on the columns b of A, a sweep
// at a time (jacobi_sweep), then decompose_finish(). Sweeps until one rotates nothing: each pair tests its
// own columns, so no separate test of all three (deform.comp tests all three first; the criterion is the
// same, |γ| ≤ 1e-7 sqrt(αβ) for every pair). Returns whether the sweep rotated anything.
inline bool jacobi_sweep(V3 (&b)[3]) {
    vm rotated = vm{};
    orthogonalise(b[0], b[1], rotated);
    orthogonalise(b[0], b[2], rotated);
    orthogonalise(b[1], b[2], rotated);
    return any(rotated);
}
inline void decompose_finish(V3 b0, V3 b1, V3 b2, M3& axes, V3& scale) {
    vf s0 = vsqrt(dot(b0, b0)), s1 = vsqrt(dot(b1, b1)), s2 = vsqrt(dot(b2, b2));
    auto swap_if = [](vm m, V3& p, V3& q, vf& sp, vf& sq) {
        const V3 t = p;
        p = sel(m, q, p), q = sel(m, t, q);
        const vf ts = sp;
        sp = sel(m, sq, sp), sq = sel(m, ts, sq);
    };
    swap_if(s1 > s0, b0, b1, s0, s1);
    swap_if(s2 > s1, b1, b2, s1, s2);
    swap_if(s1 > s0, b0, b1, s0, s1);
    // Columns that vanished (relative to the largest) are completed orthogonally.
    const vf tiny = 1e-6f * s0;
    const vm pos0 = s0 > 0.0f, big1 = s1 > tiny;
    const V3 u0 = sel(pos0, (1.0f / sel(pos0, s0, splat(1.0f))) * b0, splat3(1, 0, 0));
    const V3 other = sel(vabs(u0.x) < 0.9f, splat3(1, 0, 0), splat3(0, 1, 0));
    V3 u1 = sel(big1, (1.0f / sel(big1, s1, splat(1.0f))) * b1, normalize(cross(u0, other)));
    u1 = normalize(u1 - dot(u0, u1) * u0);  // re-orthogonalise the rounding away
    axes = {{u0, u1, cross(u0, u1)}};       // det = +1
    scale = {s0, s1, s2};
}

// Unit quaternion (w, x, y, z), w >= 0, of a proper rotation (Shepperd: divide by the largest of four).
void to_quat(const M3& m, vf q[4]) {
    const vf m00 = m.c[0].x, m01 = m.c[0].y, m02 = m.c[0].z;
    const vf m10 = m.c[1].x, m11 = m.c[1].y, m12 = m.c[1].z;
    const vf m20 = m.c[2].x, m21 = m.c[2].y, m22 = m.c[2].z;
    const vf tr = m00 + m11 + m22;
    const vm c0 = tr > 0.0f;
    const vm c1 = ~c0 & (m00 > m11) & (m00 > m22);
    const vm c2 = ~c0 & ~c1 & (m11 > m22);
    const vf arg =
        sel(c0, tr + 1.0f,
            sel(c1, 1.0f + m00 - m11 - m22, sel(c2, 1.0f + m11 - m00 - m22, 1.0f + m22 - m00 - m11)));
    const vf ra = rsqrt(arg);  // arg >= 1: the largest of the four for a rotation
    const vf s = 2.0f * (arg * ra), inv = 0.5f * ra, big = 0.25f * s;
    const vf a = (m12 - m21) * inv, b = (m20 - m02) * inv, c = (m01 - m10) * inv;
    const vf d = (m10 + m01) * inv, e = (m20 + m02) * inv, f = (m21 + m12) * inv;
    vf w = sel(c0, big, sel(c1, a, sel(c2, b, c)));
    vf x = sel(c0, a, sel(c1, big, sel(c2, d, e)));
    vf y = sel(c0, b, sel(c1, d, sel(c2, big, f)));
    vf z = sel(c0, c, sel(c1, e, sel(c2, f, big)));
    const vf n = rsqrt(w * w + x * x + y * y + z * z);
    const vf sign = sel(w < 0.0f, -n, n);
    q[0] = w * sign, q[1] = x * sign, q[2] = y * sign, q[3] = z * sign;
}

// Orthogonal factor of J = R U where `need` (scaled Newton, Higham: the GPU's polar_rotation): x starts
// at J (I where not needed: its own fixed point), newton_step() until no lane is active, then polar_ok()
// (false where the result is not finite).
inline void newton_step(M3& x, vm& active) {
    const V3 c0 = cross(x.c[1], x.c[2]), c1 = cross(x.c[2], x.c[0]), c2 = cross(x.c[0], x.c[1]);
    const vf inv_det = 1.0f / dot(x.c[0], c0);
    const M3 inv_t = {{inv_det * c0, inv_det * c1, inv_det * c2}};  // (X⁻¹)ᵀ: cofactors / det
    const vf nx = dot(x.c[0], x.c[0]) + dot(x.c[1], x.c[1]) + dot(x.c[2], x.c[2]);
    const vf ni = dot(inv_t.c[0], inv_t.c[0]) + dot(inv_t.c[1], inv_t.c[1]) + dot(inv_t.c[2], inv_t.c[2]);
    const vf zeta = vsqrt(vsqrt(ni / nx)), half_zeta = 0.5f * zeta, half_inv = 0.5f / zeta;
    M3 next;
    vf change = splat(0.0f);
    for (int c = 0; c < 3; ++c) {
        next.c[c] = half_zeta * x.c[c] + half_inv * inv_t.c[c];
        const V3 d = next.c[c] - x.c[c];
        change += dot(d, d);
    }
    x = sel(active, next, x);
    active &= ~(change <= 1e-13f * 3.0f);
}
inline vm polar_ok(const M3& x, vm need) {
    vm ok = need;
    for (int c = 0; c < 3; ++c) ok &= finite(x.c[c].x) & finite(x.c[c].y) & finite(x.c[c].z);
    return ok;
}

// Band l (1..3) of the 3DGS SH basis at d (systems/gaussian/sh.h: same constants and order).
inline void sh_band(int l, V3 d, vf* y) {
    const vf x = d.x, yy_ = d.y, z = d.z;
    if (l == 1) {
        y[0] = float(-kShC1) * yy_, y[1] = float(kShC1) * z, y[2] = float(-kShC1) * x;
        return;
    }
    const vf xx = x * x, yy = yy_ * yy_, zz = z * z;
    if (l == 2) {
        y[0] = float(kShC2[0]) * x * yy_;
        y[1] = float(kShC2[1]) * yy_ * z;
        y[2] = float(kShC2[2]) * (2.0f * zz - xx - yy);
        y[3] = float(kShC2[3]) * x * z;
        y[4] = float(kShC2[4]) * (xx - yy);
        return;
    }
    y[0] = float(kShC3[0]) * yy_ * (3.0f * xx - yy);
    y[1] = float(kShC3[1]) * x * yy_ * z;
    y[2] = float(kShC3[2]) * yy_ * (4.0f * zz - xx - yy);
    y[3] = float(kShC3[3]) * z * (2.0f * zz - 3.0f * xx - 3.0f * yy);
    y[4] = float(kShC3[4]) * x * (4.0f * zz - xx - yy);
    y[5] = float(kShC3[5]) * z * (xx - yy);
    y[6] = float(kShC3[6]) * x * (xx - 3.0f * yy);
}

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

// Coefficients c[k] (RGB in x, y, z) of band 1..degree rotated by r: D_l c = A_l⁻¹ [f_l(rᵀ d_j)]_j.
void rotate_sh(int degree, const M3& r, V3* c) {
    const ShTables& t = sh_tables();
    const M3 rt = transpose(r);
    for (int l = 1; l <= degree; ++l) {
        const int n = 2 * l + 1, first = l * l;
        V3 v[7];
        for (int j = 0; j < n; ++j) {
            vf y[7];
            sh_band(l, mul(rt, splat3(t.dirs[l][j][0], t.dirs[l][j][1], t.dirs[l][j][2])), y);
            V3 f = y[0] * c[first];
            for (int m = 1; m < n; ++m) f = f + y[m] * c[first + m];
            v[j] = f;
        }
        for (int row = 0; row < n; ++row) {
            V3 o = splat(t.inv[l][row * n]) * v[0];
            for (int j = 1; j < n; ++j) o = o + splat(t.inv[l][row * n + j]) * v[j];
            c[first + row] = o;  // band l's inputs are all in v[] already
        }
    }
}

// The SH coefficients of a whole group of degree-3 Gaussians (16 rows of 48 floats) to lanes and back:
// three 16x16 transposes in registers instead of 768 scalar moves each way.
#if defined(__AVX512F__)
constexpr bool kTransposeBlocks = true;
// Stage s swaps bit s between row and lane index: rows i and i + s exchange their off-diagonal s-blocks.
struct TransposeIndex {
    alignas(64) int lo[4][16], hi[4][16];
    constexpr TransposeIndex() : lo{}, hi{} {
        for (int stage = 0; stage < 4; ++stage) {
            const int s = 1 << stage;
            for (int l = 0; l < 16; ++l) {
                lo[stage][l] = (l & s) ? l - s + 16 : l;  // row i: its own lanes, row i + s's lanes - s
                hi[stage][l] = (l & s) ? l + 16 : l + s;  // row i + s: row i's lanes + s, its own lanes
            }
        }
    }
};
constexpr TransposeIndex kTranspose;
__attribute__((always_inline)) inline void transpose16(__m512 m[16]) {
#pragma GCC unroll 4
    for (int stage = 0; stage < 4; ++stage) {
        const int s = 1 << stage;
        const __m512i lo = _mm512_load_si512(kTranspose.lo[stage]),
                      hi = _mm512_load_si512(kTranspose.hi[stage]);
#pragma GCC unroll 16
        for (int i = 0; i < 16; ++i) {
            if (i & s) continue;
            const __m512 a = m[i], b = m[i + s];
            m[i] = _mm512_permutex2var_ps(a, lo, b);
            m[i + s] = _mm512_permutex2var_ps(a, hi, b);
        }
    }
}
void to_lanes(const float* rows, float (&soa)[48][W]) {
    for (int b = 0; b < 3; ++b) {
        __m512 m[16];
        for (int l = 0; l < 16; ++l) m[l] = _mm512_loadu_ps(rows + l * 48 + b * 16);
        transpose16(m);
        for (int k = 0; k < 16; ++k) _mm512_store_ps(soa[b * 16 + k], m[k]);
    }
}
void to_rows(const float (&soa)[48][W], float (*rows)[48]) {
    for (int b = 0; b < 3; ++b) {
        __m512 m[16];
        for (int k = 0; k < 16; ++k) m[k] = _mm512_load_ps(soa[b * 16 + k]);
        transpose16(m);
        for (int l = 0; l < 16; ++l) _mm512_storeu_ps(rows[l] + b * 16, m[l]);
    }
}
// Copies count floats from src to dst: the 64-byte lines wholly inside dst with streaming stores (no read of
// the line before it is written, and it does not push the working set out of the caches), the partial lines
// at either end with plain stores. deform_shapes_fast() fences before it returns.
void stream_floats(const float* src, float* dst, std::size_t count) {
    const auto addr = reinterpret_cast<std::uintptr_t>(dst);
    std::size_t head = addr % sizeof(float) ? count : ((64 - addr % 64) % 64) / sizeof(float);
    head = std::min(head, count);
    std::memcpy(dst, src, head * sizeof(float));
    std::size_t k = head;
    for (; k + 16 <= count; k += 16) _mm512_stream_ps(dst + k, _mm512_loadu_ps(src + k));
    std::memcpy(dst + k, src + k, (count - k) * sizeof(float));
}
void fence() { _mm_sfence(); }
#else
constexpr bool kTransposeBlocks = false;
void to_lanes(const float*, float (&)[48][W]) {}
void to_rows(const float (&)[48][W], float (*)[48]) {}
void stream_floats(const float*, float*, std::size_t) {}
void fence() {}
#endif

// Lanes whose J is near-singular: polar_decomposition's rule, in double as there (W lanes of double).
inline vm near_singular(const M3& j) {
    typedef double vd __attribute__((vector_size(W * sizeof(double))));
    typedef long long vl __attribute__((vector_size(W * sizeof(long long))));
    vd c[3][3];
    for (int k = 0; k < 3; ++k) {
        c[k][0] = __builtin_convertvector(j.c[k].x, vd);
        c[k][1] = __builtin_convertvector(j.c[k].y, vd);
        c[k][2] = __builtin_convertvector(j.c[k].z, vd);
    }
    vd n2 = vd{};
    for (int k = 0; k < 3; ++k) n2 += c[k][0] * c[k][0] + c[k][1] * c[k][1] + c[k][2] * c[k][2];
    const vd det = c[0][0] * (c[1][1] * c[2][2] - c[2][1] * c[1][2]) -
                   c[1][0] * (c[0][1] * c[2][2] - c[2][1] * c[0][2]) +
                   c[2][0] * (c[0][1] * c[1][2] - c[1][1] * c[0][2]);
    vd root = n2, adet = det;
    for (int l = 0; l < W; ++l) root[l] = std::sqrt(root[l]), adet[l] = std::fabs(adet[l]);
    const vl regular = adet > 1e-12 * n2 * root;  // false where NaN, as the reference's !(… > …)
    return __builtin_convertvector(~regular, vm);
}

// Lanes where x is not finite, OR-ed over `count` vectors of p.
inline vm not_finite_any(const float (*p)[W], int count) {
    vm bad = vm{};
    for (int k = 0; k < count; ++k) {
        vf v;
        std::memcpy(&v, p[k], sizeof v);
        bad |= ~finite(v);
    }
    return bad;
}

// A whole group's J, rotation (w, x, y, z) and scale into lanes: one hardware gather per entry instead of
// a load and a store per entry and Gaussian (masked gathers: GCC 12 warns that the plain one's undefined
// source may be used).
#if defined(__AVX512F__)
constexpr bool kGatherWhole = true;
// W consecutive vec3 into lanes.
V3 gather_xyz(const glm::vec3* p) {
    const __m512i by3 = _mm512_mullo_epi32(
        _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0), _mm512_set1_epi32(3));
    const auto* f = reinterpret_cast<const float*>(p);
    vf c[3];
    for (int k = 0; k < 3; ++k)
        c[k] = (vf)_mm512_mask_i32gather_ps(_mm512_setzero_ps(), 0xffff,
                                            _mm512_add_epi32(by3, _mm512_set1_epi32(k)), f, 4);
    return {c[0], c[1], c[2]};
}
void gather_whole(const glm::mat3* j, const glm::quat* q, const glm::vec3* s, float (&jl)[9][W],
                  float (&ql)[4][W], float (&sl)[3][W]) {
    const __m512i lane = _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
    const __m512i by9 = _mm512_mullo_epi32(lane, _mm512_set1_epi32(9)), by4 = _mm512_slli_epi32(lane, 2);
    const auto* jf = reinterpret_cast<const float*>(j);
    for (int e = 0; e < 9; ++e)
        _mm512_store_ps(jl[e], _mm512_mask_i32gather_ps(_mm512_setzero_ps(), 0xffff,
                                                        _mm512_add_epi32(by9, _mm512_set1_epi32(e)), jf, 4));
    // glm's member order, whichever it is.
    const auto* qf = reinterpret_cast<const float*>(q);
    const float* member[4] = {&q->w, &q->x, &q->y, &q->z};
    for (int k = 0; k < 4; ++k)
        _mm512_store_ps(ql[k], _mm512_mask_i32gather_ps(
                                   _mm512_setzero_ps(), 0xffff,
                                   _mm512_add_epi32(by4, _mm512_set1_epi32(int(member[k] - qf))), qf, 4));
    const V3 sv = gather_xyz(s);
    _mm512_store_ps(sl[0], (__m512)sv.x), _mm512_store_ps(sl[1], (__m512)sv.y),
        _mm512_store_ps(sl[2], (__m512)sv.z);
}
// The same layout back: a whole group's scales and rotations (w, x, y, z) with one scatter per entry.
void scatter_whole(const V3& sv, const vf (&qv)[4], glm::vec3* s, glm::quat* q) {
    const __m512i lane = _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
    const __m512i by4 = _mm512_slli_epi32(lane, 2), by3 = _mm512_mullo_epi32(lane, _mm512_set1_epi32(3));
    auto* sf = reinterpret_cast<float*>(s);
    const vf sc[3] = {sv.x, sv.y, sv.z};
    for (int c = 0; c < 3; ++c)
        _mm512_i32scatter_ps(sf, _mm512_add_epi32(by3, _mm512_set1_epi32(c)), (__m512)sc[c], 4);
    auto* qf = reinterpret_cast<float*>(q);
    const float* member[4] = {&q->w, &q->x, &q->y, &q->z};
    for (int k = 0; k < 4; ++k)
        _mm512_i32scatter_ps(qf, _mm512_add_epi32(by4, _mm512_set1_epi32(int(member[k] - qf))), (__m512)qv[k],
                             4);
}
inline int count(vm m) { return __builtin_popcount(_mm512_test_epi32_mask((__m512i)m, (__m512i)m)); }
// A mask as W bytes 1 (true) or 0.
void store_flags(vm m, std::uint8_t* out) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out),
                     _mm512_maskz_cvtepi32_epi8(0xffff, _mm512_and_si512((__m512i)m, _mm512_set1_epi32(1))));
}
#else
constexpr bool kGatherWhole = false;
void scatter_whole(const V3&, const vf (&)[4], glm::vec3*, glm::quat*) {}
V3 gather_xyz(const glm::vec3*) { return {}; }
void store_flags(vm, std::uint8_t*) {}
inline int count(vm m) {
    int k = 0;
    for (int l = 0; l < W; ++l) k += m[l] != 0;
    return k;
}
void gather_whole(const glm::mat3*, const glm::quat*, const glm::vec3*, float (&)[9][W], float (&)[4][W],
                  float (&)[3][W]) {}
#endif

// One vector of Gaussians first .. first + n - 1 (n <= W). Returns the near-singular count.
std::size_t group(const FastShapeArgs& a, std::size_t first, int n) {
    const GaussianCloud& in = *a.in;
    GaussianCloud& out = *a.out;
    const bool copy = &out != &in;
    const int K = sh_coeffs(in.sh_degree);
    const std::size_t stride = std::size_t(K) * 3;
    // Gather: J, rotation, scale per lane; padding lanes get J = I (not moved).
    alignas(64) float jl[9][W], ql[4][W], sl[3][W];
    if (kGatherWhole && n == W)
        gather_whole(&a.jacobians[first - a.first], &in.rotations[first], &in.scales[first], jl, ql, sl);
    else
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
    auto load = [](const float* p) {
        vf v;
        std::memcpy(&v, p, sizeof v);
        return v;
    };
    M3 J;
    for (int c = 0; c < 3; ++c) J.c[c] = {load(jl[c * 3]), load(jl[c * 3 + 1]), load(jl[c * 3 + 2])};
    vm moved = vm{};  // all false
    for (int c = 0; c < 3; ++c) {
        moved |= J.c[c].x != (c == 0 ? 1.0f : 0.0f);
        moved |= J.c[c].y != (c == 1 ? 1.0f : 0.0f);
        moved |= J.c[c].z != (c == 2 ? 1.0f : 0.0f);
    }
    std::size_t singular_count = 0;
    // Whole groups of degree 3 move their coefficients as 16x16 blocks (to_lanes, to_rows). Copied to another
    // cloud, their 3 KB of output rows are one run, written with streaming stores: the SH are most of a
    // Gaussian's bytes, and a plain store first reads each line it fills from memory.
    const bool whole = kTransposeBlocks && n == W && stride == 48;
    const bool stream = whole && copy;
    const float* sh_in_rows = &in.sh[first * stride];
    alignas(64) float sh_rows[W][48];
    bool rotate_coeffs = false;
    vm rows_rotated = vm{};  // lanes whose sh_rows hold rotated coefficients
    // Whole groups whose coefficients pass through the lanes are checked there (finite_shape()'s tests,
    // vector at a time); the others per Gaussian at the end.
    bool checked = false;
    vm not_finite = vm{};
    if (any(moved)) {
        // polar_decomposition's rule, in double as there: a J singular in exact arithmetic (a flattened cell)
        // has a float determinant of rounding size, far above the 1e-12 threshold.
        const vm singular = moved & near_singular(J);
        // Input rotation (normalised; a zero quaternion reads as I) times the scales: A = J R S.
        vf w = load(ql[0]), x = load(ql[1]), y = load(ql[2]), z = load(ql[3]);
        const vf qn2 = w * w + x * x + y * y + z * z;
        const vm qok = qn2 > 0.0f;
        const vf qinv = 1.0f / vsqrt(sel(qok, qn2, splat(1.0f)));
        w = sel(qok, w * qinv, splat(1.0f)), x = sel(qok, x * qinv, splat(0.0f));
        y = sel(qok, y * qinv, splat(0.0f)), z = sel(qok, z * qinv, splat(0.0f));
        const V3 r0 = {1.0f - 2.0f * (y * y + z * z), 2.0f * (x * y + w * z), 2.0f * (x * z - w * y)};
        const V3 r1 = {2.0f * (x * y - w * z), 1.0f - 2.0f * (x * x + z * z), 2.0f * (y * z + w * x)};
        const V3 r2 = {2.0f * (x * z + w * y), 2.0f * (y * z - w * x), 1.0f - 2.0f * (x * x + y * y)};
        const M3 A = {{mul(J, load(sl[0]) * r0), mul(J, load(sl[1]) * r1), mul(J, load(sl[2]) * r2)}};
        // Normalised by the largest entry so that neither tiny nor huge scales under/overflow the squares.
        vf m = splat(0.0f);
        for (int c = 0; c < 3; ++c) m = vmax(m, vmax(vabs(A.c[c].x), vmax(vabs(A.c[c].y), vabs(A.c[c].z))));
        const vm mpos = m > 0.0f;
        const vf minv = 1.0f / sel(mpos, m, splat(1.0f));
        // The shape's Jacobi sweeps and the colour's Newton steps are independent chains of dependent
        // operations (each rotation needs the previous one's columns): one loop runs both, so that each
        // fills the other's waiting. Same sweeps and steps, same results, as running them one after the
        // other.
        V3 b[3] = {minv * A.c[0], minv * A.c[1], minv * A.c[2]};
        const vm need = moved & ~singular;
        M3 R = sel(need, J, identity());
        vm active = need;
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
        vf q[4];
        to_quat(axes, q);
        // What is written for each lane: the new shape where moved, else the input's.
        const V3 s_out = sel(moved, scale, V3{load(sl[0]), load(sl[1]), load(sl[2])});
        vf q_out[4];
        for (int k = 0; k < 4; ++k) q_out[k] = sel(moved, q[k], load(ql[k]));
        alignas(64) float out_s[3][W], out_q[4][W];
        std::memcpy(out_s[0], &scale.x, sizeof(vf)), std::memcpy(out_s[1], &scale.y, sizeof(vf));
        std::memcpy(out_s[2], &scale.z, sizeof(vf));
        for (int k = 0; k < 4; ++k) std::memcpy(out_q[k], &q[k], sizeof(vf));

        // Colour: the polar rotation where J is regular (coefficients rotated, or the frame stored).
        const vm rotated = K > 1 ? polar_ok(R, need) : vm{};
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
            const vm band0_bad = whole ? not_finite_any(sh_soa, 3) : vm{};
            // Rotated lanes need no input test: a non-finite coefficient makes its whole band non-finite.
            const vm input_bad = whole && any(~rotated) ? not_finite_any(sh_soa + 3, 45) : vm{};
            V3 c[16];
            for (int k = 0; k < K; ++k)
                c[k] = {load(sh_soa[3 * k]), load(sh_soa[3 * k + 1]), load(sh_soa[3 * k + 2])};
            rotate_sh(in.sh_degree, R, c);
            for (int k = 1; k < K; ++k) {
                std::memcpy(sh_soa[3 * k], &c[k].x, sizeof(vf));
                std::memcpy(sh_soa[3 * k + 1], &c[k].y, sizeof(vf));
                std::memcpy(sh_soa[3 * k + 2], &c[k].z, sizeof(vf));
            }
            if (whole) {
                to_rows(sh_soa, sh_rows);  // every lane, the band 0 colour included
                const vm rotated_bad = not_finite_any(sh_soa + 3, 45);
                // finite_shape() of what is written.
                const vf q2 =
                    q_out[1] * q_out[1] + q_out[2] * q_out[2] + q_out[3] * q_out[3] + q_out[0] * q_out[0];
                not_finite = band0_bad | (rotated & rotated_bad) | (~rotated & input_bad) | ~finite(s_out.x) |
                             ~finite(s_out.y) | ~finite(s_out.z) |
                             ~finite(q_out[0] + q_out[1] + q_out[2] + q_out[3]) | ~(vabs(q2 - 1.0f) < 1e-3f);
                checked = true;
            }
            rows_rotated = rotated;
        }
        // Whole groups store their shapes with scatters (the input's where not moved); with their SH rows
        // streamed below and no frames to write, no lane has anything left to do one at a time.
        const bool scattered = kGatherWhole && n == W;
        if (scattered) {
            scatter_whole(s_out, q_out, &out.scales[first], &out.rotations[first]);
            singular_count += std::size_t(count(singular));
        }
        for (int l = 0; l < n && !(scattered && stream && !a.view_mode); ++l) {
            const std::size_t i = first + std::size_t(l);
            const float* sh_in = &in.sh[i * stride];
            float* sh_out = &out.sh[i * stride];
            if (!moved[l]) {  // outside the lattice or not moved by it
                if (copy) {
                    if (!scattered) out.scales[i] = in.scales[i], out.rotations[i] = in.rotations[i];
                    if (!stream) std::copy(sh_in, sh_in + stride, sh_out);
                }
                continue;
            }
            if (!scattered) {
                singular_count += singular[l] != 0;
                out.scales[i] = glm::vec3(out_s[0][l], out_s[1][l], out_s[2][l]);
                out.rotations[i] = glm::quat(out_q[0][l], out_q[1][l], out_q[2][l], out_q[3][l]);
            }
            if (rotate_coeffs && rotated[l]) {
                if (stream) continue;  // the row in sh_rows is written below
                if (whole) std::memcpy(sh_out + 3, sh_rows[l] + 3, (stride - 3) * sizeof(float));
                else
                    for (std::size_t k = 3; k < stride; ++k) sh_out[k] = sh_soa[k][l];
                if (copy) std::copy(sh_in, sh_in + 3, sh_out);
                continue;
            }
            if (copy && !stream) std::copy(sh_in, sh_in + stride, sh_out);
            if (a.view_mode && rotated[l]) {
                glm::mat3 p;
                for (int c = 0; c < 3; ++c) p[c] = glm::vec3(R.c[c].x[l], R.c[c].y[l], R.c[c].z[l]);
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
            if (!rows_rotated[l]) std::memcpy(sh_rows[l], sh_in_rows + l * 48, 48 * sizeof(float));
        rows_out = &sh_rows[0][0];
    }
    if (stream) stream_floats(rows_out, &out.sh[first * stride], std::size_t(W) * 48);
    if (a.not_finite) {
        // J itself too, as the shader tests it: a J that is not finite can still give a finite-looking shape.
        vm bad = checked ? not_finite : vm{};
        for (int c = 0; c < 3; ++c) bad |= ~finite(J.c[c].x) | ~finite(J.c[c].y) | ~finite(J.c[c].z);
        // A whole group checked in the lanes tests its centres there too and stores its 16 answers at once.
        if (kGatherWhole && checked && n == W && !a.view_mode) {
            const V3 p = gather_xyz(&out.positions[first]);
            bad |= ~finite(p.x) | ~finite(p.y) | ~finite(p.z);
            store_flags(bad, &a.not_finite[first - a.first]);
            return singular_count;
        }
        for (int l = 0; l < n; ++l) {
            const std::size_t i = first + std::size_t(l);
            bool drop = bad[l] != 0 || !finite3(out.positions[i]);
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

int shape_lane_width() { return W; }

// Groups ahead whose SH rows are prefetched (measured: 2 to 8 are alike, none is about 8% slower).
constexpr int kPrefetch = 4;

std::size_t deform_shapes_fast(const FastShapeArgs& a, std::size_t begin, std::size_t end) {
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
            for (std::size_t o = 0; o < bytes; o += 64) __builtin_prefetch(p + o, 0, 3);
        }
        singular += group(a, a.first + b, int(std::min<std::size_t>(W, end - b)));
    }
    fence();  // streamed rows are visible to whichever thread reads them next
    return singular;
}

}  // namespace sffd::gaussian::detail
