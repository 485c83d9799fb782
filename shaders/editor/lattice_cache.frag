#version 450 core
// Lattice overlay line cache (systems/editor/lattice_overlay.cpp): the unchanged edges, drawn earlier into
// a texture as premultiplied colour and coverage (every edge blended at the same constant opacity), put
// over the frame: colour = cached + (1 - coverage) * frame through dual-source blending, alpha 1 where an
// edge is, as drawing the edges themselves leaves it. Pixels no edge covers keep the frame.
#include "common/bindings.h"

layout(binding = SFFD_TEX_OVERLAY_CACHE) uniform sampler2D u_cache;
layout(location = 0, index = 0) out vec4 o_color;
layout(location = 0, index = 1) out vec4 o_keep;

void main() {
    const vec4 c = texelFetch(u_cache, ivec2(gl_FragCoord.xy), 0);
    if (c.a <= 0.0) discard;
    o_color = vec4(c.rgb, 1.0);
    o_keep = vec4(1.0 - c.a);
}
