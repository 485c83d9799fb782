#version 450 core
// Refreshes the window's sRGB display copy after the lattice overlay was drawn into the linear colour
// target (same conversion as splat_render/display.frag, which runs inside render_system, before the
// overlay): colour over the background, sRGB-encoded.
uniform sampler2D u_linear_color;
uniform vec3 u_background;
layout(location = 0) out vec4 o_color;

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    vec4 c = texelFetch(u_linear_color, ivec2(gl_FragCoord.xy), 0);
    o_color = vec4(linear_to_srgb(mix(u_background, c.rgb, clamp(c.a, 0.0, 1.0))), 1.0);
}
