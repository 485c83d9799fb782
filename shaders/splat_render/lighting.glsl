// Blinn-Phong with directional lights and ambient, in linear space (world-space vectors).
#ifndef SFFD_LIGHTING_GLSL
#define SFFD_LIGHTING_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

vec3 shade_blinn_phong(vec3 albedo, vec3 n, vec3 to_eye) {
    vec3 color = frame.ambient.rgb * albedo;
    for (uint i = 0u; i < frame.counts.y; ++i) {
        vec3 l = frame.light_dir[i].xyz;
        float ndl = dot(n, l);
        if (ndl <= 0.0) continue;
        vec3 h = normalize(l + to_eye);
        float spec = pow(max(dot(n, h), 0.0), frame.material.y) * frame.material.x;
        color += frame.light_color[i].rgb * (albedo * ndl + vec3(spec));
    }
    return color;
}

// World-space direction from the surface towards the eye for this pixel.
vec3 pixel_to_eye_world() {
    vec2 ndc = gl_FragCoord.xy * frame.viewport.zw * 2.0 - 1.0;
    vec3 ray = vec3(ndc.x / frame.projection[0][0], ndc.y / frame.projection[1][1], -1.0);
    return -normalize(mat3(frame.view_to_world) * ray);
}

#endif
