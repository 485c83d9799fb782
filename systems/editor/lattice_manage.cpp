#include "systems/editor/lattice_manage.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/entity_undo.h"
#include "systems/ffd/lattice_io.h"
#include "systems/gaussian/components.h"
#include "systems/picking/components.h"
#include "systems/animation/components.h"

namespace sffd::editor {

namespace {

void say(EditorState& state, std::string message) {
    log::info("editor: ", message);
    state.status = std::move(message);
}

std::string name_of(const ecs::Registry& r, ecs::Entity e, const char* fallback) {
    const Name* n = r.valid(e) ? r.try_get<Name>(e) : nullptr;
    return n && !n->value.empty() ? n->value : fallback;
}

bool is_lattice(const ecs::Registry& r, ecs::Entity e) { return r.valid(e) && r.has<Lattice>(e); }

// A cloud lattices deform: surface splats (SplatCloud) or 3D Gaussians (GaussianCloud).
bool is_cloud(const ecs::Registry& r, ecs::Entity e) {
    return r.valid(e) && (r.has<SplatCloud>(e) || r.has<GaussianCloud>(e));
}

// The authored centres and origin of either kind of cloud.
const std::vector<glm::vec3>& cloud_positions(const ecs::Registry& r, ecs::Entity e, glm::dvec3& origin) {
    if (const SplatCloud* c = r.try_get<SplatCloud>(e)) return origin = c->origin, c->positions;
    const GaussianCloud& g = r.get<GaussianCloud>(e);
    return origin = g.origin, g.positions;
}

std::vector<ecs::Entity> all_lattices(const ecs::Registry& r) {
    std::vector<ecs::Entity> out;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<Lattice>(e)) out.push_back(e);
    });
    return out;
}

// Clouds whose Deformers list `lattice`.
std::vector<ecs::Entity> clouds_deformed_by(const ecs::Registry& r, ecs::Entity lattice) {
    std::vector<ecs::Entity> out;
    r.each_entity([&](ecs::Entity e) {
        const Deformers* d = r.try_get<Deformers>(e);
        if (d && is_cloud(r, e) &&
            std::find(d->lattices.begin(), d->lattices.end(), lattice) != d->lattices.end())
            out.push_back(e);
    });
    return out;
}

// A name no other entity has: "<base>", "<base>2", …
std::string unique_name(const ecs::Registry& r, const std::string& base) {
    for (int k = 1;; ++k) {
        std::string candidate = base;
        if (k > 1) candidate += std::to_string(k);
        bool taken = false;
        r.each_entity([&](ecs::Entity e) {
            if (const Name* n = r.try_get<Name>(e); n && n->value == candidate) taken = true;
        });
        if (!taken) return candidate;
    }
}

// Records the change of component C on `e` made by `edit` (emplace, patch or remove) into `group`.
template <class C, class Fn>
void change(ecs::Registry& r, CommandGroup& group, ecs::Entity e, const char* label, Fn&& edit) {
    ComponentEdit<C> before(r, e, label);
    edit();
    group.add(before.finish(r));
}

// A lattice entity bound last to `cloud` (placed like the cloud), active, as one undo step.
bool add_bound_lattice(ecs::Registry& r, EditorState& state, ecs::Entity cloud, Lattice lattice,
                       const char* label) {
    // Never leave a cloud without Deformers once it had a lattice: the deformation phase only rewrites
    // DeformedSplats for clouds that have it (an empty list gives the authored splats back).
    if (!r.has<Deformers>(cloud)) r.emplace<Deformers>(cloud);
    const std::string name = unique_name(r, name_of(r, cloud, "cloud") + ".lattice");
    const Transform* t = r.try_get<Transform>(cloud);
    const Transform placed = t ? *t : Transform{};
    const ecs::Entity e = r.create();
    r.emplace<Name>(e, Name{name});
    r.emplace<Transform>(e, placed);
    r.emplace<Lattice>(e, std::move(lattice));
    auto group = std::make_unique<CommandGroup>(label);
    // Undo destroys the entity (its components kept in the step); redo creates it again (entity_undo.h).
    group->add(std::make_unique<LatticeLife>(label, r, e, LatticeLife::Kind::created));
    change<Deformers>(r, *group, cloud, label, [&] { r.patch<Deformers>(cloud).lattices.push_back(e); });
    state.undo.push(std::move(group));
    state.active_lattice = e;
    state.last_edit = {};
    say(state, std::string(label) + ": '" + name + "' on '" + name_of(r, cloud, "cloud") + "', " +
                   std::to_string(control_points_inside_object(r, r.get<Lattice>(e))) +
                   " control points inside the object's box");
    return true;
}

