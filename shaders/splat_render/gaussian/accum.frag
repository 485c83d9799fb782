#version 450 core
// Render system's Gaussian pass (systems/splat_render/gaussian_pass.h): the Gaussian renderer's splat
// fragment (shaders/splat_render/gaussian/splat.frag: same conic, same 0.99 / (1/255) clamps), blended front to back
// (GL_ONE_MINUS_DST_ALPHA, GL_ONE) into two targets: premultiplied colour + coverage, and
// Σ T α view-depth (x) + coverage (w) for the aux output's depth where no surface splat is.
uniform vec2 u_size;
uniform vec2 u_ndc_depth;  // z_ndc = x + y / depth (the vertex shader's mapping), inverted for the depth

flat in vec2 v_center;
flat in vec4 v_conic_opacity;
flat in vec3 v_color;

layout(location = 0) out vec4 out_color;
#ifndef SFFD_GAUSS_COLOUR_ONLY  // defined for frames without aux outputs: no depth sum is blended
layout(location = 1) out vec4 out_depth;
#endif

void main() {
    const vec2 pix = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);  // y down, pixel centres at +0.5
    const vec2 d = pix - v_center;
    const vec3 k = v_conic_opacity.xyz;
    const float power = -0.5 * (k.x * d.x * d.x + k.z * d.y * d.y) - k.y * d.x * d.y;
    if (power > 0.0) discard;
    const float alpha = min(0.99, v_conic_opacity.w * exp(power));
    if (alpha < 1.0 / 255.0) discard;
    out_color = vec4(v_color * alpha, alpha);
#ifndef SFFD_GAUSS_COLOUR_ONLY
    const float z_ndc = 2.0 * gl_FragCoord.z - 1.0;
    const float depth = u_ndc_depth.y / (z_ndc - u_ndc_depth.x);
    out_depth = vec4(depth * alpha, 0.0, 0.0, alpha);
#endif
}
