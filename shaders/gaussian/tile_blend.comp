#version 450 core
// Tile path, step 4: one work group per 16x16 tile, one invocation per pixel; the tile's Gaussians
// (front to back) are staged 256 at a time in shared memory and blended exactly like the CPU reference:
// only inside each Gaussian's pixel box, α = min(0.99, o·exp(power)), skipped below 1/255, and the pixel
// stops at the Gaussian that would take its transmittance below 1e-4 (3DGS's early termination). The
// whole group stops once every pixel has. Writes rgb premultiplied and a = 1 − T, like the quad path.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = SFFD_GAUSS_TILE, local_size_y = SFFD_GAUSS_TILE) in;

layout(std430, binding = SFFD_GAUSS_SSBO_PROJECTED) readonly buffer Projected { GpuProjected projected[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_TILE_VALUES) readonly buffer TileValues { uint tile_values[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_RANGES) readonly buffer Ranges { uvec2 ranges[]; };
layout(binding = SFFD_GAUSS_IMAGE_COLOR, rgba32f) uniform writeonly image2D u_color;

uniform vec2 u_size;
uniform uvec2 u_tiles;

#include "gaussian/tile_common.glsl"

const uint kBatch = SFFD_GAUSS_TILE * SFFD_GAUSS_TILE;
shared vec2 s_center[kBatch];
shared ivec4 s_box[kBatch];  // the Gaussian's clipped pixel box, computed once per batch, not per pixel
shared vec4 s_conic_opacity[kBatch];
shared vec3 s_color[kBatch];
shared uint s_done;

void main() {
    const uint tile = gl_WorkGroupID.y * u_tiles.x + gl_WorkGroupID.x;
    const uvec2 pixel = gl_GlobalInvocationID.xy;  // y down
    const bool inside = pixel.x < uint(u_size.x) && pixel.y < uint(u_size.y);
    const uint tid = gl_LocalInvocationIndex;
    const uvec2 range = ranges[tile];
    bool done = !inside;
    vec3 color = vec3(0.0);
    float t = 1.0;
    for (uint begin = range.x; begin < range.y; begin += kBatch) {
        // Every invocation reaches these barriers: the loop bounds are uniform over the group.
        if (tid == 0u) s_done = 0u;
        barrier();
        if (done) atomicAdd(s_done, 1u);
        if (begin + tid < range.y) {
            const GpuProjected p = projected[tile_values[begin + tid]];
            s_center[tid] = p.center_depth_radius.xy;
            s_box[tid] = pixel_box(p.center_depth_radius);
            s_conic_opacity[tid] = p.conic_opacity;
            s_color[tid] = p.color.rgb;
        }
        barrier();
        if (s_done == kBatch) break;  // uniform: every invocation read the same count after the barrier
        const uint batch = min(kBatch, range.y - begin);
        for (uint j = 0u; j < batch && !done; ++j) {
            const ivec4 box = s_box[j];
            if (int(pixel.x) < box.x || int(pixel.x) > box.z || int(pixel.y) < box.y || int(pixel.y) > box.w) continue;
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
            t = next;
        }
        barrier();  // the batch is read before the next one overwrites it
    }
    if (inside) imageStore(u_color, ivec2(pixel.x, int(u_size.y) - 1 - int(pixel.y)), vec4(color, 1.0 - t));
}
