// FFD evaluation shared by the compute pass (deform.comp), paper mode (paper_mode.vert) and the Gaussian
// deformation (shaders/gaussian/deform.comp).
// Convention: ../../systems/ffd/README.md (displacement form X' = X + Σ ΔP B B B, J = I + G M⁻¹, normals by
// the cofactor of J). Control points arrive as displacements ΔP (vec4 xyz) in SSBO SFFD_SSBO_CONTROL_POINTS:
// Bernstein: flat index (i*(m+1)+j)*(n+1)+k; B-spline: zero-bordered grid (l+3)(m+3)(n+3), index + 1.
#ifndef FFD_COMMON_GLSL
#define FFD_COMMON_GLSL

#include "common/bindings.h"

// The C++ side compiles one program per lattice shape and basis with FFD_L/FFD_M/FFD_N (divisions),
// FFD_MAXB (largest + 1) and FFD_BASIS (0 Bernstein, 1 B-spline) defined: constant loop bounds and small
// arrays let the driver unroll and keep the basis in registers (llvmpipe otherwise spills 65-float arrays
// to memory: ~15x slower), and the other basis's code is not compiled at all (the B-spline program would
// otherwise carry the Bernstein sum's 65-float arrays and its branch). Without them, any lattice up to
// kMaxDivisions works with the UBO's divisions and basis.
#ifdef FFD_MAXB
#define FFD_MAX_B FFD_MAXB
#else
#define FFD_MAX_B 65   // kMaxDivisions + 1 (systems/ffd/lattice.h)
#endif

layout(std140, binding = SFFD_UBO_FFD) uniform FfdBlock {
    vec4 ffd_minv0;      // rows of M⁻¹ (xyz)
    vec4 ffd_minv1;
    vec4 ffd_minv2;
    vec4 ffd_stu0;       // M⁻¹ (cloud origin − lattice origin)
    ivec4 ffd_div;       // l, m, n, basis (0 bernstein, 1 bspline)
    vec4 ffd_cull_lo;    // local box outside which nothing moves (xyz)
    vec4 ffd_cull_hi;
    uvec4 ffd_count;     // x: number of splats, y: 1 = nothing moved, z: the cloud index of the first
};

layout(std430, binding = SFFD_SSBO_CONTROL_POINTS) readonly buffer FfdControlPoints {
    vec4 ffd_dp[];
};

// Per-point weights (PointWeights, runtime/scene/point_columns.h), compiled in only for clouds that have
// them (FFD_WEIGHTS: a program of its own, so a cloud without weights runs the unweighted code): a point
// moves by w D and its Jacobian is I + w G M⁻¹ = I + w (J − I); weight 0 (or NaN) leaves it as it is.
#ifdef FFD_WEIGHTS
layout(std430, binding = SFFD_SSBO_WEIGHTS) readonly buffer FfdWeights { float ffd_weights[]; };
#endif

// Where the sums read ΔP_i (FFD_DP(i), a vec3). Three kernels of the same arithmetic:
// - FFD_CP_SHARED (compute only, GpuBernsteinKernel::shared): deform.comp copies the lattice's control
//   points into shared memory once per work group (xyz only: 11³ points = 15,972 bytes, within GL's
//   guaranteed 32 KB), so the (l+1)(m+1)(n+1) reads per point hit on-chip memory (every lane reads the same
//   element: a broadcast) instead of the UBO's constant cache, which an 11³ lattice (21 KB) overflows.
//   B-spline: the zero-bordered grid (13³ points for 11³ control points = 26,364 bytes), so each point's
//   64 scattered reads hit shared memory instead of 64 uncoalesced 16-byte global loads; the copy is 9
//   coalesced loads per invocation of a 256-wide group.
// - FFD_CP_UBO (Bernstein only): read from a UBO: every invocation reads the same element, which llvmpipe
//   turns into one scalar load instead of a per-lane gather (llvmpipe's best: barrier() costs it coroutine
//   switches). B-spline lanes read different elements: the UBO would gain nothing.
// - neither: the SSBO (any lattice size); with FFD_BSPLINE_RUNS the B-spline's grid arrives as runs of
//   4 points along u, packed as their x, y, z (GpuBernsteinKernel::packed).
//
// The Bernstein sums run over the coordinates of ΔP that move, as the CPU kernel's do (a twist leaves its
// axis's coordinate still, a stretch along an axis two: a third or two thirds of the arithmetic saved):
// FFD_MOVE is their swizzle (x, xz, ...), FFD_MOVE_N their number, FFD_MOVE_A and FFD_MOVE_B where the
// first two go in the vec3 (DeformPrograms::bind defines them when fewer than three move). FFD_DPM(i) reads those coordinates of ΔP_i as an
// FFD_MVEC; shared memory holds only them.
#ifndef FFD_MOVE
#define FFD_MOVE xyz
#define FFD_MOVE_N 3
#endif
#if FFD_MOVE_N == 1
#define FFD_MVEC float
#elif FFD_MOVE_N == 2
#define FFD_MVEC vec2
#else
#define FFD_MVEC vec3
#endif
#if defined(FFD_CP_SHARED)
shared float ffd_dp_shared[FFD_MOVE_N * FFD_CP_SHARED];
#define FFD_DP(i) vec3(ffd_dp_shared[3 * (i)], ffd_dp_shared[3 * (i) + 1], ffd_dp_shared[3 * (i) + 2])
#if FFD_MOVE_N == 1
#define FFD_DPM(i) ffd_dp_shared[i]
#elif FFD_MOVE_N == 2
#define FFD_DPM(i) vec2(ffd_dp_shared[2 * (i)], ffd_dp_shared[2 * (i) + 1])
#else
#define FFD_DPM(i) FFD_DP(i)
#endif
#elif defined(FFD_CP_UBO)
layout(std140, binding = SFFD_UBO_FFD_CONTROL) uniform FfdControlBlock {
    vec4 ffd_dp_ubo[FFD_CP_UBO];
};
#define FFD_DP(i) ffd_dp_ubo[i].xyz
#define FFD_DPM(i) ffd_dp_ubo[i].FFD_MOVE
#else
#define FFD_DP(i) ffd_dp[i].xyz
#define FFD_DPM(i) ffd_dp[i].FFD_MOVE
#endif

