#version 450 core
#include "common/bindings.h"

in vec4 v_color;
layout(location = SFFD_LOC_OVERLAY_POINTS) uniform int u_points;  // 1: round point sprites, 0: lines
layout(location = 0) out vec4 o_color;

void main() {
    if (u_points == 1) {
        vec2 d = gl_PointCoord * 2.0 - 1.0;
        float r2 = dot(d, d);
        if (r2 > 1.0) discard;
        // Dark rim so points read against any surface colour.
        o_color = r2 > 0.55 ? vec4(0.02, 0.02, 0.02, 1.0) : vec4(v_color.rgb, 1.0);
        return;
    }
    o_color = vec4(v_color.rgb, 1.0);
}