// The authored points of `clouds` relative to the first one's origin.
std::vector<glm::vec3> points_of(const ecs::Registry& r, const std::vector<ecs::Entity>& clouds,
                                 glm::dvec3& origin) {
    std::vector<glm::vec3> pts;
    bool first = true;
    for (ecs::Entity c : clouds) {
        glm::dvec3 cloud_origin(0.0);
        const std::vector<glm::vec3>& positions = cloud_positions(r, c, cloud_origin);
        if (first) origin = cloud_origin, first = false;
        for (const glm::vec3& p : positions) pts.push_back(glm::vec3(cloud_origin - origin + glm::dvec3(p)));
    }
    return pts;
}

}  // namespace

LatticeFitSettings& lattice_fit_settings(ecs::Registry& registry) {
    if (LatticeFitSettings* s = registry.try_resource<LatticeFitSettings>()) return *s;
    return registry.set_resource<LatticeFitSettings>();
}

std::vector<ecs::Entity> lattices_of(const ecs::Registry& registry, ecs::Entity cloud) {
    const Deformers* d = registry.valid(cloud) ? registry.try_get<Deformers>(cloud) : nullptr;
    std::vector<ecs::Entity> out;
    if (d)
        for (ecs::Entity l : d->lattices)
            if (is_lattice(registry, l)) out.push_back(l);
    return out;
}

ecs::Entity target_cloud(const ecs::Registry& r, const EditorState& state) {
    if (is_cloud(r, state.selected_entity)) return state.selected_entity;
    if (is_lattice(r, state.active_lattice))
        if (auto clouds = clouds_deformed_by(r, state.active_lattice); !clouds.empty()) return clouds.front();
    ecs::Entity first = ecs::null_entity;
    r.each_entity([&](ecs::Entity e) {
        if (!first && is_cloud(r, e)) first = e;
    });
    return first;
}

bool add_lattice(ecs::Registry& r, EditorState& state) {
    const ecs::Entity cloud = target_cloud(r, state);
    if (!cloud) return say(state, "add lattice: the scene has no point cloud"), false;
    glm::dvec3 origin(0.0);
    const std::vector<glm::vec3>& positions = cloud_positions(r, cloud, origin);
    const ffd::FitOptions fit = lattice_fit_settings(r).fit;
    auto l = ffd::fit_lattice(positions, origin, fit);
    if (!l) return say(state, "add lattice: " + l.message()), false;
    return add_bound_lattice(r, state, cloud, std::move(*l), "add lattice");
}

bool remove_lattice(ecs::Registry& r, EditorState& state) {
    const ecs::Entity e = state.active_lattice;
    if (!is_lattice(r, e)) return say(state, "remove lattice: no active lattice"), false;
    if (state.drag.kind != Drag::Kind::none) return false;
    const std::string name = name_of(r, e, "lattice");
    auto group = std::make_unique<CommandGroup>("remove lattice");
    for (ecs::Entity cloud : clouds_deformed_by(r, e))
        change<Deformers>(r, *group, cloud, "remove lattice", [&] {
            auto& list = r.patch<Deformers>(cloud).lattices;
            list.erase(std::remove(list.begin(), list.end(), e), list.end());
        });
    // The entity goes; the step keeps its components (clip, selection, un-keyed edit included) and undo
    // creates it again, the clouds' Deformers mapped to the new id (entity_undo.h).
    group->add(LatticeLife::destroy("remove lattice", r, e));
    state.undo.push(std::move(group));
    const auto rest = all_lattices(r);
    state.active_lattice = rest.empty() ? ecs::null_entity : rest.front();
    if (state.selected_entity == e) state.selected_entity = ecs::null_entity;
    state.last_edit = {};
    say(state, "removed lattice '" + name + "'");
    return true;
}

bool refit_lattice(ecs::Registry& r, EditorState& state) {
    const ecs::Entity e = state.active_lattice;
    if (!is_lattice(r, e)) return say(state, "refit: no active lattice"), false;
    std::vector<ecs::Entity> clouds = clouds_deformed_by(r, e);
    if (clouds.empty())
        if (const ecs::Entity c = target_cloud(r, state)) clouds.push_back(c);
    if (clouds.empty()) return say(state, "refit: no point cloud"), false;
    glm::dvec3 origin(0.0);
    const std::vector<glm::vec3> pts = points_of(r, clouds, origin);
    auto fitted = ffd::fit_lattice(pts, origin, lattice_fit_settings(r).fit);
    if (!fitted) return say(state, "refit: " + fitted.message()), false;
    auto group = std::make_unique<CommandGroup>("refit lattice");
    change<Lattice>(r, *group, e, "refit lattice", [&] { r.patch<Lattice>(e) = std::move(*fitted); });
    if (r.has<picking::LatticeSelection>(e))
        change<picking::LatticeSelection>(r, *group, e, "refit lattice",
                                          [&] { r.patch<picking::LatticeSelection>(e).indices.clear(); });
    state.undo.push(std::move(group));
    state.last_edit = {};
    say(state, "refitted '" + name_of(r, e, "lattice") + "' (" +
                   ffd::fit_spec_string(lattice_fit_settings(r).fit) + ")");
    return true;
}

