// The editor's lattice settings: resample, basis, fit, apply as rest (each one undo step).
#include "systems/editor/editor_system_detail.h"
#include "systems/ffd/lattice_frame.h"

namespace sffd::editor {

using namespace detail;

namespace {

// Replaces the active lattice by `next` (and clears its selection) as one undo step.
bool replace_lattice(ecs::Registry& registry, EditorState& state, Lattice next, const char* label) {
    const ecs::Entity e = state.active_lattice;
    auto group = std::make_unique<CommandGroup>(label);
    ComponentEdit<Lattice> lattice_edit(registry, e, label);
    ComponentEdit<picking::LatticeSelection> selection_edit(registry, e, label);
    registry.patch<Lattice>(e) = std::move(next);
    if (registry.has<picking::LatticeSelection>(e))
        registry.patch<picking::LatticeSelection>(e).indices.clear();
    group->add(lattice_edit.finish(registry));
    group->add(selection_edit.finish(registry));
    state.undo.push(std::move(group));
    state.last_edit = {};
    return true;
}

// Point clouds deformed by `lattice` (Deformers lists it).
std::vector<ecs::Entity> clouds_of(ecs::Registry& registry, ecs::Entity lattice, bool first_only) {
    std::vector<ecs::Entity> out;
    registry.view<const SplatCloud, const Deformers>().each(
        [&](ecs::Entity e, const SplatCloud&, const Deformers& d) {
            if (first_only ? (!d.lattices.empty() && d.lattices.front() == lattice)
                           : std::find(d.lattices.begin(), d.lattices.end(), lattice) != d.lattices.end())
                out.push_back(e);
        });
    return out;
}

}  // namespace

bool resample_lattice(ecs::Registry& registry, EditorState& state, glm::ivec3 divisions) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    if (divisions == lattice->divisions) return false;
    Lattice next = *lattice;
    const glm::ivec3 up = glm::max(divisions, lattice->divisions);
    if (up != lattice->divisions) {
        auto raised = ffd::raise_resolution(next, up);
        if (!raised) return say(state, "resample: " + raised.message()), false;
        next = std::move(*raised);
    }
    if (divisions != up) {
        auto lowered = ffd::lower_resolution(next, divisions);
        if (!lowered) return say(state, "resample: " + lowered.message()), false;
        next = std::move(*lowered);
    }
    replace_lattice(registry, state, std::move(next), "resample");
    say(state,
        log::str("lattice resampled to ", divisions.x, "x", divisions.y, "x", divisions.z, " divisions"));
    return true;
}

bool set_lattice_basis(ecs::Registry& registry, EditorState& state, LatticeBasis basis) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice || lattice->basis == basis) return false;
    Lattice next = *lattice;
    next.basis = basis;
    replace_lattice(registry, state, std::move(next), "basis");
    say(state, basis == LatticeBasis::bernstein ? "basis: Bernstein" : "basis: cubic B-spline");
    return true;
}

bool fit_lattice_to(ecs::Registry& registry, EditorState& state, bool to_selection) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    glm::dvec3 lo(-std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::max());
    if (to_selection) {
        const auto sel = selection_of(registry, state.active_lattice);
        if (sel.size() < 2) return say(state, "fit to selection: select at least two control points"), false;
        lo = glm::dvec3(std::numeric_limits<double>::max()), hi = -lo;
        for (std::uint32_t i : sel)
            lo = glm::min(lo, lattice->current[i]), hi = glm::max(hi, lattice->current[i]);
    }
    std::vector<glm::vec3> points;
    glm::dvec3 origin(0.0);
    bool have_origin = false;
    for (ecs::Entity e : clouds_of(registry, state.active_lattice, false)) {
        const SplatCloud& cloud = registry.get<SplatCloud>(e);
        // The points in the lattice's own frame (both Transforms), where its box and control points live.
        const glm::dmat4 to_lattice = glm::inverse(ffd::lattice_to_cloud(registry, e, state.active_lattice));
        if (!have_origin) origin = glm::dvec3(to_lattice * glm::dvec4(cloud.origin, 1.0)), have_origin = true;
        for (const glm::vec3& p : cloud.positions) {
            const glm::dvec3 w = glm::dvec3(to_lattice * glm::dvec4(cloud.origin + glm::dvec3(p), 1.0));
            if (glm::all(glm::greaterThanEqual(w, lo)) && glm::all(glm::lessThanEqual(w, hi)))
                points.push_back(glm::vec3(w - origin));
        }
    }
    if (points.empty())
        return say(state, "fit: no points of the clouds this lattice deforms are in range"), false;
    auto fitted = ffd::fit_lattice(points, origin, lattice->divisions, lattice->basis);
    if (!fitted) return say(state, "fit: " + fitted.message()), false;
    replace_lattice(registry, state, std::move(*fitted), to_selection ? "fit to selection" : "fit to object");
    say(state, log::str("lattice fitted to ", points.size(), " points"));
    return true;
}

bool apply_lattice_as_rest(ecs::Registry& registry, EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return false;
    auto group = std::make_unique<CommandGroup>("apply as rest");
    ComponentEdit<Lattice> lattice_edit(registry, state.active_lattice, "apply as rest");
    Lattice next = *lattice;
    const std::vector<ecs::Entity> clouds = clouds_of(registry, state.active_lattice, true);
    for (std::size_t c = 0; c < clouds.size(); ++c) {
        ComponentEdit<SplatCloud> cloud_edit(registry, clouds[c], "bake");
        SplatCloud& cloud = registry.patch<SplatCloud>(clouds[c]);
        ffd::BakeTarget bake{&cloud.positions, cloud.normals.empty() ? nullptr : &cloud.normals,
                             cloud.axis_u.empty() ? nullptr : &cloud.axis_u,
                             cloud.axis_v.empty() ? nullptr : &cloud.axis_v, cloud.origin};
        // Each cloud is baked by the lattice in its own frame (both Transforms, as the deformation reads it);
        // apply_as_rest resets the lattice, so every cloud starts from the same one.
        Lattice scratch =
            ffd::map_lattice(*lattice, ffd::lattice_to_cloud(registry, clouds[c], state.active_lattice));
        if (Status st = ffd::apply_as_rest(scratch, &bake); !st) {
            group->add(cloud_edit.finish(registry));
            EntityMap none;  // not on the stack: nothing was re-created
            group->undo(registry, none);
            return say(state, "apply as rest: " + st.message()), false;
        }
        group->add(cloud_edit.finish(registry));
    }
    if (Status st = ffd::apply_as_rest(next); !st) {  // the lattice itself, in its own frame
        EntityMap none;
        if (!clouds.empty()) group->undo(registry, none);
        return say(state, "apply as rest: " + st.message()), false;
    }
    registry.patch<Lattice>(state.active_lattice) = std::move(next);
    group->add(lattice_edit.finish(registry));
    state.undo.push(std::move(group));
    state.last_edit = {};
    say(state, log::str("applied as rest (", clouds.size(), " clouds baked)"));
    return true;
}

}  // namespace sffd::editor
