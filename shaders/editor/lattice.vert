#version 450 core
// Lattice overlay (systems/editor/lattice_overlay.cpp): control points as round sprites, cell edges as
// lines. Positions are relative to `u_anchor` (the lattice origin), so lattices far from the world
// origin stay precise in float; u_view_proj already contains the translation to the anchor.
#include "common/bindings.h"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec4 a_color;
layout(location = 2) in float a_size;

layout(location = SFFD_LOC_OVERLAY_VIEW_PROJ) uniform mat4 u_view_proj;
layout(location = SFFD_LOC_OVERLAY_PIXEL) uniform float u_pixel;  // sizes are in window pixels

out vec4 v_color;

void main() {
    gl_Position = u_view_proj * vec4(a_position, 1.0);
    // Pull the overlay a hair towards the camera so points sitting on the surface win the depth test.
    gl_Position.z -= 1e-4 * gl_Position.w;
    gl_PointSize = max(a_size * u_pixel, 1.0);
    v_color = a_color;  // opacity is the blend constant (lattice_overlay.cpp)
}
