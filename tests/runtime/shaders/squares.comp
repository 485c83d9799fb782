#version 450 core
// Test: writes data[i] = i * i + OFFSET (OFFSET injected by the loader) through a helper in lib/.
#include "lib/square.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Out { uint data[]; };
uniform uint u_count;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < u_count) data[i] = square(i) + uint(OFFSET);
}