#ifdef FFD_CP_SHARED
// Every invocation of the work group copies its share of the control points' moving coordinates
// (`invocation` of `group_size`; a header included before the shader declares its size cannot name
// gl_WorkGroupSize); the caller then waits at a barrier (uniform control flow).
void ffd_share_control_points(uint invocation, uint group_size) {
    for (uint c = invocation; c < uint(FFD_CP_SHARED); c += group_size) {
        FFD_MVEC d = ffd_dp[c].FFD_MOVE;
#if FFD_MOVE_N == 1
        ffd_dp_shared[c] = d;
#else
        for (uint a = 0u; a < uint(FFD_MOVE_N); ++a) ffd_dp_shared[uint(FFD_MOVE_N) * c + a] = d[a];
#endif
    }
}
#endif

// The moving coordinates back in a vec3, zeros for the still ones.
vec3 ffd_unpack_moving(FFD_MVEC v) {
#if FFD_MOVE_N == 3
    return v;
#else
    vec3 r = vec3(0.0);
#if FFD_MOVE_N == 1
    r[FFD_MOVE_A] = v;
#else
    r[FFD_MOVE_A] = v.x;
    r[FFD_MOVE_B] = v.y;
#endif
    return r;
#endif
}

const float FFD_SLACK = 1e-6;

// Bernstein basis B(L,i,s) and derivative L (B(L-1,i-1) - B(L-1,i)) from powers and binomials.
void ffd_bernstein(float s, int L, out float b[FFD_MAX_B], out float db[FFD_MAX_B]) {
    float r = 1.0 - s;
    float sp[FFD_MAX_B], rp[FFD_MAX_B];
    sp[0] = 1.0;
    rp[0] = 1.0;
    for (int i = 1; i <= L; ++i) {
        sp[i] = sp[i - 1] * s;
        rp[i] = rp[i - 1] * r;
    }
    float c = 1.0, c1 = 1.0;  // C(L,i), C(L-1,i)
    float prev = 0.0;         // B(L-1,i-1)
    float fl = float(L);
    for (int i = 0; i <= L; ++i) {
        b[i] = c * sp[i] * rp[L - i];
        float cur = i <= L - 1 ? c1 * sp[i] * rp[L - 1 - i] : 0.0;  // B(L-1,i)
        db[i] = fl * (prev - cur);
        prev = cur;
        c = c * float(L - i) / float(i + 1);
        c1 = c1 * float(L - 1 - i) / float(i + 1);
    }
}

void ffd_bspline_weights(float f, float n, out vec4 w, out vec4 dw) {
    float f2 = f * f, f3 = f2 * f, r = 1.0 - f;
    w = vec4(r * r * r, 3.0 * f3 - 6.0 * f2 + 4.0, -3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0, f3) / 6.0;
    dw = vec4(-0.5 * r * r, 1.5 * f2 - 2.0 * f, -1.5 * f2 + f + 0.5, 0.5 * f2) * n;
}

// Local coordinates of a point relative to the cloud origin.
vec3 ffd_local(vec3 p) {
    return ffd_stu0.xyz + vec3(dot(ffd_minv0.xyz, p), dot(ffd_minv1.xyz, p), dot(ffd_minv2.xyz, p));
}

bool ffd_inside(vec3 stu) {
    return all(greaterThanEqual(stu, vec3(-FFD_SLACK))) && all(lessThanEqual(stu, vec3(1.0 + FFD_SLACK)));
}

