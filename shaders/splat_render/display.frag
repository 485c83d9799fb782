#version 450
// Display copy for a window: the linear colour target composited over the background and sRGB-encoded
// into an RGBA8 texture, so the present phase's plain blit shows correct colours.
#include "common/bindings.h"
#include "splat_render/frame_block.h"

layout(binding = SFFD_TEX_ACCUM_COLOR) uniform sampler2D linear_color;
layout(location = 0) out vec4 out_color;

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    vec4 c = texelFetch(linear_color, ivec2(gl_FragCoord.xy), 0);
    out_color = vec4(linear_to_srgb(mix(frame.background.rgb, c.rgb, clamp(c.a, 0.0, 1.0))), 1.0);
}
