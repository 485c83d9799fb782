#version 450 core
// GPU deformation of 3D Gaussians through one FFD lattice (systems/gaussian/gpu_deform.h). Reads
// GpuGaussian[] (the rest cloud, or the previous deformer's output when several apply in order: in place)
// and writes the deformed Gaussian:
//   centre  μ' = μ + D(μ)                     (shaders/ffd/ffd_common.glsl, the ffd pass's own evaluation)
//   shape   Σ' = J Σ Jᵀ = A Aᵀ with A = J R S (the deformed axes), stored back as rotation + scale. Σ' is
//           never formed: a one-sided (Hestenes) Jacobi orthogonalises the columns of A by plane rotations
//           from the right, A W = B; then Σ' = B Bᵀ = Σ b_i b_iᵀ with orthogonal b_i, so the scales are
//           |b_i| and the axes b_i / |b_i|. Squaring A would double float's relative error on thin
//           Gaussians (σ_min/σ_max = 1e-3 loses the small axis to rounding); orthogonalising A keeps it.
//           Repeated singular values need no rotation (the columns are already orthogonal); a singular
//           J leaves zero columns, whose axes are completed by cross products (scale 0: a flat Gaussian).
//   frames  (GAUSS_FRAMES) the rotation R_p of the polar decomposition J = R_p U, composed onto the
//           previous deformer's frame: frames[3i + c] = column c (the SH are evaluated at frameᵀ d).
//           Near-singular J (|det J| <= 1e-12 ‖J‖_F³, the CPU's rule) keeps the previous frame.
//   SH      (ShMode::rotate_coefficients, GAUSS_SH) the coefficients rotated by R_p per band, as the CPU's
//           sh_rotation (systems/gaussian/sh.cpp): band l's function is evaluated at its 2l+1 sample
//           directions turned by R_pᵀ and mapped back to coefficients by A_l⁻¹ (tables in sh_tab[]).
//           Unmoved and near-singular Gaussians keep their coefficients.
// Opacity is carried. A result that is not finite (a degenerate or overflowing lattice) is never left
// for the renderer to compare against NaN: the Gaussian is written with opacity 0, scale 0 and its input
// centre, and stats[2] counts it. Finiteness is tested on the IEEE exponent bits, which no fast-math
// optimisation of isnan/isinf can remove.
#include "ffd/ffd_common.glsl"
#include "gaussian/gaussian_layout.h"

