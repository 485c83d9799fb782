#version 450 core
// Paper mode (Beddiaf & Babahenini): the FFD runs in the vertex shader, once per vertex per pass per
// frame, instead of once per edit in the compute pass. PAPER_DEFORM=1: deform rest splats here;
// PAPER_DEFORM=0: draw splats the compute pass already deformed (the comparison's other side).
#include "ffd/ffd_common.glsl"

layout(std430, binding = SFFD_SSBO_SPLATS_IN) readonly buffer SplatsIn { GpuSplat splats_in[]; };

layout(location = 0) uniform mat4 u_view_proj;
layout(location = 1) uniform float u_point_size;

out vec3 v_normal;

void main() {
    GpuSplat s = splats_in[gl_VertexID];
    vec3 p = s.center;
    vec3 n = s.normal.xyz;
#if PAPER_DEFORM
    vec3 stu = ffd_local(p);
    if (ffd_count.y == 0u && ffd_inside(stu)) {
        vec3 D;
        mat3 G;
        ffd_eval(stu, true, D, G);
        p += D;
        n = ffd_cofactor_normal(ffd_jacobian(G), n);
    }
#endif
    v_normal = n;
    gl_Position = u_view_proj * vec4(p, 1.0);
    gl_PointSize = u_point_size;
}
