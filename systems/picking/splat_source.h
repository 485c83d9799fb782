// Which splats picking sees for a point-cloud entity: the deformer's CPU output when the cloud has one
// (DeformedSplats, written by systems/ffd), otherwise the authored SplatCloud. Spans into the
// components; valid until the registry changes.
#pragma once

#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"

namespace sffd::picking {

struct SplatSource {
    enum class Kind : int { none, authored, deformed };
    Kind kind = Kind::none;
    std::uint64_t version = 0;  // change stamp of the component the spans point into
    glm::dvec3 origin{0.0};     // positions are relative to this (entity space)
    std::span<const glm::vec3> positions, normals, axis_u, axis_v;
};

SplatSource splat_source(const ecs::Registry& registry, ecs::Entity cloud);

// Latest change stamp of the deformed-output storage (0 while no cloud has one).
std::uint64_t splat_source_storage_version(const ecs::Registry& registry);

}  // namespace sffd::picking
