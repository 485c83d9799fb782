#version 450
// Compute rasteriser: copies the compute visibility depths into the depth target (full-screen triangle,
// depth test LESS, depth writes on), so it holds the minimum of both paths' visibility depths for the
// attribute passes and the shading pass's background test.
#include "splat_render/compute_raster.glsl"

void main() {
    uint d = raster_depth[raster_pixel(ivec2(gl_FragCoord.xy))];
    if (d >= RASTER_DEPTH_CLEAR) discard;
    gl_FragDepth = uintBitsToFloat(d);
}
