#include "systems/editor/lattice_tools.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace sffd::editor {

std::vector<std::uint8_t> outer_layer_mask(const Lattice& lattice) {
    const glm::ivec3 d = lattice.divisions;
    std::vector<std::uint8_t> mask(lattice.size(), 0);
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k)
                mask[lattice.index(i, j, k)] =
                    (i == 0 || i == d.x || j == 0 || j == d.y || k == 0 || k == d.z) ? 1 : 0;
    return mask;
}

std::vector<std::uint8_t> inside_box_mask(const Lattice& lattice, const glm::dvec3& lo,
                                          const glm::dvec3& hi) {
    std::vector<std::uint8_t> mask(lattice.current.size(), 0);
    for (std::size_t c = 0; c < lattice.current.size(); ++c) {
        const glm::dvec3& p = lattice.current[c];
        mask[c] = glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi)) ? 1 : 0;
    }
    return mask;
}

std::vector<std::uint32_t> editable_points(const Lattice& lattice, std::span<const std::uint32_t> selection,
                                           ToolScope scope, bool pin_outer) {
    const auto n = static_cast<std::uint32_t>(lattice.current.size());
    std::vector<std::uint32_t> out;
    if (scope == ToolScope::global) {
        out.resize(n);
        for (std::uint32_t c = 0; c < n; ++c) out[c] = c;
        return out;
    }
    const std::vector<std::uint8_t> pinned =
        pin_outer ? outer_layer_mask(lattice) : std::vector<std::uint8_t>();
    for (std::uint32_t c : selection)
        if (c < n && (pinned.empty() || !pinned[c])) out.push_back(c);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

glm::dvec3 centroid(const Lattice& lattice, std::span<const std::uint32_t> indices) {
    if (indices.empty()) {
        return lattice.origin + 0.5 * (lattice.axes[0] + lattice.axes[1] + lattice.axes[2]);
    }
    glm::dvec3 sum(0.0);
    for (std::uint32_t c : indices) sum += lattice.current[c];
    return sum / double(indices.size());
}

void stretch_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                    std::span<const std::uint32_t> indices, const glm::dvec3& displacement) {
    assert(start.size() == out.size());
    std::copy(start.begin(), start.end(), out.begin());
    for (std::uint32_t c : indices) out[c] = start[c] + displacement;
}

void twist_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, const glm::dvec3& pivot, const glm::dvec3& axis,
                  double angle) {
    assert(start.size() == out.size());
    std::copy(start.begin(), start.end(), out.begin());
    if (glm::length(axis) == 0.0) return;
    const glm::dvec3 k = glm::normalize(axis);
    const double c = std::cos(angle), s = std::sin(angle);
    for (std::uint32_t i : indices) {
        // Rodrigues: v cos + (k x v) sin + k (k.v)(1 - cos).
        const glm::dvec3 v = start[i] - pivot;
        out[i] = pivot + v * c + glm::cross(k, v) * s + k * glm::dot(k, v) * (1.0 - c);
    }
}

void stretch_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                    std::span<const std::uint32_t> indices, std::span<const double> weights,
                    const glm::dvec3& displacement) {
    assert(start.size() == out.size() && weights.size() == indices.size());
    std::copy(start.begin(), start.end(), out.begin());
    for (std::size_t i = 0; i < indices.size(); ++i)
        out[indices[i]] = start[indices[i]] + weights[i] * displacement;
}

void twist_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, std::span<const double> weights,
                  const glm::dvec3& pivot, const glm::dvec3& axis, double angle) {
    assert(start.size() == out.size() && weights.size() == indices.size());
    std::copy(start.begin(), start.end(), out.begin());
    if (glm::length(axis) == 0.0) return;
    const glm::dvec3 k = glm::normalize(axis);
    for (std::size_t i = 0; i < indices.size(); ++i) {
        const double a = weights[i] * angle, c = std::cos(a), s = std::sin(a);
        const glm::dvec3 v = start[indices[i]] - pivot;
        out[indices[i]] = pivot + v * c + glm::cross(k, v) * s + k * glm::dot(k, v) * (1.0 - c);
    }
}

void scale_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, std::span<const double> weights,
                  const glm::dvec3& pivot, const glm::dmat3& linear) {
    assert(start.size() == out.size() && weights.size() == indices.size());
    std::copy(start.begin(), start.end(), out.begin());
    for (std::size_t i = 0; i < indices.size(); ++i) {
        const glm::dvec3& p = start[indices[i]];
        const glm::dvec3 scaled = pivot + linear * (p - pivot);
        out[indices[i]] = weights[i] == 1.0 ? scaled : p + weights[i] * (scaled - p);
    }
}

}  // namespace sffd::editor
