#include "systems/ffd/deform_cloud.h"

#include "runtime/core/log.h"
#include "systems/ffd/deform.h"

namespace sffd::ffd {

void deform_cloud(const ecs::Registry& registry, const SplatCloud& cloud,
                  const std::vector<ecs::Entity>& lattices, DeformedSplats& out, const char* who) {
    const std::size_t n = cloud.size();
    out.origin = cloud.origin;
    out.positions = cloud.positions;
    out.normals = cloud.normals;
    out.axis_u = cloud.axis_u;
    out.axis_v = cloud.axis_v;
    out.inverted = 0;
    auto ptr = [n](std::vector<glm::vec3>& v) { return v.size() == n ? v.data() : nullptr; };
    for (const ecs::Entity le : lattices) {
        const Lattice* lattice = registry.valid(le) ? registry.try_get<Lattice>(le) : nullptr;
        if (!lattice) continue;
        // In place: each lattice deforms the previous one's output (allowed by ffd::deform).
        const PointsIn in{out.positions.data(), ptr(out.normals), ptr(out.axis_u), ptr(out.axis_v), n,
                          cloud.origin};
        const PointsOut o{out.positions.data(), ptr(out.normals), ptr(out.axis_u), ptr(out.axis_v)};
        const auto stats = deform(*lattice, in, o);
        if (!stats) {
            log::warn(who, ": ", stats.message(), " (lattice skipped)");
            continue;
        }
        out.inverted += stats->inverted;
    }
    out.cpu_valid = true;
}

}  // namespace sffd::ffd
