// The frame a lattice deforms a cloud in: the one place a cloud's lattices are prepared for the kernels.
//
// A lattice deforms what lies inside it in the world: the cloud's points (origin + p) reach the world
// through the cloud's model matrix C = model_matrix(Transform of the cloud), the lattice's box and control
// points through L = model_matrix(Transform of the lattice). The deformation runs in the cloud's frame,
// with the lattice expressed there: box, axes and control points mapped by A = C⁻¹ L. An affine map of a
// Bernstein or B-spline lattice maps its control points (the weights sum to one), so a point's result is
// C⁻¹ f_world(C p): the deformed cloud stays in the cloud's frame, where the renderer, picking and the
// overlay place it with C, and normals, splat axes and Gaussian covariances follow from the Jacobian in
// that frame. Every deformer (ffd_system's CPU and GPU paths, gaussian_deform_system, picking, the
// commands) reads its lattices through cloud_lattices(), so they agree on where a lattice is.
#pragma once

#include <deque>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

// C⁻¹ L: from the lattice entity's frame to the cloud's (either entity may lack a Transform: identity).
// Exactly the identity when both Transforms are equal (the editor and the commands place a lattice they
// add with its cloud's Transform).
glm::dmat4 lattice_to_cloud(const ecs::Registry& registry, ecs::Entity cloud, ecs::Entity lattice);

// The lattice with origin, axes and rest and current control points mapped by the affine `m` (control
// points that did not move stay equal to their rest, bit for bit, so the moved-point tests still hold).
Lattice map_lattice(const Lattice& lattice, const glm::dmat4& m);

// A cloud's lattices as its deformation reads them, in Deformers order: each points into the registry
// when its frame is the cloud's, else into `mapped`. Move-only (the pointers follow the storage); valid
// while the registry's Lattice storage does not change.
struct CloudLattices {
    std::vector<ecs::Entity> entities;     // the lattice entities (those with a Lattice), in order
    std::vector<const Lattice*> lattices;  // the same lattices in the cloud's frame
    std::deque<Lattice> mapped;            // storage of the ones that were mapped

    CloudLattices() = default;
    CloudLattices(CloudLattices&&) = default;
    CloudLattices& operator=(CloudLattices&&) = default;
    CloudLattices(const CloudLattices&) = delete;
    CloudLattices& operator=(const CloudLattices&) = delete;
    std::span<const Lattice* const> span() const { return lattices; }
};
// Entities that are not alive or have no Lattice are left out.
CloudLattices cloud_lattices(const ecs::Registry& registry, ecs::Entity cloud,
                             std::span<const ecs::Entity> lattices);

// The axis-aligned box holding `box` (in the frame `model` maps to the world) in the world: its eight
// corners mapped. Empty stays empty.
Box world_box(const Box& box, const glm::dmat4& model);

}  // namespace sffd::ffd
