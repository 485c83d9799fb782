#version 450 core
// FFD compute pass (skinning-style): reads GpuSplat[] (rest, or the previous deformer's output when
// several deformers apply in order, in place) and writes deformed centres, normals and splat axes.
// normal.w toggles (1 -> 0) when the splat's cell is inverted (det J < 0); stats[0] counts them.
#include "ffd/ffd_common.glsl"

// FFD_LOCAL_SIZE: 64, or 256 with FFD_CP_SHARED (the shared copy, 16 KB for 11³ points, amortised over
// more splats per group, and more groups resident per multiprocessor). GpuDeformer dispatches the same size.
#ifndef FFD_LOCAL_SIZE
#define FFD_LOCAL_SIZE 64
#endif
layout(local_size_x = FFD_LOCAL_SIZE) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_SSBO_SPLATS_IN) readonly buffer SplatsIn { GpuSplat splats_in[]; };
layout(std430, binding = SFFD_SSBO_SPLATS_OUT) writeonly buffer SplatsOut { GpuSplat splats_out[]; };
layout(std430, binding = SFFD_SSBO_STATS) buffer Stats { uint stats[]; };  // [0] inverted, [1] inside

void main() {
    uint id = sffd_dispatch_index();
#ifdef FFD_CP_SHARED
    // Every invocation of the group copies its share, then all wait (uniform control flow: before any
    // return). Only the displacements' xyz travel.
    for (uint c = gl_LocalInvocationIndex; c < uint(FFD_CP_SHARED); c += gl_WorkGroupSize.x) {
        vec3 d = ffd_dp[c].xyz;
        ffd_dp_shared[3u * c] = d.x;
        ffd_dp_shared[3u * c + 1u] = d.y;
        ffd_dp_shared[3u * c + 2u] = d.z;
    }
    memoryBarrierShared();
    barrier();
#endif
    if (id >= ffd_count.x) return;
    GpuSplat s = splats_in[id];
    vec3 stu = ffd_local(s.center.xyz);
    bool culled = ffd_count.y != 0u || !ffd_inside(stu) ||
                  (ffd_div.w == 1 && (any(lessThanEqual(stu, ffd_cull_lo.xyz)) || any(greaterThanEqual(stu, ffd_cull_hi.xyz))));
    if (culled) {
        if (ffd_inside(stu)) atomicAdd(stats[1], 1u);
        splats_out[id] = s;
        return;
    }
    atomicAdd(stats[1], 1u);
    vec3 D;
    mat3 G;
    ffd_eval(stu, true, D, G);
    mat3 J = ffd_jacobian(G);
    float det = determinant(J);
    GpuSplat o;
    o.center = vec4(s.center.xyz + D, s.center.w);
    o.normal = vec4(ffd_cofactor_normal(J, s.normal.xyz), det < 0.0 ? 1.0 - s.normal.w : s.normal.w);
    o.axis_u = vec4(J * s.axis_u.xyz, s.axis_u.w);
    o.axis_v = vec4(J * s.axis_v.xyz, s.axis_v.w);
    if (det < 0.0) atomicAdd(stats[0], 1u);
    splats_out[id] = o;
}
