#version 450 core
// Render system's Gaussian pass, last step: the Gaussians' front-to-back result (premultiplied G, coverage
// A) over the surface splats' colour (straight S, coverage Sa; copied before this pass, the output target
// is written here): premultiplied C = G + (1 − A) Sa S, coverage A + (1 − A) Sa, stored straight like
// every other writer of the target. The aux output keeps the surface's normal + depth where a surface
// splat is, else gets the Gaussians' mean depth (normal 0) where they cover the pixel.
layout(binding = 0) uniform sampler2D gauss_color;
layout(binding = 1) uniform sampler2D gauss_depth;
layout(binding = 2) uniform sampler2D surface_color;
layout(binding = 3) uniform sampler2D surface_aux;
uniform int u_aux;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

void main() {
    const ivec2 p = ivec2(gl_FragCoord.xy);
    const vec4 g = texelFetch(gauss_color, p, 0);
    const vec4 s = texelFetch(surface_color, p, 0);
    const float sa = clamp(s.a, 0.0, 1.0);
    const float a = g.a + (1.0 - g.a) * sa;
    const vec3 premultiplied = g.rgb + (1.0 - g.a) * sa * s.rgb;
    out_color = a > 0.0 ? vec4(premultiplied / a, a) : s;
    vec4 aux = u_aux != 0 ? texelFetch(surface_aux, p, 0) : vec4(0.0, 0.0, 0.0, -1.0);
    if (aux.w < 0.0 && g.a > 0.0) aux = vec4(0.0, 0.0, 0.0, texelFetch(gauss_depth, p, 0).x / g.a);
    out_aux = aux;
}
