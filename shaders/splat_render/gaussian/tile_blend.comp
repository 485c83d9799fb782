#version 450 core
// Tile path, step 4: one work group per 16x16 tile, one invocation per pixel; the tile's Gaussians
// (front to back) are staged 256 at a time in shared memory and blended exactly like the CPU reference:
// only inside each Gaussian's pixel box, α = min(0.99, o·exp(power)), skipped below 1/255, and the pixel
// stops at the Gaussian that would take its transmittance below 1e-4 (3DGS's early termination). The
// whole group stops once every pixel has. Blends into what the target holds (rgb premultiplied, a = 1 − T:
// earlier clouds of the frame, or zero), like the quad path's (GL_ONE_MINUS_DST_ALPHA, GL_ONE).
// The render system's options, as its quads do (splat.vert, gaussian_accum.frag): a depth test against
// the surface splats (each Gaussian at its centre's depth, GL_LESS), and Σ T α view depth into a second
// target (x; w = coverage).
// Run once per range of the depth order, front to back (gl_render: the depth-ordered projection bound from
// u_src_first, so no block holds more than one range): each tile blends the part of its entries whose
// values (depth-order positions, ascending within a tile) fall in the range, carrying colour, transmittance
// and the stopped flag (u_state) in the images from one range to the next.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = SFFD_GAUSS_TILE, local_size_y = SFFD_GAUSS_TILE) in;

layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) readonly buffer ProjColor { vec4 proj_color[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_VALUES) readonly buffer TileValues { uint tile_values[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_RANGES) readonly buffer Ranges { uvec2 ranges[]; };
// Entries the groups staged before they stopped, summed over the frame (the work early termination left).
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_STATS) buffer TileStats { uint staged_entries; };
// Each pixel is read and written by its own invocation only.
layout(binding = SFFD_GAUSS_IMAGE_COLOR, rgba32f) uniform image2D u_color;
layout(binding = SFFD_GAUSS_IMAGE_DEPTH, rgba32f) uniform image2D u_depth_sum;
layout(binding = SFFD_GAUSS_IMAGE_STATE, rg32f) uniform image2D u_state;
layout(binding = 0) uniform sampler2D u_surface_depth;

uniform vec2 u_size;
uniform uvec2 u_tiles;
uniform int u_depth_test;   // 1: a Gaussian is hidden where u_surface_depth <= its window depth
uniform int u_write_depth;  // 1: accumulate u_depth_sum
uniform vec2 u_ndc_depth;   // NDC z = x + y / view depth, as splat.vert (clamped the same way)
uniform uint u_src_first;   // depth-order position of the bound range's first Gaussian
uniform uint u_src_count;   // Gaussians in the bound range

#include "splat_render/gaussian/tile_common.glsl"

const uint kBatch = SFFD_GAUSS_TILE * SFFD_GAUSS_TILE;
shared vec2 s_center[kBatch];
shared ivec4 s_box[kBatch];  // the Gaussian's clipped pixel box, computed once per batch, not per pixel
shared vec4 s_conic_opacity[kBatch];
shared vec3 s_color[kBatch];
shared vec2 s_depth[kBatch];  // window depth (the depth test's), view depth from the clamped NDC z
shared uint s_done;

// The first entry of `entries` whose value is at least `value` (the values ascend within a tile).
uint lower_bound(uvec2 entries, uint value) {
    uint lo = entries.x, hi = entries.y;
    while (lo < hi) {
        const uint mid = lo + (hi - lo) / 2u;
        if (tile_values[mid] < value) lo = mid + 1u;
        else hi = mid;
    }
    return lo;
}

// The tile's entries whose Gaussians lie in the bound range (uniform over the group).
uvec2 entries_in_source(uvec2 entries) {
    const uint begin = lower_bound(entries, u_src_first);
    return uvec2(begin, lower_bound(uvec2(begin, entries.y), u_src_first + u_src_count));
}

void main() {
    const uint tile = gl_WorkGroupID.y * u_tiles.x + gl_WorkGroupID.x;
    const uvec2 pixel = gl_GlobalInvocationID.xy;  // y down
    const bool inside = pixel.x < uint(u_size.x) && pixel.y < uint(u_size.y);
    const ivec2 texel = ivec2(pixel.x, int(u_size.y) - 1 - int(pixel.y));  // GL rows bottom-up
    const uint tid = gl_LocalInvocationIndex;
    const uvec2 range = entries_in_source(ranges[tile]);
    vec4 prior = inside ? imageLoad(u_color, texel) : vec4(0.0);
    vec3 color = prior.rgb;
    const vec2 state = inside ? imageLoad(u_state, texel).xy : vec2(0.0);
    float t = state.y > 0.5 ? state.x : 1.0 - prior.a;
    float depth_sum = inside && u_write_depth != 0 ? imageLoad(u_depth_sum, texel).x : 0.0;
    const float surface = inside && u_depth_test != 0 ? texelFetch(u_surface_depth, texel, 0).r : 2.0;
    bool done = !inside || t < 1e-4 || state.y > 1.5;
    uint staged = 0u;
    for (uint begin = range.x; begin < range.y; begin += kBatch) {
        // Every invocation reaches these barriers: the loop bounds are uniform over the group.
        if (tid == 0u) s_done = 0u;
        barrier();
        if (done) atomicAdd(s_done, 1u);
        if (begin + tid < range.y) {
            const uint g = tile_values[begin + tid] - u_src_first;
            const vec4 center_depth_radius = proj_center[g];
            s_center[tid] = center_depth_radius.xy;
            s_conic_opacity[tid] = proj_conic[g];
            s_box[tid] = pixel_box(center_depth_radius, s_conic_opacity[tid]);
            s_color[tid] = proj_color[g].rgb;
            const float z = clamp(u_ndc_depth.x + u_ndc_depth.y / center_depth_radius.z, -1.0, 0.999999);
            s_depth[tid] = vec2(0.5 * z + 0.5, u_ndc_depth.y / (z - u_ndc_depth.x));
        }
        barrier();
        if (s_done == kBatch) break;  // uniform: every invocation read the same count after the barrier
        const uint batch = min(kBatch, range.y - begin);
        staged += batch;
        for (uint j = 0u; j < batch && !done; ++j) {
            const ivec4 box = s_box[j];
            if (int(pixel.x) < box.x || int(pixel.x) > box.z || int(pixel.y) < box.y || int(pixel.y) > box.w) continue;
            if (s_depth[j].x >= surface) continue;
            const vec2 d = vec2(pixel) + 0.5 - s_center[j];
            const vec4 k = s_conic_opacity[j];
            const float power = -0.5 * (k.x * d.x * d.x + k.z * d.y * d.y) - k.y * d.x * d.y;
            if (power > 0.0) continue;
            const float alpha = min(0.99, k.w * exp(power));
            if (alpha < 1.0 / 255.0) continue;
            const float next = t * (1.0 - alpha);
            if (next < 1e-4) {
                done = true;
                break;
            }
            color += s_color[j] * (alpha * t);
            depth_sum += s_depth[j].y * (alpha * t);
            t = next;
        }
        barrier();  // the batch is read before the next one overwrites it
    }
    if (tid == 0u && staged > 0u) atomicAdd(staged_entries, staged);
    if (!inside) return;
    imageStore(u_color, texel, vec4(color, 1.0 - t));
    imageStore(u_state, texel, vec4(t, done ? 2.0 : 1.0, 0.0, 0.0));
    if (u_write_depth != 0) imageStore(u_depth_sum, texel, vec4(depth_sum, 0.0, 0.0, 1.0 - t));
}
