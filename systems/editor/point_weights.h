// Deformation weights from the point selection (runtime/scene/point_columns.h PointWeights: every
// deformer moves a point by w times the lattice's displacement, J_w = I + w (J - I)).
//
// weights_from_selection: each point of a cloud with a selection gets the weight falloff_weight(curve,
// d, radius) of proportional.h, d its world distance (authored positions through the cloud's model
// matrix, so a weight belongs to the rest shape and does not move with a deformation) to the nearest
// selected point: 1 on the selection, falling to 0 at the radius, 0 beyond. So the lattice then moves
// the selection and a soft band around it, and nothing else. clear_weights empties the column (weight 1
// everywhere, as before any painting). Each is one undo step per cloud, holding the changed points'
// indices and both values (12 bytes a changed point; a cloud without weights is stored as such, not as
// a column of ones). Saving writes the column as _WEIGHT (content/README.md).
//
// Nearest distances: a uniform grid of cell radius/4 over the selected points, searched ring by ring
// outwards until the ring is farther than the best distance or the radius (at most 11^3 cells a point),
// for the points that a grid of cell radius finds near a selected one (27 cells); the others are far.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/editor/proportional.h"
#include "systems/editor/undo_stack.h"

namespace sffd::editor {

struct EditorState;

// The weights of one cloud before and after an edit, at the points where they differ.
class PointWeightChange final : public Command {
public:
    PointWeightChange(std::string label, ecs::Entity cloud, std::size_t points, bool before_empty,
                      bool after_empty, std::vector<std::uint32_t> indices, std::vector<float> before,
                      std::vector<float> after);
    void undo(ecs::Registry& registry, EntityMap& map) const override;
    void redo(ecs::Registry& registry, EntityMap& map) const override;
    bool empty() const override { return m_indices.empty() && m_before_empty == m_after_empty; }
    std::size_t bytes() const override;

private:
    void apply(ecs::Registry& registry, const EntityMap& map, bool forward) const;
    ecs::Entity m_cloud;
    std::size_t m_points = 0;
    bool m_before_empty = true, m_after_empty = true;
    std::vector<std::uint32_t> m_indices;
    std::vector<float> m_before, m_after;
};

// For each of `points` the distance to the nearest of `world[selected]`, capped: points farther than
// `radius` from every selected one get +infinity. `selected` sorted, unique.
std::vector<double> distance_to_selection(std::span<const glm::dvec3> world,
                                          std::span<const std::uint32_t> selected, double radius);

// Sets the weights of every cloud with a selected point (one undo step); false when none has one.
bool weights_from_selection(ecs::Registry& registry, EditorState& state, double radius, Falloff falloff);
// Empties every cloud's weights (one undo step); false when no cloud had any.
bool clear_weights(ecs::Registry& registry, EditorState& state);

}  // namespace sffd::editor
