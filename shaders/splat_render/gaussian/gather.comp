#version 450 core
// The projection in depth order: position p of range `u_first` (bound from there) takes the Gaussian
// order[p] if that Gaussian lies in the source range bound now (u_src_first, u_src_count), so the blend
// reads the depth-ordered arrays front to back, range by range, and never needs the whole cloud in one
// storage block (GL_MAX_SHADER_STORAGE_BLOCK_SIZE). gl_render dispatches it once per (destination range,
// source range) pair; each position is written by exactly one of them. With u_write_command, invocation 0
// also writes the quads' draw of this destination range: its positions below the drawn count.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_ORDER) readonly buffer Order { uint order[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) readonly buffer ProjColor { vec4 proj_color[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_SORTED_CENTER) writeonly buffer SortedCenter { vec4 sorted_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_SORTED_CONIC) writeonly buffer SortedConic { vec4 sorted_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_SORTED_COLOR) writeonly buffer SortedColor { vec4 sorted_color[]; };
// project.comp's command and coverage, then the per-range commands (SFFD_GAUSS_DRAW_RANGE_COMMANDS).
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) buffer Draw {
    uint vertex_count, instance_count, first, base_instance;
    uint covered_pixels, covered_wrapped, pad0, pad1;
    uvec4 range_commands[];
};

uniform uint u_count;      // positions in this destination range
uniform uint u_first;      // depth-order position of its first element
uniform uint u_src_first;  // Gaussian index of the source range's first element
uniform uint u_src_count;
uniform uint u_range;      // index of this destination range (its command)
uniform int u_write_command;

void main() {
    const uint p = sffd_dispatch_index();
    if (p == 0u && u_write_command != 0) {
        const uint drawn = instance_count > u_first ? min(instance_count - u_first, u_count) : 0u;
        range_commands[u_range] = uvec4(4u, drawn, 0u, 0u);
    }
    if (p >= u_count || u_first + p >= instance_count) return;
    const uint i = order[p] - u_src_first;  // wraps past u_src_count when before the source range
    if (i >= u_src_count) return;
    sorted_center[p] = proj_center[i];
    sorted_conic[p] = proj_conic[i];
    sorted_color[p] = proj_color[i];
}
