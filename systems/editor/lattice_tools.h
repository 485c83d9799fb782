// What the editor's stretch and twist tools touch: which control points are editable (selection,
// global scope, the pinned outer layer), their pivot, and the edit itself applied from a snapshot.
//
// Pinning: the outer layer of control points is pinned by default. The deformation is continuous where
// the surface leaves the lattice box only if the boundary control points stay at rest (Sederberg-Parry;
// ../shared/notes/ffd-math.md), so local edits touch inner points only. Unpinning is one toggle
// (EditorState::pin_outer_layer). Global edits (every control point, the paper's "global deformation")
// ignore pins: they move the whole box.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "systems/ffd/components.h"

namespace sffd::editor {

enum class ToolScope : std::uint8_t { local, global };

// 1 for control points on the lattice's outer layer (i, j or k at 0 or at the division count).
std::vector<std::uint8_t> outer_layer_mask(const Lattice& lattice);
// 1 for control points (current positions) inside the axis-aligned box [lo, hi] (inclusive): the editor
// highlights them as "inside the object's bounds", i.e. the points that actually carry surface.
std::vector<std::uint8_t> inside_box_mask(const Lattice& lattice, const glm::dvec3& lo, const glm::dvec3& hi);

// The control points an edit moves: global scope -> all; local -> the selection minus pinned points
// (when pin_outer). Sorted, unique, in range.
std::vector<std::uint32_t> editable_points(const Lattice& lattice, std::span<const std::uint32_t> selection,
                                           ToolScope scope, bool pin_outer);

// Mean of the current positions of `indices` (lattice centre when empty).
glm::dvec3 centroid(const Lattice& lattice, std::span<const std::uint32_t> indices);

// Paper eq. (23): out[c] = start[c] + d for c in indices; other points copy start.
void stretch_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                    std::span<const std::uint32_t> indices, const glm::dvec3& displacement);
// Paper eq. (24) with a pivot: out[c] = pivot + R(axis, angle)(start[c] - pivot) for c in indices.
void twist_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, const glm::dvec3& pivot, const glm::dvec3& axis,
                  double angle);
// The same with a weight per index (proportional editing, proportional.h): point indices[i] moves by
// weights[i] times the edit (a stretch by w·d, a twist by w·angle), and scale_points moves it to
// start + w·(pivot + L(start - pivot) - start) for the linear map L (a scale, in lattice space).
void stretch_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                    std::span<const std::uint32_t> indices, std::span<const double> weights,
                    const glm::dvec3& displacement);
void twist_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, std::span<const double> weights,
                  const glm::dvec3& pivot, const glm::dvec3& axis, double angle);
void scale_points(std::span<const glm::dvec3> start, std::span<glm::dvec3> out,
                  std::span<const std::uint32_t> indices, std::span<const double> weights,
                  const glm::dvec3& pivot, const glm::dmat3& linear);

}  // namespace sffd::editor
