// PickCache: what picking computes or reads back itself, for clouds of both kinds (surface splats and
// Gaussians), one entry per cloud. Owned by PickingState and filled only when a pick needs it:
//   - a deformed output that lives only on the GPU is read back once per its `deformed_version`;
//   - without a readable output (no context, or stale), picking deforms what it needs itself, once per
//     change of the deformation's inputs (the cloud, its Deformers and every lattice: their stamps).
// The Embree refresh compares an entry's `serial` (a new value per fill) with what its geometry was built
// from, so a cloud is rebuilt exactly when its data changed.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/lattice.h"
#include "systems/ffd/components.h"

namespace sffd::picking {

enum class PickCloudKind : std::uint8_t { surface, gaussian };

struct PickCache {
    struct Entry {
        bool read_back = false;              // true: read back from the GPU; false: picking's own deformation
        std::uint64_t deformed_version = 0;  // read_back: the resident output's deformed_version
        DeformInputStamps inputs;            // the inputs the data belongs to
        std::uint64_t serial = 0;            // a new value per fill (0: empty)
        std::vector<glm::vec3> positions;    // centres, relative to the cloud's origin (both kinds)
        std::vector<glm::vec3> normals, axis_u, axis_v;  // surface clouds: the deformed splats' frames
        std::vector<glm::mat3> jacobians;                // Gaussians, own deformation: J per Gaussian
        std::vector<glm::vec3> scales;                   // Gaussians, read back
        std::vector<glm::quat> rotations;

        bool holds_read_back(std::uint64_t version, const DeformInputStamps& in) const {
            return serial != 0 && read_back && deformed_version == version && inputs == in;
        }
        bool holds_deformation(const DeformInputStamps& in) const {
            return serial != 0 && !read_back && inputs == in;
        }
    };

    // The entry of a cloud (created empty).
    Entry& entry(PickCloudKind kind, ecs::Entity cloud) { return entries[{cloud.bits(), kind}]; }
    void erase(PickCloudKind kind, ecs::Entity cloud) { entries.erase({cloud.bits(), kind}); }
    // Marks `e` as filled now from `read_back` data (for its `version`) or picking's own deformation.
    void filled(Entry& e, bool read_back, std::uint64_t version, DeformInputStamps inputs) {
        e.read_back = read_back;
        e.deformed_version = version;
        e.inputs = std::move(inputs);
        e.serial = ++fills;
    }

    std::map<std::pair<std::uint64_t, PickCloudKind>, Entry> entries;  // by entity bits and kind
    std::uint64_t fills = 0;
    // Work done (tests check it stays lazy): per kind, deformations run and GPU outputs read back.
    std::uint64_t deformations = 0, read_backs = 0;
    std::uint64_t gaussian_deformations = 0, gaussian_read_backs = 0;
};

}  // namespace sffd::picking
