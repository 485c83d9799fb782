// What a cloud's deformation reads, gathered once for every deforming system (ffd_system for point
// clouds, gaussian_deform_system for Gaussians): the live lattices of its Deformers and their change
// stamps. A system compares the stamps with the ones its output kept and skips the cloud when none moved.
#pragma once

#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/lattice.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

struct DeformInputs {
    std::vector<ecs::Entity> lattices;  // Deformers::lattices that are alive and have a Lattice, in order
    DeformInputStamps stamps;           // stamps.lattices[d] belongs to lattices[d]
};

// Inputs of cloud entity e, whose authored cloud component is Cloud (SplatCloud, GaussianCloud); e must
// have Cloud and Deformers.
template <class Cloud>
DeformInputs deform_inputs(ecs::Registry& reg, ecs::Entity e) {
    DeformInputs in;
    for (ecs::Entity le : reg.get<Deformers>(e).lattices)
        if (reg.valid(le) && reg.has<Lattice>(le)) {
            in.lattices.push_back(le);
            in.stamps.lattices.push_back(reg.version<Lattice>(le) ^ (le.bits() << 1));
        }
    in.stamps.cloud = reg.version<Cloud>(e);
    in.stamps.deformers = reg.version<Deformers>(e);
    return in;
}

}  // namespace sffd::ffd
