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

// Lane types, vector maths, polar and SH steps, loads and stores (per target, see the file).
#include "systems/gaussian/gaussian_lanes-inl.h"  // NOLINT(bugprone-suspicious-include)

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
