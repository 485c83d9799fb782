// The lane arithmetic of the Gaussian shape kernel (gaussian_deform_fast.cpp): W-wide 3-vectors and 3x3
// matrices, the Jacobi and polar steps, SH band rotation, row/lane transposes and masked loads and stores.
// Included INSIDE that file's per-target namespace (sffd::gaussian::detail::HWY_NAMESPACE, anonymous), once
// per Highway target as foreach_target re-reads the .cpp, so it has no include guard on purpose and is
// never included anywhere else.

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
