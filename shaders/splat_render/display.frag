#version 450
// Display copy for a window: the linear colour target composited over the background and sRGB-encoded
// into an RGBA8 texture, so the present phase's plain blit shows correct colours. A reduced preview frame
// (RenderSettings::preview_divider) covers the target's lower-left corner: u_scale maps a window pixel
// into it (nearest; 1, 1 for a full frame, where it is the pixel itself).
#include "common/bindings.h"
#include "splat_render/frame_block.h"

layout(binding = SFFD_TEX_ACCUM_COLOR) uniform sampler2D linear_color;
layout(location = SFFD_LOC_DISPLAY_SCALE) uniform vec2 u_scale;
layout(location = 0) out vec4 out_color;

// The sRGB curve from three square roots instead of pow (exp2 and log2): within 0.25 of an 8-bit step of
// 1.055 c^(1/2.4) - 0.055 over [0.0031308, 1], so at most one step off where the exact value lies near a
// rounding boundary. A CPU rasteriser evaluates this for every pixel of the window each frame: pow was a
// third of this pass there.
vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    vec3 s1 = sqrt(c), s2 = sqrt(s1), s3 = sqrt(s2);
    vec3 curve = 0.662002687 * s1 + 0.684122060 * s2 - 0.323583601 * s3 - 0.0225411470 * c;
    return mix(c * 12.92, curve, greaterThan(c, vec3(0.0031308)));
}

void main() {
    vec4 c = texelFetch(linear_color, ivec2(gl_FragCoord.xy * u_scale), 0);
    out_color = vec4(linear_to_srgb(mix(frame.background.rgb, c.rgb, clamp(c.a, 0.0, 1.0))), 1.0);
}