#ifndef FFD_LOCAL_SIZE
#define FFD_LOCAL_SIZE 64
#endif
layout(local_size_x = FFD_LOCAL_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_IN) readonly buffer GaussiansIn { GpuGaussian g_in[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DEFORMED) writeonly buffer GaussiansOut { GpuGaussian g_out[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_FRAMES) buffer Frames { vec4 frames[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_SH) readonly buffer ShIn { float sh_in[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DEFORMED_SH) writeonly buffer ShOut { float sh_out[]; };
// sh_tab: band 1..3 sample directions (3 + 5 + 7, xyz each: floats 0..44), then A_1⁻¹ (45..53), A_2⁻¹
// (54..78), A_3⁻¹ (79..127), row-major.
layout(std430, binding = SFFD_GAUSS_SSBO_SH_TABLES) readonly buffer ShTables { float sh_tab[]; };
// Per page (ffd/page_stats.glsl): [0] inverted, [1] inside, [2] not finite, [3] singular.
layout(std430, binding = SFFD_SSBO_STATS) buffer Stats { uint stats[]; };
#define SFFD_PAGE_COUNTERS 4u
#include "ffd/page_stats.glsl"
// The group's counts, added to its page's once per group (as the ffd pass does): one global atomic per
// Gaussian on the same word serialises the dispatch on GPUs that do not combine a warp's atomics.
shared uint s_counts[4];

// What a dispatch writes is fixed when the program is made (GpuGaussianDeformer specialises it), so the
// code of the outputs it does not write is left out:
//   GAUSS_FRAMES     1: write frames (compose onto the previous deformer's when u_compose, else start at I)
//   GAUSS_SH         1: rotate the SH coefficients (degree u_sh_degree, 1..3) sh_in -> sh_out (the same
//                    buffer after the first deformer); 0: coefficients not written
// The degree stays a uniform: a constant degree 3 unrolled the rotation, which made it slower on llvmpipe.
// Without them (the generic program, compiled to check the shader): both written.
#ifndef GAUSS_FRAMES
#define GAUSS_FRAMES 1
#endif
#ifndef GAUSS_SH
#define GAUSS_SH 1
#endif
layout(location = 0) uniform uint u_compose;   // set only for programs with frames (they use it)
layout(location = 1) uniform int u_sh_degree;  // set only for programs with coefficients

// Band l (1..3) of the 3DGS SH basis at d (systems/gaussian/sh.h, same constants and order).
void sh_band(int l, vec3 d, out float y[7]) {
    float x = d.x, yy_ = d.y, z = d.z;
    if (l == 1) {
        y[0] = -0.4886025119029199 * yy_; y[1] = 0.4886025119029199 * z; y[2] = -0.4886025119029199 * x;
        return;
    }
    float xx = x * x, yy = yy_ * yy_, zz = z * z;
    if (l == 2) {
        y[0] = 1.0925484305920792 * x * yy_;
        y[1] = -1.0925484305920792 * yy_ * z;
        y[2] = 0.31539156525252005 * (2.0 * zz - xx - yy);
        y[3] = -1.0925484305920792 * x * z;
        y[4] = 0.5462742152960396 * (xx - yy);
        return;
    }
    y[0] = -0.5900435899266435 * yy_ * (3.0 * xx - yy);
    y[1] = 2.890611442640554 * x * yy_ * z;
    y[2] = -0.4570457994644658 * yy_ * (4.0 * zz - xx - yy);
    y[3] = 0.3731763325901154 * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
    y[4] = -0.4570457994644658 * x * (4.0 * zz - xx - yy);
    y[5] = 1.445305721320277 * z * (xx - yy);
    y[6] = -0.5900435899266435 * x * (xx - 3.0 * yy);
}

// Coefficients of Gaussian id: rotated by r (D_l c = A_l⁻¹ [f_l(rᵀ d_j)]_j per band) when `rotate`, else copied.
void sh_write(uint id, int degree, bool rotate, mat3 r) {
    int K = (degree + 1) * (degree + 1);
    uint base = id * uint(K) * 3u;
    vec3 c[16];
    for (int k = 0; k < K; ++k) c[k] = vec3(sh_in[base + 3u * uint(k)], sh_in[base + 3u * uint(k) + 1u], sh_in[base + 3u * uint(k) + 2u]);
    if (rotate) {
        mat3 rt = transpose(r);
        int dir0 = 0, inv0 = 45;
        for (int l = 1; l <= degree; ++l) {
            int n = 2 * l + 1, first = l * l;
            vec3 v[7];
            for (int j = 0; j < n; ++j) {
                int t = 3 * (dir0 + j);
                float y[7];
                sh_band(l, rt * vec3(sh_tab[t], sh_tab[t + 1], sh_tab[t + 2]), y);
                vec3 f = vec3(0.0);
                for (int m = 0; m < n; ++m) f += y[m] * c[first + m];
                v[j] = f;
            }
            for (int row = 0; row < n; ++row) {
                vec3 o = vec3(0.0);
                for (int j = 0; j < n; ++j) o += sh_tab[inv0 + row * n + j] * v[j];
                c[first + row] = o;  // band l's inputs are all in v[] already
            }
            dir0 += n;
            inv0 += n * n;
        }
    }
    for (int k = 0; k < K; ++k) {
        sh_out[base + 3u * uint(k)] = c[k].x;
        sh_out[base + 3u * uint(k) + 1u] = c[k].y;
        sh_out[base + 3u * uint(k) + 2u] = c[k].z;
    }
}

bool finite_f(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool finite_v(vec4 v) { return finite_f(v.x) && finite_f(v.y) && finite_f(v.z) && finite_f(v.w); }

mat3 quat_to_mat3(vec4 q) {  // q = (w, x, y, z), normalised here
    float n2 = dot(q, q);
    q = n2 > 0.0 ? q * inversesqrt(n2) : vec4(1.0, 0.0, 0.0, 0.0);
    float w = q.x, x = q.y, y = q.z, z = q.w;
    return mat3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y),
                2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x),
                2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y));
}

// Unit quaternion (w, x, y, z), w >= 0, of a proper rotation (Shepperd: divide by the largest of the four).
vec4 mat3_to_quat(mat3 m) {
    float tr = m[0][0] + m[1][1] + m[2][2];
    vec4 q;
    if (tr > 0.0) {
        float s = sqrt(tr + 1.0) * 2.0;
        q = vec4(0.25 * s, (m[1][2] - m[2][1]) / s, (m[2][0] - m[0][2]) / s, (m[0][1] - m[1][0]) / s);
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        float s = sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2.0;
        q = vec4((m[1][2] - m[2][1]) / s, 0.25 * s, (m[1][0] + m[0][1]) / s, (m[2][0] + m[0][2]) / s);
    } else if (m[1][1] > m[2][2]) {
        float s = sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2.0;
        q = vec4((m[2][0] - m[0][2]) / s, (m[1][0] + m[0][1]) / s, 0.25 * s, (m[2][1] + m[1][2]) / s);
    } else {
        float s = sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2.0;
        q = vec4((m[0][1] - m[1][0]) / s, (m[2][0] + m[0][2]) / s, (m[2][1] + m[1][2]) / s, 0.25 * s);
    }
    q = normalize(q);
    return q.x < 0.0 ? -q : q;
}

// One Hestenes rotation of columns p, q of b: makes them orthogonal (no-op when they already are, to
// float precision, or when either is zero).
void orthogonalise(inout vec3 bp, inout vec3 bq) {
    float alpha = dot(bp, bp), beta = dot(bq, bq), gamma = dot(bp, bq);
    if (!(abs(gamma) > 1e-7 * sqrt(alpha * beta)) || gamma == 0.0) return;
    // The angle from its double, as the CPU kernel: cos 2θ = |d| / r, sin 2θ = sign(d) g / r
    // (d = β − α, g = 2γ, r = |(d, g)|, |θ| ≤ π/4), then c = sqrt((1 + cos 2θ) / 2), s = sin 2θ / (2c).
    // d and g are divided by the larger first: no square under- or overflows (g is not 0 here).
    float d = beta - alpha, g = 2.0 * gamma;
    const float m = max(abs(d), abs(g));
    d /= m, g /= m;
    const float rr = inversesqrt(d * d + g * g);
    const float cos2 = abs(d) * rr, sin2 = (d < 0.0 ? -g : g) * rr;
    const float h = 0.5 + 0.5 * cos2, rh = inversesqrt(h);
    float c = h * rh, s = (0.5 * sin2) * rh;
    vec3 np = c * bp - s * bq;
    vec3 nq = s * bp + c * bq;
    bp = np;
    bq = nq;
}

// Axes (columns, a proper rotation) and scales (descending) of A Aᵀ.
void decompose(mat3 a, out mat3 axes, out vec3 scale) {
    vec3 b0 = a[0], b1 = a[1], b2 = a[2];
    for (int sweep = 0; sweep < 12; ++sweep) {
        float off = 0.0;
        float n0 = dot(b0, b0), n1 = dot(b1, b1), n2 = dot(b2, b2);
        off = max(max(abs(dot(b0, b1)) * inversesqrt(max(n0 * n1, 1e-37)), abs(dot(b0, b2)) * inversesqrt(max(n0 * n2, 1e-37))),
                  abs(dot(b1, b2)) * inversesqrt(max(n1 * n2, 1e-37)));
        if (!(off > 1e-7)) break;
        orthogonalise(b0, b1);
        orthogonalise(b0, b2);
        orthogonalise(b1, b2);
    }
    vec3 s = vec3(length(b0), length(b1), length(b2));
    // Sort descending (three compare-swaps).
    if (s.y > s.x) { vec3 t = b0; b0 = b1; b1 = t; s.xy = s.yx; }
    if (s.z > s.y) { vec3 t = b1; b1 = b2; b2 = t; s.yz = s.zy; }
    if (s.y > s.x) { vec3 t = b0; b0 = b1; b1 = t; s.xy = s.yx; }
    // Axes; columns that vanished (relative to the largest) are completed orthogonally.
    float tiny = 1e-6 * s.x;
    vec3 u0 = s.x > 0.0 ? b0 / s.x : vec3(1.0, 0.0, 0.0);
    vec3 u1;
    if (s.y > tiny) {
        u1 = b1 / s.y;
    } else {
        vec3 other = abs(u0.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
        u1 = normalize(cross(u0, other));
    }
    u1 = normalize(u1 - dot(u0, u1) * u0);   // re-orthogonalise the rounding away
    vec3 u2 = cross(u0, u1);                 // det = +1 (a flipped b2 only changes the sign of an axis)
    axes = mat3(u0, u1, u2);
    scale = s;
}

// Orthogonal factor of J = R U (scaled Newton, Higham), the CPU's polar_decomposition in float.
bool polar_rotation(mat3 j, out mat3 r) {
    r = mat3(1.0);
    float n2 = dot(j[0], j[0]) + dot(j[1], j[1]) + dot(j[2], j[2]);
    if (!(abs(determinant(j)) > 1e-12 * n2 * sqrt(n2))) return false;
    mat3 x = j;
    for (int it = 0; it < 20; ++it) {
        mat3 inv_t = transpose(inverse(x));
        float nx = dot(x[0], x[0]) + dot(x[1], x[1]) + dot(x[2], x[2]);
        float ni = dot(inv_t[0], inv_t[0]) + dot(inv_t[1], inv_t[1]) + dot(inv_t[2], inv_t[2]);
        float zeta = sqrt(sqrt(ni / nx));
        mat3 next = 0.5 * (zeta * x + (1.0 / zeta) * inv_t);
        vec3 d0 = next[0] - x[0], d1 = next[1] - x[1], d2 = next[2] - x[2];
        float change = dot(d0, d0) + dot(d1, d1) + dot(d2, d2);
        x = next;
        if (change <= 1e-13 * 3.0) break;
    }
    bool finite = true;
    for (int c = 0; c < 3; ++c) finite = finite && finite_v(vec4(x[c], 0.0));
    if (!finite) return false;
    r = x;
    return true;
}

void write_frame(uint id, mat3 r) {
    frames[3u * id] = vec4(r[0], 0.0);
    frames[3u * id + 1u] = vec4(r[1], 0.0);
    frames[3u * id + 2u] = vec4(r[2], 0.0);
}

// Deforms Gaussian `id`; returns its counts as bits (bit k adds 1 to stats[k]).
uint deform_gaussian(uint id) {
    uint counts = 0u;
    const bool want_frames = GAUSS_FRAMES != 0;
    const bool compose = want_frames && u_compose != 0u;
    const bool want_coefficients = GAUSS_SH != 0;
    GpuGaussian g = g_in[id];
    mat3 prev_frame = mat3(1.0);
    if (want_frames && compose) prev_frame = mat3(frames[3u * id].xyz, frames[3u * id + 1u].xyz, frames[3u * id + 2u].xyz);
    vec3 stu = ffd_local(g.pos_opacity.xyz);
    bool culled = ffd_count.y != 0u || !ffd_inside(stu) ||
                  (ffd_div.w == 1 && (any(lessThanEqual(stu, ffd_cull_lo.xyz)) || any(greaterThanEqual(stu, ffd_cull_hi.xyz))));
#ifdef FFD_WEIGHTS
    const float weight = ffd_weights[id];
    culled = culled || !(weight > 0.0);  // weight 0: at rest
#endif
    if (ffd_inside(stu)) counts |= 2u;
    if (culled) {  // not moved: copied unchanged, frames start at identity
        g_out[id] = g;
        if (want_frames && !compose) write_frame(id, mat3(1.0));
        if (want_coefficients) sh_write(id, u_sh_degree, false, mat3(1.0));
        return counts;
    }
    vec3 D;
    mat3 G;
    ffd_eval(stu, true, D, G);
#ifdef FFD_WEIGHTS
    D *= weight;  // X + w D, J_w = I + w G M⁻¹
    G *= weight;
#endif
    mat3 J = ffd_jacobian(G);
    GpuGaussian o = g;
    o.pos_opacity.xyz = g.pos_opacity.xyz + D;
    mat3 frame = prev_frame;
    bool rotated = false;
    mat3 polar = mat3(1.0);
    if (J != mat3(1.0)) {  // J = I exactly (as the CPU tests it): shape and frame unchanged
        float det = determinant(J);
        if (det < 0.0) counts |= 1u;
        float n2 = dot(J[0], J[0]) + dot(J[1], J[1]) + dot(J[2], J[2]);
        bool singular = !(abs(det) > 1e-12 * n2 * sqrt(n2));  // the CPU's polar_decomposition rule
        if (singular) counts |= 8u;
        mat3 rq = quat_to_mat3(g.rotation);
        vec3 s = g.scale.xyz;
        mat3 a = J * mat3(rq[0] * s.x, rq[1] * s.y, rq[2] * s.z);
        // Normalised by the largest entry so that neither tiny nor huge scales under/overflow the squares.
        float m = max(max(max(abs(a[0].x), abs(a[0].y)), max(abs(a[0].z), abs(a[1].x))),
                      max(max(abs(a[1].y), abs(a[1].z)), max(max(abs(a[2].x), abs(a[2].y)), abs(a[2].z))));
        mat3 axes = mat3(1.0);
        vec3 scale = vec3(0.0);
        if (m > 0.0) {
            decompose(a * (1.0 / m), axes, scale);
            scale *= m;
        }
        o.rotation = mat3_to_quat(axes);
        o.scale = vec4(scale, g.scale.w);
        if ((want_frames || want_coefficients) && !singular && polar_rotation(J, polar)) {
            rotated = true;
            frame = polar * prev_frame;
        }
    }
    // J too: a non-finite J can still give a finite-looking shape (max() of NaN is undefined, m > 0 false).
    bool ok = finite_v(vec4(J[0], J[1].x)) && finite_v(vec4(J[1].yz, J[2].xy)) && finite_f(J[2].z) &&
              finite_v(o.pos_opacity) && finite_v(o.rotation) && finite_v(o.scale) &&
              finite_v(vec4(frame[0], frame[1].x)) && finite_v(vec4(frame[1].yz, frame[2].xy)) && finite_f(frame[2].z);
    if (!ok) {
        counts |= 4u;
        o.pos_opacity = vec4(finite_v(vec4(g.pos_opacity.xyz, 0.0)) ? g.pos_opacity.xyz : vec3(0.0), 0.0);
        o.rotation = vec4(1.0, 0.0, 0.0, 0.0);
        o.scale = vec4(0.0);
        frame = mat3(1.0);
    }
    g_out[id] = o;
    if (want_frames) write_frame(id, frame);
    if (want_coefficients) sh_write(id, u_sh_degree, rotated && ok, polar);
    return counts;
}

void main() {
    uint id = sffd_dispatch_index();
    if (gl_LocalInvocationIndex < 4u) s_counts[gl_LocalInvocationIndex] = 0u;
#ifdef FFD_CP_SHARED
    ffd_share_control_points(gl_LocalInvocationIndex, gl_WorkGroupSize.x);
#endif
    memoryBarrierShared();
    barrier();
    const uint counts = id < ffd_count.x ? deform_gaussian(id) : 0u;
    const bool one_page = ffd_group_in_one_page(id);
    for (uint k = 0u; k < 4u; ++k) {
        const uint c = (counts >> k) & 1u;
        if (!one_page) ffd_count_in_page(id, k, c);  // a group across two pages counts point by point
        else if (c != 0u) atomicAdd(s_counts[k], 1u);
    }
    memoryBarrierShared();
    barrier();
    if (one_page && gl_LocalInvocationIndex < 4u)
        ffd_count_in_page(id - gl_LocalInvocationIndex, gl_LocalInvocationIndex, s_counts[gl_LocalInvocationIndex]);
}
