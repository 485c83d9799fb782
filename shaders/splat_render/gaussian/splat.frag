#version 450 core
// Front-to-back blending (GL_ONE_MINUS_DST_ALPHA, GL_ONE): dst.rgb += T c α, dst.a += T α with
// T = 1 − dst.a, the transmittance, as in the 3DGS rasterizer (without its early stop at T < 1e-4).
uniform vec2 u_size;

flat in vec2 v_center;
flat in vec4 v_conic_opacity;
flat in vec3 v_color;

layout(location = 0) out vec4 out_color;

void main() {
    const vec2 pix = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);  // y down, pixel centres at +0.5
    const vec2 d = pix - v_center;
    const vec3 k = v_conic_opacity.xyz;
    const float power = -0.5 * (k.x * d.x * d.x + k.z * d.y * d.y) - k.y * d.x * d.y;
    if (power > 0.0) discard;
    const float alpha = min(0.99, v_conic_opacity.w * exp(power));
    if (alpha < 1.0 / 255.0) discard;
    out_color = vec4(v_color * alpha, alpha);
}
