#include "systems/gaussian/gaussian_system.h"

#include <vector>

#include "runtime/core/log.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"

namespace sffd {

void gaussian_deform_system(ecs::Registry& reg, const FrameContext&) {
    // Collect first: emplacing DeformedGaussians while iterating is a structural change.
    std::vector<ecs::Entity> clouds;
    reg.view<const GaussianCloud, const Deformers>().each(
        [&](ecs::Entity e, const GaussianCloud&, const Deformers&) { clouds.push_back(e); });
    for (ecs::Entity e : clouds) {
        const GaussianCloud& cloud = reg.get<GaussianCloud>(e);
        const ffd::DeformInputs inputs = ffd::deform_inputs<GaussianCloud>(reg, e);
        const std::vector<ecs::Entity>& lattices = inputs.lattices;
        const DeformedGaussians* seen = reg.try_get<DeformedGaussians>(e);
        if (seen && seen->seen == inputs.stamps) continue;  // nothing this cloud depends on moved
        if (!seen) reg.emplace<DeformedGaussians>(e);
        DeformedGaussians& out = reg.patch<DeformedGaussians>(e);
        out.seen = inputs.stamps;
        out.inverted = out.degenerate = 0;
        ++out.version;
        // Opacities are not copied (a deformation never changes them): readers use the authored cloud's.
        out.cloud.origin = cloud.origin;
        out.cloud.sh_degree = cloud.sh_degree;
        out.cloud.positions = cloud.positions;
        out.cloud.scales = cloud.scales;
        out.cloud.rotations = cloud.rotations;
        out.cloud.sh = cloud.sh;
        out.cloud.opacities.clear();
        for (ecs::Entity le : lattices) {
            auto stats = gaussian::deform(reg.get<Lattice>(le), out.cloud, out.cloud, ffd::Backend::automatic, false);
            if (!stats) {
                log::warn("gaussian_deform_system: ", stats.message(), " (lattice skipped)");
                continue;
            }
            out.inverted += stats->inverted;
            out.degenerate += stats->degenerate;
        }
    }
}

}  // namespace sffd
