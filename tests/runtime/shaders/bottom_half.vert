#version 450 core
// A quad (triangle strip, 4 vertices) covering the bottom half of the target: NDC y in [-1, 0], z = 0.5.
const vec2 corners[4] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 0.0), vec2(1.0, 0.0));
void main() { gl_Position = vec4(corners[gl_VertexID], 0.5, 1.0); }
