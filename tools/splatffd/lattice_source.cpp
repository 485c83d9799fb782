#include "tools/splatffd/lattice_source.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "runtime/assets/scene.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/ffd/lattice_io.h"
#include "systems/engine/engine_frame.h"

namespace sffd::cli {

namespace {

std::string lower_ext(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string name_of(const ecs::Registry& r, ecs::Entity e) {
    const Name* n = r.try_get<Name>(e);
    return n && !n->value.empty() ? n->value : "lattice";
}

std::string quoted_list(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
    return s;
}

}  // namespace

bool is_scene_path(const std::string& path) {
    const std::string e = lower_ext(path);
    return e == ".glb" || e == ".gltf";
}

bool is_json_path(const std::string& path) { return lower_ext(path) == ".json"; }

Result<Lattice> fit_lattice_for(const std::string& command, const std::vector<glm::vec3>& positions,
                                const glm::dvec3& origin, const ffd::FitOptions& fit) {
    auto l = ffd::fit_lattice(positions, origin, fit);
    if (!l || fit.shape != ffd::FitShape::oriented) return l;
    const auto& a = l->axes;
    const bool aligned =
        a[0].y == 0 && a[0].z == 0 && a[1].x == 0 && a[1].z == 0 && a[2].x == 0 && a[2].y == 0;
    if (aligned)
        std::fprintf(stderr,
                     "splatffd %s: warning: obb: the cloud's principal axes give no box at least 5%% smaller "
                     "than the axis-aligned one (a near-isotropic cloud), so the lattice is axis-aligned\n",
                     command.c_str());
    return l;
}

Result<LatticeChain> pick_scene_lattices(const ecs::Registry& r, const std::string& file,
                                         const std::string& name) {
    std::vector<ecs::Entity> all;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<Lattice>(e)) all.push_back(e);
    });
    std::vector<std::string> all_names;
    for (ecs::Entity e : all) all_names.push_back(name_of(r, e));
    if (all.empty())
        return make_error(file + ": has no lattice (add one: splatffd convert " + file +
                          " OUT.glb --lattice fit, or in the editor: shift+a)");
    LatticeChain chain;
    if (!name.empty()) {
        std::vector<ecs::Entity> hits;
        for (ecs::Entity e : all)
            if (name_of(r, e) == name) hits.push_back(e);
        if (hits.empty())
            return make_error(file + ": no lattice named '" + name +
                              "' (lattices: " + quoted_list(all_names) + ")");
        if (hits.size() > 1)
            return make_error(file + ": " + std::to_string(hits.size()) + " lattices are named '" + name +
                              "'");
        chain.names.push_back(name);
        r.each_entity([&](ecs::Entity c) {
            if (const Deformers* d = r.try_get<Deformers>(c);
                d && !chain.cloud &&
                std::find(d->lattices.begin(), d->lattices.end(), hits[0]) != d->lattices.end())
                chain.cloud = c;
        });
        // In the cloud's frame, as the engine deforms it (systems/ffd/lattice_frame.h); an unbound one
        // in the world.
        chain.lattices.push_back(
            ffd::map_lattice(r.get<Lattice>(hits[0]), ffd::lattice_to_cloud(r, chain.cloud, hits[0])));
        return chain;
    }
    // The deformed clouds and their chains.
    std::vector<ecs::Entity> bound_clouds;
    r.each_entity([&](ecs::Entity c) {
        if (const Deformers* d = r.try_get<Deformers>(c); d && !d->lattices.empty())
            bound_clouds.push_back(c);
    });
    if (bound_clouds.size() == 1) {
        chain.cloud = bound_clouds[0];
        for (ecs::Entity l : r.get<Deformers>(bound_clouds[0]).lattices)
            if (r.valid(l) && r.has<Lattice>(l)) {
                chain.lattices.push_back(
                    ffd::map_lattice(r.get<Lattice>(l), ffd::lattice_to_cloud(r, chain.cloud, l)));
                chain.names.push_back(name_of(r, l));
            }
        return chain;
    }
    if (bound_clouds.empty() && all.size() == 1) {
        chain.lattices.push_back(
            ffd::map_lattice(r.get<Lattice>(all[0]), ffd::lattice_to_cloud(r, {}, all[0])));
        chain.names.push_back(all_names[0]);
        return chain;
    }
    return make_error(
        file + ": " + std::to_string(all.size()) + " lattices (" + quoted_list(all_names) + ")" +
        (bound_clouds.size() > 1 ? " bound to " + std::to_string(bound_clouds.size()) + " clouds" : "") +
        "; choose one with --lattice-name NAME");
}

Result<LatticeChain> load_lattice_source(const std::string& source, const std::string& name) {
    if (is_scene_path(source)) {
        ecs::Registry r;
        sffd::use_engine_scene_hooks(r);
        if (Status s = load_scene(r, source); !s) return s.error();
        return pick_scene_lattices(r, source, name);
    }
    if (!name.empty())
        return make_error(source + ": --lattice-name needs a scene file (.glb/.gltf), not a lattice JSON");
    auto l = ffd::load_lattice(source);
    if (!l) return l.error();
    LatticeChain chain;
    chain.lattices.push_back(std::move(*l));
    chain.names.push_back(std::filesystem::path(source).stem().string());
    return chain;
}

Status save_cloud_with_lattices(SplatCloud cloud, const std::string& cloud_name,
                                const std::vector<Lattice>& lattices, const std::string& path,
                                const SplatMaterial& material, std::span<const float> weights) {
    ecs::Registry r;
    sffd::use_engine_scene_hooks(r);
    const ecs::Entity c = r.create();
    r.emplace<Name>(c, Name{cloud_name});
    r.emplace<Transform>(c, Transform{});
    r.emplace<SplatCloud>(c, std::move(cloud));
    r.emplace<SplatMaterial>(c, material);
    if (!weights.empty()) r.emplace<PointWeights>(c, PointWeights{{weights.begin(), weights.end()}});
    Deformers d;
    for (std::size_t i = 0; i < lattices.size(); ++i) {
        const ecs::Entity l = r.create();
        r.emplace<Name>(l, Name{cloud_name + ".lattice" + (i ? std::to_string(i + 1) : std::string())});
        r.emplace<Transform>(l, Transform{});
        r.emplace<Lattice>(l, lattices[i]);
        d.lattices.push_back(l);
    }
    if (!d.lattices.empty()) r.emplace<Deformers>(c, std::move(d));
    return save_scene(r, path);
}

}  // namespace sffd::cli