// Displacement D and its derivatives G = [∂D/∂s ∂D/∂t ∂D/∂u] (columns) at clamped local coordinates.
// Both bases evaluate their 1D basis (and derivative) once per axis per point and sum factorised,
// Σ_i B_i(s) Σ_j B_j(t) Σ_k B_k(u) ΔP_ijk; the B-spline reads only the 4×4×4 control points around the
// point's cell.
void ffd_eval(vec3 stu, bool full, out vec3 D, out mat3 G) {
    stu = clamp(stu, vec3(0.0), vec3(1.0));
#ifdef FFD_L
    const int L = FFD_L, M = FFD_M, N = FFD_N;
#else
    int L = ffd_div.x, M = ffd_div.y, N = ffd_div.z;
#endif
    D = vec3(0.0);
    vec3 Fs = vec3(0.0), Ft = vec3(0.0), Fu = vec3(0.0);
#if !defined(FFD_BASIS)
    if (ffd_div.w == 0)
#endif
#if !defined(FFD_BASIS) || FFD_BASIS == 0
    {
        float bs[FFD_MAX_B], dbs[FFD_MAX_B], bt[FFD_MAX_B], dbt[FFD_MAX_B], bu[FFD_MAX_B], dbu[FFD_MAX_B];
        ffd_bernstein(stu.x, L, bs, dbs);
        ffd_bernstein(stu.y, M, bt, dbt);
        ffd_bernstein(stu.z, N, bu, dbu);
        FFD_MVEC Dm = FFD_MVEC(0.0), Fsm = FFD_MVEC(0.0), Ftm = FFD_MVEC(0.0), Fum = FFD_MVEC(0.0);
        for (int i = 0; i <= L; ++i) {
            FFD_MVEC R = FFD_MVEC(0.0), Rt = FFD_MVEC(0.0), Ru = FFD_MVEC(0.0);
            for (int j = 0; j <= M; ++j) {
                int base = (i * (M + 1) + j) * (N + 1);
                FFD_MVEC q = FFD_MVEC(0.0), w = FFD_MVEC(0.0);
                for (int k = 0; k <= N; ++k) {
                    FFD_MVEC d = FFD_DPM(base + k);
                    q += bu[k] * d;
                    w += dbu[k] * d;
                }
                R += q * bt[j];
                Rt += q * dbt[j];
                Ru += w * bt[j];
            }
            Dm += R * bs[i];
            Fsm += R * dbs[i];
            Ftm += Rt * bs[i];
            Fum += Ru * bs[i];
        }
        D = ffd_unpack_moving(Dm);
        Fs = ffd_unpack_moving(Fsm);
        Ft = ffd_unpack_moving(Ftm);
        Fu = ffd_unpack_moving(Fum);
    }
#endif
#if !defined(FFD_BASIS)
    else
#endif
#if !defined(FFD_BASIS) || FFD_BASIS == 1
    {
        vec3 g = stu * vec3(L, M, N);
        ivec3 c = min(ivec3(g), ivec3(L, M, N) - 1);
        vec3 f = g - vec3(c);
        vec4 ws, dws, wt, dwt, wu, dwu;
        ffd_bspline_weights(f.x, float(L), ws, dws);
        ffd_bspline_weights(f.y, float(M), wt, dwt);
        ffd_bspline_weights(f.z, float(N), wu, dwu);
        int PM = M + 3, PK = N + 3;
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
#ifdef FFD_BSPLINE_RUNS
                // The run of 4 points along u as their x, y and z (gpu_block.h bspline_runs).
                int run = 3 * (((c.x + a) * PM + (c.y + b)) * N + c.z);
                vec4 X = ffd_dp[run], Y = ffd_dp[run + 1], Z = ffd_dp[run + 2];
                vec3 q = vec3(dot(wu, X), dot(wu, Y), dot(wu, Z));
                vec3 w = vec3(dot(dwu, X), dot(dwu, Y), dot(dwu, Z));
#else
                int base = ((c.x + a) * PM + (c.y + b)) * PK + c.z;
                vec3 q = vec3(0.0), w = vec3(0.0);
                for (int k = 0; k < 4; ++k) {
                    vec3 d = FFD_DP(base + k);
                    q += wu[k] * d;
                    w += dwu[k] * d;
                }
#endif
                D += q * (ws[a] * wt[b]);
                Fs += q * (dws[a] * wt[b]);
                Ft += q * (ws[a] * dwt[b]);
                Fu += w * (ws[a] * wt[b]);
            }
    }
#endif
    G = mat3(Fs, Ft, Fu);
}

// J = I + G M⁻¹ (M⁻¹ given by rows).
mat3 ffd_jacobian(mat3 G) {
    mat3 minv = transpose(mat3(ffd_minv0.xyz, ffd_minv1.xyz, ffd_minv2.xyz));
    return mat3(1.0) + G * minv;
}

vec3 ffd_cofactor_normal(mat3 J, vec3 n) {
    vec3 a = J[0], b = J[1], c = J[2];
    vec3 r = cross(b, c) * n.x + cross(c, a) * n.y + cross(a, b) * n.z;
    float len = length(r);
    return len > 0.0 ? r / len : r;
}

#endif
