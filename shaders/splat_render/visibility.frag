#version 450
// HQ pass 1: depth only. The true ray-ellipse depth, pushed back along the view ray by eps, so splats of
// the same surface within eps pass the attribute pass's depth test and blend.
#include "splat_render/raycast.glsl"

void main() {
    vec3 ray;
    float r2;
    vec3 p = raycast_splat(ray, r2);
    p += normalize(ray) * v_eps;
    gl_FragDepth = window_depth(p.z);
}
