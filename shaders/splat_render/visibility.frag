#version 450
// HQ pass 1: depth only. The true ray-ellipse depth, pushed back along the view ray by eps, so splats of
// the same surface within eps pass the attribute pass's depth test and blend.
#include "splat_render/raycast.glsl"

void main() {
    vec3 ray;
    float r2;
    float t = raycast_splat(ray, r2);
    float eps = v_plane.w;
    // Pushed back by eps along the ray: the view-axis depth grows by eps / |ray| (ray.z = -1).
    gl_FragDepth = window_depth(t + eps * inversesqrt(dot(ray, ray)));
}
