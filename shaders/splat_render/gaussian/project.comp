#version 450 core
// Per Gaussian: EWA projection to a 2D conic with the 0.3 px² low-pass, footprint radius, SH colour.
// The same steps as the CPU reference (systems/gaussian/reference_render.cpp), in float.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"
#include "splat_render/gaussian/footprint.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_IN) readonly buffer Gaussians { GpuGaussian gaussians[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_SH) readonly buffer Sh { float sh[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) writeonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) writeonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) writeonly buffer ProjColor { vec4 proj_color[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_FRAMES) readonly buffer Frames { vec4 frames[]; };
// The GPU sort's payloads are written by sort_payload.comp: one more block here would be a ninth.
layout(std430, binding = SFFD_GAUSS_SSBO_DEPTH) writeonly buffer Depth { uint depth_keys[]; };
// DrawArraysIndirectCommand; instance_count counts the drawn Gaussians (zeroed by the CPU before the pass).
// Then the pixels the drawn Gaussians' clipped pixel boxes cover, summed (the quad path's fragments), and
// a flag set when that sum wrapped: gl_render's draw_gaussians picks quads or tiles from them.
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) buffer Draw {
    uint vertex_count, instance_count, first, base_instance;
    uint covered_pixels, covered_wrapped;
};

uniform mat4 u_view;        // cloud (origin-relative) -> camera, composed in double on the CPU
uniform vec3 u_eye;         // camera position relative to the cloud origin
uniform vec2 u_size;        // image width, height
uniform float u_focal;      // pixels
uniform vec2 u_limit;       // 1.3 x tan(half fov) per axis (3DGS clamps x/z, y/z for the Jacobian)
uniform float u_near;
uniform uint u_count;
uniform int u_degree;
uniform int u_frames;       // 1: evaluate the SH at frameᵀ d (GaussianCloud::sh_frames)
uniform float u_min_footprint;  // > 0 (preview): skip Gaussians whose unfiltered 3σ radius is below it, px

const float C0 = 0.28209479177387814;
const float C1 = 0.4886025119029199;
const float C2[5] = float[5](1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396);
const float C3[7] = float[7](-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
                             -0.4570457994644658, 1.445305721320277, -0.5900435899266435);

vec3 coeff(uint base, int k) { uint o = base + uint(k) * 3u; return vec3(sh[o], sh[o + 1u], sh[o + 2u]); }

vec3 sh_color(uint i, vec3 d) {
    const int K = (u_degree + 1) * (u_degree + 1);
    const uint base = i * uint(K) * 3u;
    vec3 c = C0 * coeff(base, 0);
    if (u_degree >= 1) {
        float x = d.x, y = d.y, z = d.z;
        c += -C1 * y * coeff(base, 1) + C1 * z * coeff(base, 2) - C1 * x * coeff(base, 3);
        if (u_degree >= 2) {
            float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
            c += C2[0] * xy * coeff(base, 4) + C2[1] * yz * coeff(base, 5) + C2[2] * (2.0 * zz - xx - yy) * coeff(base, 6) +
                 C2[3] * xz * coeff(base, 7) + C2[4] * (xx - yy) * coeff(base, 8);
            if (u_degree >= 3) {
                c += C3[0] * y * (3.0 * xx - yy) * coeff(base, 9) + C3[1] * xy * z * coeff(base, 10) +
                     C3[2] * y * (4.0 * zz - xx - yy) * coeff(base, 11) + C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * coeff(base, 12) +
                     C3[4] * x * (4.0 * zz - xx - yy) * coeff(base, 13) + C3[5] * z * (xx - yy) * coeff(base, 14) +
                     C3[6] * x * (xx - 3.0 * yy) * coeff(base, 15);
            }
        }
    }
    return max(c + 0.5, vec3(0.0));
}

// Whether every component is finite, from the bits (exponent not all ones). GLSL leaves comparisons with
// NaN undefined and NVIDIA folds `!(x >= y)` into `x < y`, so NaN is caught here and never reaches a
// comparison (as in splat_common.glsl's all_finite; splat_record.h).
bool finite4(vec4 v) {
    return all(notEqual(floatBitsToUint(v) & 0x7f800000u, uvec4(0x7f800000u)));
}

// One Gaussian's projection, stored in the three SFFD_GAUSS_SSBO_PROJ_* arrays (gaussian_layout.h).
struct Projection {
    vec4 center_depth_radius;
    vec4 conic_opacity;
    vec4 color;
};

void store(uint i, Projection o) {
    proj_center[i] = o.center_depth_radius;
    proj_conic[i] = o.conic_opacity;
    proj_color[i] = o.color;
}

