// Per-point marks in the draw passes (layout: common/bindings.h, "Per-point marks"; uploaded by the
// residency, runtime/gfx/point_marks.h). point_mark(i, mode) is drawn element i's mark: without
// SFFD_MARKS_PRESENT nothing is read and every point is visible, unselected, of weight 1. The C++ twin
// of every function here is in runtime/gfx/point_marks.h (the CPU cull draws the same colours).
#ifndef SFFD_POINT_MARKS_GLSL
#define SFFD_POINT_MARKS_GLSL

#include "common/bindings.h"

layout(std430, binding = SFFD_SSBO_POINT_MARKS) readonly buffer PointMarks { uint point_marks[]; };
layout(std430, binding = SFFD_SSBO_PREVIEW_INDEX) readonly buffer PreviewIndex { uint preview_index[]; };

const uint SFFD_MARK_DEFAULT = 0xff00u;  // visible, unselected, weight 1

uint point_mark(uint i, uint mode) {
    if ((mode & SFFD_MARKS_PRESENT) == 0u) return SFFD_MARK_DEFAULT;
    const uint j = (mode & SFFD_MARKS_INDEXED) != 0u ? preview_index[i] : i;
    return (point_marks[j >> 1u] >> ((j & 1u) << 4u)) & 0xffffu;
}

bool mark_gone(uint mark) { return (mark & SFFD_MARK_GONE) != 0u; }

// The weight overlay's ramp: blue (0) through green (0.5) to red (1).
vec3 weight_ramp(float w) {
    w = clamp(w, 0.0, 1.0);
    return w < 0.5 ? mix(vec3(0.0, 0.0, 1.0), vec3(0.0, 1.0, 0.0), 2.0 * w)
                   : mix(vec3(0.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), 2.0 * w - 1.0);
}

// The colour a mark shows `color` as: the weight ramp (SFFD_MARKS_WEIGHTS) in place of it, then half way
// to yellow when selected (SFFD_MARKS_SELECTION).
vec3 mark_overlay(vec3 color, uint mark, uint mode) {
    if ((mode & SFFD_MARKS_WEIGHTS) != 0u) color = weight_ramp(float(mark >> 8u) * (1.0 / 255.0));
    if ((mode & SFFD_MARKS_SELECTION) != 0u && (mark & SFFD_MARK_SELECTED) != 0u)
        color = mix(color, vec3(1.0, 0.85, 0.0), 0.5);
    return color;
}

#endif
