#include "tools/splatffd/scene_subset.h"

#include <algorithm>

#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"

namespace sffd::cli {

namespace {

std::string name_of(const ecs::Registry& r, ecs::Entity e) {
    const Name* n = r.try_get<Name>(e);
    return n ? n->value : std::string();
}

std::string quoted_names(const ecs::Registry& r, const std::vector<ecs::Entity>& es) {
    std::string s;
    for (ecs::Entity e : es) s += (s.empty() ? "'" : ", '") + name_of(r, e) + "'";
    return s.empty() ? "none" : s;
}

std::size_t cloud_size(const ecs::Registry& r, ecs::Entity e) {
    if (const SplatCloud* c = r.try_get<SplatCloud>(e)) return c->size();
    return r.get<GaussianCloud>(e).size();
}

// Destroys the clouds of `all` not in `keep`, and the lattices bound to a destroyed cloud that no kept
// cloud is bound to (with their clips: they live on the lattice entity).
void remove_clouds(ecs::Registry& r, const std::vector<ecs::Entity>& all,
                   const std::vector<ecs::Entity>& keep) {
    std::vector<ecs::Entity> kept_lattices, dropped_lattices;
    for (ecs::Entity e : all) {
        const Deformers* d = r.try_get<Deformers>(e);
        if (!d) continue;
        const bool kept = std::find(keep.begin(), keep.end(), e) != keep.end();
        auto& to = kept ? kept_lattices : dropped_lattices;
        to.insert(to.end(), d->lattices.begin(), d->lattices.end());
    }
    for (ecs::Entity e : all)
        if (std::find(keep.begin(), keep.end(), e) == keep.end()) r.destroy(e);
    for (ecs::Entity l : dropped_lattices)
        if (r.valid(l) && std::find(kept_lattices.begin(), kept_lattices.end(), l) == kept_lattices.end())
            r.destroy(l);
}

}  // namespace

Result<std::vector<ecs::Entity>> narrow_scene(ecs::Registry& r, const std::string& in,
                                              const SceneSubset& subset, bool scene_out) {
    std::vector<ecs::Entity> all;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<SplatCloud>(e) || r.has<GaussianCloud>(e)) all.push_back(e);
    });
    std::vector<ecs::Entity> clouds = all;
    if (!subset.entity.empty()) {
        std::vector<ecs::Entity> named;
        for (ecs::Entity e : all)
            if (name_of(r, e) == subset.entity) named.push_back(e);
        if (named.empty()) {
            bool lattice = false;
            r.each_entity([&](ecs::Entity e) {
                lattice = lattice || (r.has<Lattice>(e) && name_of(r, e) == subset.entity);
            });
            return make_error(in + ": " +
                              (lattice ? "'" + subset.entity + "' is a lattice, not a cloud"
                                       : "no cloud named '" + subset.entity + "'") +
                              " (its clouds: " + quoted_names(r, all) + ")");
        }
        if (named.size() > 1)
            return make_error(in + ": " + std::to_string(named.size()) + " clouds are named '" +
                              subset.entity +
                              "'; --entity needs a name only one cloud has (rename one in splatffd view)");
        clouds = named;
    }
    if (subset.selected) {
        std::vector<ecs::Entity> with;
        for (ecs::Entity e : clouds)
            if (!points_with(r.try_get<PointFlags>(e), cloud_size(r, e), kPointSelected, kPointGone).empty())
                with.push_back(e);
        if (with.empty())
            return make_error(in + ": no point is selected" +
                              (subset.entity.empty() ? std::string() : " in cloud '" + subset.entity + "'") +
                              " (select points in splatffd view and save the scene; hidden and deleted "
                              "points do not count)");
        if (!scene_out && with.size() > 1)
            return make_error(in + ": points are selected in " + std::to_string(with.size()) + " clouds (" +
                              quoted_names(r, with) +
                              "); a cloud file holds one: choose it with --entity NAME, or write a scene "
                              "(.glb/.gltf)");
        for (ecs::Entity e : with)
            if (auto kept = extract_points(r, e); !kept)
                return make_error(in + ": cloud '" + name_of(r, e) + "': " + kept.message());
        clouds = with;
    }
    if (clouds.size() != all.size()) remove_clouds(r, all, clouds);
    return clouds;
}

}  // namespace sffd::cli