// Projects Gaussian i; true when it is drawn. Writes its projection and sort key, and the
// pixels of its pixel box clipped to the image (tile_common.glsl's pixel_box, the narrowed box).
bool project(uint i, out uint pixels) {
    pixels = 0u;
    Projection o;
    o.center_depth_radius = vec4(0.0);
    o.conic_opacity = vec4(0.0);
    o.color = vec4(0.0);
    const GpuGaussian g = gaussians[i];
    depth_keys[i] = SFFD_GAUSS_NOT_DRAWN;
    // Culled: non-finite centres, opacities, rotations or scales (the loaders refuse them; a deformation
    // can still produce them).
    if (!finite4(g.pos_opacity) || !finite4(g.rotation) || !finite4(vec4(g.scale.xyz, 0.0))) {
        store(i, o);
        return false;
    }
    const vec3 t = (u_view * vec4(g.pos_opacity.xyz, 1.0)).xyz;
    const float depth = -t.z;
    if (!finite4(vec4(t, 0.0)) || depth < u_near) { store(i, o); return false; }
    // Culled too: opacity below 1/255 (every α = min(0.99, o·exp(power ≤ 0)) ≤ o would be skipped, as in
    // the reference).
    if (g.pos_opacity.w < 1.0 / 255.0) { store(i, o); return false; }
    // Σ = R S Sᵀ Rᵀ from the quaternion (w, x, y, z).
    const float w = g.rotation.x, x = g.rotation.y, y = g.rotation.z, z = g.rotation.w;
    const mat3 r = mat3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y),
                        2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x),
                        2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y));
    const mat3 m = r * mat3(g.scale.x, 0.0, 0.0, 0.0, g.scale.y, 0.0, 0.0, 0.0, g.scale.z);
    const mat3 wv = mat3(u_view);
    const mat3 v = wv * (m * transpose(m)) * transpose(wv);
    const float tx = clamp(t.x / depth, -u_limit.x, u_limit.x) * depth;
    const float ty = clamp(t.y / depth, -u_limit.y, u_limit.y) * depth;
    const vec3 jx = vec3(u_focal / depth, 0.0, u_focal * tx / (depth * depth));
    const vec3 jy = vec3(0.0, -u_focal / depth, -u_focal * ty / (depth * depth));
    const float a = dot(jx, v * jx) + 0.3, b = dot(jx, v * jy), c = dot(jy, v * jy) + 0.3;
    const float det = a * c - b * b;
    // Overflow (inf - inf) can still make NaN from finite inputs: test the bits before comparing.
    if (!finite4(vec4(a, b, c, det)) || det <= 0.0) { store(i, o); return false; }
    const float mid = 0.5 * (a + c), lmax = mid + sqrt(max(0.1, mid * mid - det));
    if (u_min_footprint > 0.0) {
        // Largest eigenvalue of the footprint without the low-pass (trace - 0.6 = 2 mid - 0.6, det of the
        // unfiltered 2x2): a Gaussian under a pixel only blurs its neighbours in a moving preview.
        const float a0 = a - 0.3, c0 = c - 0.3, mid0 = 0.5 * (a0 + c0);
        const float lmax0 = mid0 + sqrt(max(0.0, mid0 * mid0 - (a0 * c0 - b * b)));
        if (9.0 * max(lmax0, 0.0) < u_min_footprint * u_min_footprint) { store(i, o); return false; }
    }
    const vec2 center = vec2(0.5 * u_size.x + u_focal * t.x / depth, 0.5 * u_size.y - u_focal * t.y / depth);
    const float radius = ceil(3.0 * sqrt(lmax));
    // Culling before the sort: a pixel box (floor(c - r) .. ceil(c + r), the reference's) entirely off
    // the image is not drawn, like the reference's empty clipped box.
    const vec2 lo = floor(center - radius), hi = ceil(center + radius);
    if (any(lessThan(hi, vec2(0.0))) || any(greaterThan(lo, u_size - 1.0))) { store(i, o); return false; }
    depth_keys[i] = floatBitsToUint(depth);
    o.center_depth_radius = vec4(center, depth, radius);
    o.conic_opacity = vec4(c / det, -b / det, a / det, g.pos_opacity.w);
    // The coverage counts the pixels the quads and tiles visit: the box narrowed to where the Gaussian can
    // be seen (footprint.glsl), which may lie wholly off the image even where the square does not.
    const vec2 h = footprint_half_size(radius, o.conic_opacity);
    const vec2 box = min(ceil(center + h), u_size - 1.0) - max(floor(center - h), vec2(0.0)) + 1.0;
    pixels = all(greaterThan(box, vec2(0.0))) ? uint(box.x) * uint(box.y) : 0u;
    vec3 dir = normalize(g.pos_opacity.xyz - u_eye);
    if (u_frames != 0) dir = transpose(mat3(frames[3u * i].xyz, frames[3u * i + 1u].xyz, frames[3u * i + 2u].xyz)) * dir;
    o.color = vec4(sh_color(i, dir), 0.0);
    store(i, o);
    return true;
}

shared uint s_drawn, s_pixels, s_wrapped;

void main() {
    // 2D grid of groups for clouds over 64 x 65,535 Gaussians (the guaranteed groups per dimension).
    const uint i = sffd_dispatch_index();
    uint pixels = 0u;
    const bool drawn = i < u_count && project(i, pixels);
    // The drawn count reaches the indirect draw without a readback: one global atomic per group; so do the
    // covered pixels. Their sums may wrap 32 bits: the addition that wraps one says so (atomicAdd returns
    // the value before it).
    if (gl_LocalInvocationID.x == 0u) {
        s_drawn = 0u;
        s_pixels = 0u;
        s_wrapped = 0u;
    }
    barrier();
    if (drawn) {
        atomicAdd(s_drawn, 1u);
        const uint before = atomicAdd(s_pixels, pixels);
        if (before + pixels < before) atomicOr(s_wrapped, 1u);
    }
    barrier();
    if (gl_LocalInvocationID.x == 0u && s_drawn > 0u) {
        atomicAdd(instance_count, s_drawn);
        const uint before = atomicAdd(covered_pixels, s_pixels);
        if (before + s_pixels < before || s_wrapped != 0u) atomicOr(covered_wrapped, 1u);
    }
}
