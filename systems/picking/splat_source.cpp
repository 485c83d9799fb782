#include "systems/picking/splat_source.h"

#include "runtime/scene/components.h"

namespace sffd::picking {

SplatSource splat_source(const ecs::Registry& registry, ecs::Entity cloud) {
    SplatSource src;
    const SplatCloud* authored = registry.try_get<SplatCloud>(cloud);
    if (!authored) return src;
    src.kind = SplatSource::Kind::authored;
    src.version = registry.version<SplatCloud>(cloud);
    src.origin = authored->origin;
    src.positions = authored->positions;
    if (authored->normals.size() == authored->size()) src.normals = authored->normals;
    if (authored->axis_u.size() == authored->size() && authored->axis_v.size() == authored->size()) {
        src.axis_u = authored->axis_u;
        src.axis_v = authored->axis_v;
    }
    return src;
}

std::uint64_t splat_source_storage_version(const ecs::Registry&) { return 0; }

}  // namespace sffd::picking
