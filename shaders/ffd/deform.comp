#version 450 core
// FFD compute pass (skinning-style): reads GpuSplat[] (rest, or the previous deformer's output when
// several deformers apply in order, in place) and writes deformed centres, normals and splat axes.
// normal.w toggles (1 -> 0) when the splat's cell is inverted (det J < 0); counter 0 of each page
// counts them (ffd/page_stats.glsl).
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
layout(std430, binding = SFFD_SSBO_STATS) buffer Stats { uint stats[]; };  // per page: inverted, inside
#define SFFD_PAGE_COUNTERS 2u
#include "ffd/page_stats.glsl"

// The group's counts, added to its page's once per group: one global atomic per splat on the same two
// words serialised every splat of the dispatch on the GPU.
shared uint s_inverted, s_inside;

// Deforms splat `id`; returns bit 0: inside the lattice, bit 1: in an inverted cell.
uint deform_splat(uint id) {
    GpuSplat s = splats_in[id];
    vec3 stu = ffd_local(s.center);
    bool culled = ffd_count.y != 0u || !ffd_inside(stu) ||
                  (ffd_div.w == 1 && (any(lessThanEqual(stu, ffd_cull_lo.xyz)) || any(greaterThanEqual(stu, ffd_cull_hi.xyz))));
#ifdef FFD_WEIGHTS
    const float weight = ffd_weights[id];
    culled = culled || !(weight > 0.0);  // weight 0: at rest
#endif
    if (culled) {
        splats_out[id] = s;
        return ffd_inside(stu) ? 1u : 0u;
    }
    vec3 D;
    mat3 G;
    ffd_eval(stu, true, D, G);
#ifdef FFD_WEIGHTS
    D *= weight;  // X + w D, J_w = I + w G M⁻¹
    G *= weight;
#endif
    mat3 J = ffd_jacobian(G);
    float det = determinant(J);
    GpuSplat o;
    o.center = s.center + D;
    o.color = s.color;
    o.normal = vec4(ffd_cofactor_normal(J, s.normal.xyz), det < 0.0 ? 1.0 - s.normal.w : s.normal.w);
    o.axis_u = vec4(J * s.axis_u.xyz, s.axis_u.w);
    o.axis_v = vec4(J * s.axis_v.xyz, s.axis_v.w);
    splats_out[id] = o;
    return det < 0.0 ? 3u : 1u;
}

void main() {
    uint id = sffd_dispatch_index();
    if (gl_LocalInvocationIndex == 0u) {
        s_inverted = 0u;
        s_inside = 0u;
    }
#ifdef FFD_CP_SHARED
    ffd_share_control_points(gl_LocalInvocationIndex, gl_WorkGroupSize.x);
#endif
    memoryBarrierShared();
    barrier();
    const uint flags = id < ffd_count.x ? deform_splat(id) : 0u;
    const bool one_page = ffd_group_in_one_page(id);
    if (one_page) {
        if ((flags & 1u) != 0u) atomicAdd(s_inside, 1u);
        if ((flags & 2u) != 0u) atomicAdd(s_inverted, 1u);
    } else {  // a group across two pages counts point by point
        ffd_count_in_page(id, 1u, flags & 1u);
        ffd_count_in_page(id, 0u, (flags >> 1) & 1u);
    }
    memoryBarrierShared();
    barrier();
    if (one_page && gl_LocalInvocationIndex == 0u) {
        ffd_count_in_page(id, 1u, s_inside);
        ffd_count_in_page(id, 0u, s_inverted);
    }
}
