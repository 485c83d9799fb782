#version 450 core
// Attachment 0 (RGBA8): a uniform colour. Attachment 1 (R32F): the pixel column.
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_column;
uniform vec4 u_color;
void main() {
    out_color = u_color;
    out_column = floor(gl_FragCoord.x);
}
