// Per-point marks: what the draw passes know of a cloud's PointFlags and PointWeights
// (runtime/scene/point_columns.h), one 16-bit mark a point (layout: shaders/common/bindings.h,
// "Per-point marks"). No GL here: the CPU cull colours and drops points with the same functions as the
// shaders (shaders/common/point_marks.glsl), and the residency packs the marks it uploads with them.
//
// Who writes what: residency_system (phase `residency`) uploads a cloud's marks into
// ResidentCloud::marks when its PointFlags or PointWeights change, only the pages whose selection,
// visibility or weight stamps moved (point_pages.h), and never touches the cloud's other buffers, so a
// selection, hide or weight edit re-deforms and re-uploads no position. A cloud with neither column (or
// both empty) has no marks buffer and its passes read none (mode 0).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "runtime/scene/point_columns.h"
#include "shaders/common/bindings.h"

namespace sffd::gfx {

inline constexpr std::uint16_t kDefaultPointMark = 0xff00u;  // visible, unselected, weight 1

// One point's mark: its flag byte and its weight as unorm8 (non-finite: 1, as the deformers read it).
inline std::uint16_t pack_point_mark(std::uint8_t flags, float weight) {
    if (!std::isfinite(weight)) weight = 1.0f;
    const auto w8 = static_cast<std::uint16_t>(std::lround(std::clamp(weight, 0.0f, 1.0f) * 255.0f));
    return static_cast<std::uint16_t>(flags | (w8 << 8));
}

// Point i's mark from the columns (either may be null, empty or of another size: the default then).
inline std::uint16_t point_mark_of(const PointFlags* flags, const PointWeights* weights, std::size_t n,
                                   std::size_t i) {
    const std::uint8_t f = flags && flags->bits.size() == n ? flags->bits[i] : 0;
    const float w = weights && weights->values.size() == n ? weights->values[i] : 1.0f;
    return pack_point_mark(f, w);
}

inline bool mark_gone(std::uint16_t mark) { return (mark & SFFD_MARK_GONE) != 0; }

// The twins of point_marks.glsl's weight_ramp and mark_overlay, in the same float operations.
inline glm::vec3 weight_ramp(float w) {
    w = std::clamp(w, 0.0f, 1.0f);
    return w < 0.5f ? glm::mix(glm::vec3(0, 0, 1), glm::vec3(0, 1, 0), 2.0f * w)
                    : glm::mix(glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), 2.0f * w - 1.0f);
}
inline constexpr glm::vec3 kSelectionTint{1.0f, 0.85f, 0.0f};  // yellow, as SuperSplat's
inline glm::vec3 mark_overlay(glm::vec3 color, std::uint16_t mark, std::uint32_t mode) {
    if (mode & SFFD_MARKS_WEIGHTS) color = weight_ramp(float(mark >> 8) * (1.0f / 255.0f));
    if ((mode & SFFD_MARKS_SELECTION) && (mark & SFFD_MARK_SELECTED))
        color = glm::mix(color, kSelectionTint, 0.5f);
    return color;
}

// The words a marks buffer of `points` points holds (two marks a word).
constexpr std::size_t point_mark_words(std::size_t points) { return (points + 1) / 2; }

}  // namespace sffd::gfx