bool move_lattice_in_order(ecs::Registry& r, EditorState& state, int delta) {
    const ecs::Entity e = state.active_lattice;
    if (!is_lattice(r, e)) return false;
    for (ecs::Entity cloud : clouds_deformed_by(r, e)) {
        const auto& list = r.get<Deformers>(cloud).lattices;
        const auto at = std::size_t(std::find(list.begin(), list.end(), e) - list.begin());
        const long long to = (long long)at + delta;
        if (to < 0 || to >= (long long)list.size())
            return say(state, "lattice order: already " + std::string(delta < 0 ? "first" : "last")), false;
        auto group = std::make_unique<CommandGroup>("lattice order");
        change<Deformers>(r, *group, cloud, "lattice order", [&] {
            auto& l = r.patch<Deformers>(cloud).lattices;
            std::swap(l[at], l[std::size_t(to)]);
        });
        state.undo.push(std::move(group));
        say(state, "'" + name_of(r, e, "lattice") + "' is lattice " + std::to_string(to + 1) + " of " +
                       std::to_string(list.size()) + " on '" + name_of(r, cloud, "cloud") + "'");
        return true;  // the first cloud that follows it (a lattice shared by several clouds keeps one order
                      // each)
    }
    return say(state, "lattice order: the active lattice deforms no cloud"), false;
}

bool cycle_active_lattice(ecs::Registry& r, EditorState& state, int delta) {
    const auto all = all_lattices(r);
    if (all.empty()) return false;
    const auto it = std::find(all.begin(), all.end(), state.active_lattice);
    const long long n = (long long)all.size(), at = it == all.end() ? -1 : (long long)(it - all.begin());
    state.active_lattice = all[std::size_t(((at + delta) % n + n) % n)];
    state.drag = {};
    say(state, "active lattice: '" + name_of(r, state.active_lattice, "lattice") + "'");
    return true;
}

std::string lattice_json_path(ecs::Registry& r, const EditorState& state) {
    const LatticeFitSettings& settings = lattice_fit_settings(r);
    if (settings.json_folder.empty() || !is_lattice(r, state.active_lattice)) return settings.json_path;
    // Names are any text: characters a file name cannot safely hold become '_'.
    std::string file = name_of(r, state.active_lattice, "lattice");
    for (char& c : file)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
    if (file.empty() || file[0] == '.') file = "lattice" + file;
    return (std::filesystem::path(settings.json_folder) / (file + ".json")).string();
}

bool export_lattice_json(ecs::Registry& r, EditorState& state, const std::string& path) {
    if (!is_lattice(r, state.active_lattice)) return say(state, "export lattice: no active lattice"), false;
    if (Status s = ffd::save_lattice(path, r.get<Lattice>(state.active_lattice)); !s)
        return say(state, "export lattice: " + s.message()), false;
    say(state, "exported '" + name_of(r, state.active_lattice, "lattice") + "' to " + path);
    return true;
}

bool import_lattice_json(ecs::Registry& r, EditorState& state, const std::string& path) {
    auto loaded = ffd::load_lattice(path);
    if (!loaded) return say(state, "import lattice: " + loaded.message()), false;
    const ecs::Entity e = state.active_lattice;
    if (!is_lattice(r, e)) {
        const ecs::Entity cloud = target_cloud(r, state);
        if (!cloud) return say(state, "import lattice: the scene has no point cloud"), false;
        return add_bound_lattice(r, state, cloud, std::move(*loaded), "import lattice");
    }
    auto group = std::make_unique<CommandGroup>("import lattice");
    change<Lattice>(r, *group, e, "import lattice", [&] { r.patch<Lattice>(e) = std::move(*loaded); });
    if (r.has<picking::LatticeSelection>(e))
        change<picking::LatticeSelection>(r, *group, e, "import lattice",
                                          [&] { r.patch<picking::LatticeSelection>(e).indices.clear(); });
    state.undo.push(std::move(group));
    state.last_edit = {};
    say(state, "imported " + path + " into '" + name_of(r, e, "lattice") + "'");
    return true;
}

bool handle_lattice_key(ecs::Registry& r, EditorState& state, const InputEvent& ev) {
    const bool ctrl = ev.modifiers & mods::ctrl, shift = ev.modifiers & mods::shift,
               alt = ev.modifiers & mods::alt;
    const std::string& k = ev.key;
    if (alt) return false;
    if (ctrl && !shift && k == "e") return export_lattice_json(r, state, lattice_json_path(r, state)), true;
    if (ctrl && !shift && k == "i") return import_lattice_json(r, state, lattice_json_path(r, state)), true;
    if (ctrl) return false;
    if (shift && k == "a") return add_lattice(r, state), true;
    if (shift && k == "f") return refit_lattice(r, state), true;
    if (k == "delete") return remove_lattice(r, state), true;
    if (k == "tab") return cycle_active_lattice(r, state, shift ? -1 : 1), true;
    if (k == "pageup") return move_lattice_in_order(r, state, -1), true;
    if (k == "pagedown") return move_lattice_in_order(r, state, +1), true;
    return false;
}

}  // namespace sffd::editor
