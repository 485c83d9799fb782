// Texel addressing shared by the CPU's texture lookups (the reduced preview's per-splat colours,
// cpu_cull.h, the CPU sprite rasteriser's, cpu_raster.h, and the ground truth's, ground_truth.h), as GL
// samples the material texture (render_state.cpp): mip levels halve, rounded down, to 1; bilinear between
// texel centres with u repeating and v clamped to the edge; trilinear between levels.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace sffd::render {

// The four texels a bilinear lookup at (u, v) reads in a width x height level and its weights along x, y.
template <class T>
struct BilinearTaps {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    T ax = 0, ay = 0;
};

// |u|, |v| must be under about 1e6 (the cull and the ray tracer check).
template <class T>
BilinearTaps<T> bilinear_taps(T u, T v, int width, int height) {
    const T x = u * T(width) - T(0.5), y = v * T(height) - T(0.5);
    const T fx = std::floor(x), fy = std::floor(y);
    auto wrap = [](long i, int n) { return int(((i % n) + n) % n); };
    BilinearTaps<T> t;
    t.x0 = wrap(long(fx), width), t.x1 = wrap(long(fx) + 1, width);
    t.y0 = std::clamp(int(fy), 0, height - 1), t.y1 = std::clamp(int(fy) + 1, 0, height - 1);
    t.ax = x - fx, t.ay = y - fy;
    return t;
}

// The levels GL_LINEAR_MIPMAP_LINEAR blends at level of detail lambda in a texture whose last level is
// `last`: level 0 alone when magnified (lambda <= 0, or NaN), the last alone past it, else the two around
// lambda mixed by its fraction (lo's weight 1 - f, hi's f).
template <class T>
struct LevelBlend {
    int lo = 0, hi = 0;
    T f = 0;
};
template <class T>
LevelBlend<T> trilinear_levels(T lambda, int last) {
    if (!(lambda > T(0))) return {};
    if (lambda >= T(last)) return {last, last, T(0)};
    const T lo = std::floor(lambda);
    return {int(lo), int(lo) + 1, lambda - lo};
}

// The next mip level's size.
inline glm::ivec2 next_level_size(glm::ivec2 size) {
    return {std::max(size.x / 2, 1), std::max(size.y / 2, 1)};
}

// Texel (x, y) of the next level below a width x height one: the mean of its 2x2 texels (edge texels
// repeat where the size is odd), read through texel(x, y) -> glm::vec4.
template <class Texel>
glm::vec4 mean_2x2(int x, int y, int width, int height, Texel&& texel) {
    glm::vec4 sum(0.0f);
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx)
            sum += texel(std::min(2 * x + dx, width - 1), std::min(2 * y + dy, height - 1));
    return sum * 0.25f;
}

}  // namespace sffd::render
