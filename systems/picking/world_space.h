// Where picking's inputs live in the world: a point cloud's splats at Transform(origin + position), a
// lattice's control points at Transform(current[i]) (identity when the entity has no Transform; the model
// matrix is runtime/scene/camera.h's).
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"

namespace sffd::picking {

// World positions of a lattice's current control points (empty when `lattice` has no Lattice).
inline std::vector<glm::dvec3> control_points_world(const ecs::Registry& registry, ecs::Entity lattice) {
    std::vector<glm::dvec3> out;
    const Lattice* l = registry.try_get<Lattice>(lattice);
    if (!l) return out;
    const glm::dmat4 m = model_matrix(registry.try_get<Transform>(lattice));
    out.reserve(l->current.size());
    for (const glm::dvec3& p : l->current) out.push_back(glm::dvec3(m * glm::dvec4(p, 1.0)));
    return out;
}

}  // namespace sffd::picking
