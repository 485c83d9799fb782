// Blinn-Phong with directional lights and ambient, in linear space (world-space vectors).
#ifndef SFFD_LIGHTING_GLSL
#define SFFD_LIGHTING_GLSL

#include "common/bindings.h"
#include "splat_render/frame_block.h"

// The loop has a constant bound so the compiler unrolls it and indexes the light arrays with constants
// (llvmpipe turns a dynamic UBO index into a per-lane gather); lights past counts.y have zero colour.
// pow() is spelled exp2(log2()) for the same reason: it is the cheap form on llvmpipe.
// LIGHTS: the bound, a define set per program variant to the scene's light count (llvmpipe runs both
// sides of a branch under a mask, so a `break` saves nothing there: every compiled light costs).
#ifndef LIGHTS
#define LIGHTS SFFD_MAX_LIGHTS
#endif
// One light's terms, shared by both loops below: ndl (diffuse cosine) and spec (Blinn-Phong highlight).
void blinn_phong_light(int i, vec3 n, vec3 to_eye, float specular, float shininess, out float ndl, out float spec) {
    vec3 l = frame.light_dir[i].xyz;
    ndl = max(dot(n, l), 0.0);
    vec3 h = normalize(l + to_eye);
    spec = ndl > 0.0 ? exp2(shininess * log2(max(dot(n, h), 1e-8))) * specular : 0.0;
}

vec3 shade_blinn_phong(vec3 albedo, vec3 n, vec3 to_eye, float specular, float shininess) {
    vec3 color = frame.ambient.rgb * albedo;
    for (int i = 0; i < LIGHTS; ++i) {
        if (uint(i) >= frame.counts.y) break;
        float ndl, spec;
        blinn_phong_light(i, n, to_eye, specular, shininess, ndl, spec);
        color += frame.light_color[i].rgb * (albedo * ndl + vec3(spec));
    }
    return color;
}

// The two factors of shade_blinn_phong: colour = albedo * diffuse + specular (the textured preview lights
// once per splat and textures per pixel). Same loop as above.
void blinn_phong_factors(vec3 n, vec3 to_eye, float specular, float shininess, out vec3 diffuse, out vec3 spec_sum) {
    diffuse = frame.ambient.rgb;
    spec_sum = vec3(0.0);
    for (int i = 0; i < LIGHTS; ++i) {
        if (uint(i) >= frame.counts.y) break;
        float ndl, spec;
        blinn_phong_light(i, n, to_eye, specular, shininess, ndl, spec);
        diffuse += frame.light_color[i].rgb * ndl;
        spec_sum += frame.light_color[i].rgb * spec;
    }
}

// With the material of the draw (frame.material: x specular, y shininess).
vec3 shade_blinn_phong(vec3 albedo, vec3 n, vec3 to_eye) {
    return shade_blinn_phong(albedo, n, to_eye, frame.material.x, frame.material.y);
}

#endif
