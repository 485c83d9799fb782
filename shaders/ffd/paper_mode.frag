#version 450 core
// Round point sprites with two-sided Lambert shading (enough to see the shape; the real splat renderer
// lives in shaders/splat_render).
in vec3 v_normal;
layout(location = 0) out vec4 o_color;

void main() {
    vec2 d = gl_PointCoord * 2.0 - 1.0;
    if (dot(d, d) > 1.0) discard;
    vec3 n = normalize(v_normal);
    float lambert = abs(dot(n, normalize(vec3(0.4, 0.6, 0.7))));
    o_color = vec4(vec3(0.15 + 0.85 * lambert), 1.0);
}
