#version 450 core
// Render system's Gaussian pass, last step: the Gaussians' front-to-back result (premultiplied G, coverage
// A) over the surface splats' colour (straight S, coverage Sa; copied before this pass, the output target
// is written here). 3DGS colours are display-referred (sRGB values, blended in that space by the 3DGS
// rasterizer), the target is linear: the blend C = G + (1 − A) Sa sRGB(S), coverage A + (1 − A) Sa, happens
// in display space and C / coverage goes back to linear, so a PNG of a Gaussian scene holds the colours the
// 3DGS reference computes. Pixels no Gaussian covers keep S exactly. The aux output keeps the surface's
// normal + depth where a surface splat is, else gets the Gaussians' mean depth (normal 0) where they cover.
layout(binding = 0) uniform sampler2D gauss_color;
layout(binding = 1) uniform sampler2D gauss_depth;
layout(binding = 2) uniform sampler2D surface_color;
layout(binding = 3) uniform sampler2D surface_aux;
uniform int u_aux;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

vec3 to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}
vec3 to_linear(vec3 c) {
    c = max(c, vec3(0.0));
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

void main() {
    const ivec2 p = ivec2(gl_FragCoord.xy);
    const vec4 g = texelFetch(gauss_color, p, 0);
    const vec4 s = texelFetch(surface_color, p, 0);
    vec4 aux = u_aux != 0 ? texelFetch(surface_aux, p, 0) : vec4(0.0, 0.0, 0.0, -1.0);
    if (!(g.a > 0.0)) {
        out_color = s;
        out_aux = aux;
        return;
    }
    const float sa = clamp(s.a, 0.0, 1.0);
    const float a = g.a + (1.0 - g.a) * sa;
    const vec3 display = g.rgb + (1.0 - g.a) * sa * to_srgb(s.rgb);
    out_color = vec4(to_linear(display / a), a);
    if (u_aux != 0 && aux.w < 0.0) aux = vec4(0.0, 0.0, 0.0, texelFetch(gauss_depth, p, 0).x / g.a);
    out_aux = aux;
}
