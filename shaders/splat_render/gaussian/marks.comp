#version 450 core
// Per Gaussian, after the projection (project.comp), for a cloud with point marks or an overlay
// (common/point_marks.glsl; GaussianBuffers::marks_mode): a hidden or deleted Gaussian that the
// projection drew is taken out (its sort key set to not drawn, the drawn count and the covered pixels
// lowered by what project.comp added for it, so the blend's choice is the one for the cloud without it),
// and a drawn one's colour shows the overlays (weight ramp, selection tint). A separate pass so that the projection
// keeps its eight storage blocks and clouds without marks pay nothing.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"
#include "common/point_marks.glsl"
#include "splat_render/gaussian/footprint.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CENTER) readonly buffer ProjCenter { vec4 proj_center[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_CONIC) readonly buffer ProjConic { vec4 proj_conic[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_PROJ_COLOR) buffer ProjColor { vec4 proj_color[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DEPTH) buffer Depth { uint depth_keys[]; };
layout(std430, binding = SFFD_GAUSS_SSBO_DRAW) buffer Draw {
    uint vertex_count, instance_count, first, base_instance;
    uint covered_pixels, covered_wrapped;
};

uniform uint u_count;  // Gaussians of this range
uniform uint u_base;   // the range's first Gaussian: the marks are the whole cloud's
uniform uint u_mode;   // SFFD_MARKS_*
uniform vec2 u_size;   // image width, height (project.comp's)

shared uint s_removed, s_pixels;

void main() {
    const uint i = sffd_dispatch_index();
    if (gl_LocalInvocationID.x == 0u) s_removed = 0u, s_pixels = 0u;
    barrier();
    if (i < u_count && depth_keys[i] != SFFD_GAUSS_NOT_DRAWN) {
        const uint mark = point_mark(u_base + i, u_mode);
        if (mark_gone(mark)) {
            depth_keys[i] = SFFD_GAUSS_NOT_DRAWN;
            atomicAdd(s_removed, 1u);
            // The pixels project.comp counted for it (its narrowed box clipped to the image).
            const vec4 c = proj_center[i];
            const vec2 h = footprint_half_size(c.w, proj_conic[i]);
            const vec2 box = min(ceil(c.xy + h), u_size - 1.0) - max(floor(c.xy - h), vec2(0.0)) + 1.0;
            if (all(greaterThan(box, vec2(0.0)))) atomicAdd(s_pixels, uint(box.x) * uint(box.y));
        } else if ((u_mode & (SFFD_MARKS_SELECTION | SFFD_MARKS_WEIGHTS)) != 0u) {
            proj_color[i].rgb = mark_overlay(proj_color[i].rgb, mark, u_mode);
        }
    }
    barrier();
    if (gl_LocalInvocationID.x == 0u && s_removed > 0u) {
        atomicAdd(instance_count, 0u - s_removed);
        // A sum that wrapped stays flagged (covered_wrapped): it is past any budget either way.
        atomicAdd(covered_pixels, 0u - s_pixels);
    }
}
