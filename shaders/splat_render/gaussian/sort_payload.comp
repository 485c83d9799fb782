#version 450 core
// GPU sort path: the payload of each depth key, the Gaussian's index in the whole cloud (the radix sort
// carries it to the front-to-back order). Its own pass, not project.comp's: that program already binds
// the 8 storage blocks GL 4.5 guarantees a compute shader. Run in element ranges like the projection.
#include "gaussian/gaussian_layout.h"

layout(local_size_x = 64) in;
#include "common/dispatch.glsl"

layout(std430, binding = SFFD_GAUSS_SSBO_ORDER) writeonly buffer Order { uint order[]; };

uniform uint u_count;
uniform uint u_base;  // index of this range's first Gaussian (the buffer is bound from it)

void main() {
    const uint i = sffd_dispatch_index();
    if (i < u_count) order[i] = u_base + i;
}
