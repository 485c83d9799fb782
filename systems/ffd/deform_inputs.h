// What a cloud's deformation reads, gathered once for every deforming system (ffd_system for point
// clouds, gaussian_deform_system for Gaussians) and for picking: the live lattices of its Deformers and
// their change stamps (with the cloud's PointWeights stamp: the weights are an input of every deformer). A
// system compares the stamps with the ones its output kept and skips the cloud when none moved. A lattice
// deforms in the world (lattice_frame.h), so both entities' Transforms are inputs: moving the cloud or a
// lattice re-deforms, and moves the output's world bounds.
#pragma once

#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

struct DeformInputs {
    std::vector<ecs::Entity> lattices;  // Deformers::lattices that are alive and have a Lattice, in order
    DeformInputStamps stamps;           // stamps.lattices[d] belongs to lattices[d]
};

// The stamp of lattice `le` as cloud `e` reads it: its Lattice version and entity bits (swapping one
// lattice for another counts), its Transform's and the cloud's Transform's versions (the frame it is
// mapped into, lattice_frame.h). The GPU deformers upload a lattice's control points when it moves.
inline std::uint64_t lattice_stamp(const ecs::Registry& reg, ecs::Entity e, ecs::Entity le) {
    auto mix = [](std::uint64_t h, std::uint64_t v) { return (h ^ v) * 0x9E3779B97F4A7C15ull + (h >> 29); };
    std::uint64_t h = reg.version<Lattice>(le) ^ (le.bits() << 1);
    h = mix(h, reg.version<Transform>(le));
    return mix(h, reg.version<Transform>(e));
}

// Inputs of cloud entity e, whose authored cloud component is Cloud (SplatCloud, GaussianCloud); e must
// have Cloud and Deformers.
template <class Cloud>
DeformInputs deform_inputs(const ecs::Registry& reg, ecs::Entity e) {
    DeformInputs in;
    for (ecs::Entity le : reg.get<Deformers>(e).lattices)
        if (reg.valid(le) && reg.has<Lattice>(le)) {
            in.lattices.push_back(le);
            in.stamps.lattices.push_back(lattice_stamp(reg, e, le));
        }
    in.stamps.cloud = reg.version<Cloud>(e);
    in.stamps.deformers = reg.version<Deformers>(e);
    in.stamps.transform = reg.version<Transform>(e);
    in.stamps.weights = reg.version<PointWeights>(e);  // every deformer reads them (point_columns.h)
    return in;
}

}  // namespace sffd::ffd
