// The editor's input system: setup, selection helpers and the state helpers its parts share (the parts:
// editor_input.cpp keys and typed entry, editor_tools.cpp mouse gestures, editor_commands.cpp operations,
// lattice_commands.cpp lattice settings).
#include "systems/editor/editor_system_detail.h"

#include <limits>
#include <type_traits>

#include "systems/editor/lattice_tools.h"
#include "systems/gaussian/components.h"

namespace sffd::editor {

const char* tool_name(Tool tool) {
    switch (tool) {
        case Tool::select: return "select";
        case Tool::move: return "move";
        case Tool::twist: return "twist";
        case Tool::brush: return "brush";
        case Tool::scale: return "scale";
    }
    return "?";
}

namespace detail {

void say(EditorState& state, std::string message) {
    log::info("editor: ", message);
    state.status = std::move(message);
}

Camera* camera_of(ecs::Registry& registry, EditorState& state) {
    if (registry.valid(state.camera))
        if (Camera* c = registry.try_get<Camera>(state.camera)) return c;
    return nullptr;
}

picking::ScreenView screen_view(const Camera& camera, const Viewport& vp) {
    return picking::make_screen_view(camera, {vp.width, vp.height});
}

glm::dmat4 lattice_model(const ecs::Registry& registry, ecs::Entity lattice) {
    return model_matrix(registry.try_get<Transform>(lattice));
}

const Lattice* active_lattice(const ecs::Registry& registry, const EditorState& state) {
    return registry.valid(state.active_lattice) ? registry.try_get<Lattice>(state.active_lattice) : nullptr;
}

// Undoing an added lattice (or redoing a removal) leaves the active entity without a Lattice: another
// lattice, if any, becomes active, so the panels and tools do not show "no lattice" beside lattices.
void keep_an_active_lattice(ecs::Registry& registry, EditorState& state) {
    if (active_lattice(registry, state)) return;
    state.active_lattice = ecs::null_entity;
    registry.view<Lattice>().each([&](ecs::Entity e, Lattice&) {
        if (!state.active_lattice) state.active_lattice = e;
    });
}

std::vector<std::uint32_t> selection_of(const ecs::Registry& registry, ecs::Entity lattice) {
    if (const auto* s = registry.try_get<picking::LatticeSelection>(lattice)) return s->indices;
    return {};
}

}  // namespace detail

using namespace detail;

void set_selection(ecs::Registry& registry, EditorState& state, ecs::Entity lattice,
                   std::vector<std::uint32_t> indices, const char* label) {
    if (!registry.valid(lattice) || !registry.has<Lattice>(lattice)) return;
    const auto* current = registry.try_get<picking::LatticeSelection>(lattice);
    if (current && current->indices == indices) return;
    if (!current && indices.empty()) return;
    ComponentEdit<picking::LatticeSelection> edit(registry, lattice, label);
    if (current) registry.patch<picking::LatticeSelection>(lattice).indices = std::move(indices);
    else registry.emplace<picking::LatticeSelection>(lattice, picking::LatticeSelection{std::move(indices)});
    state.undo.push(edit.finish(registry));
}

std::vector<std::uint32_t> editable_selection(const ecs::Registry& registry, const EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return {};
    const std::vector<std::uint32_t> sel = selection_of(registry, state.active_lattice);
    return editable_points(*lattice, sel, state.scope, state.pin_outer_layer);
}

namespace {

// One cloud's world box: every authored point through its model matrix (exact, O(points)).
template <class Cloud>
SceneBoundsCache::Entry cloud_box(const ecs::Registry& registry, ecs::Entity e, const Cloud& cloud) {
    SceneBoundsCache::Entry box;
    box.entity = e;
    box.cloud_version = registry.version<Cloud>(e);
    box.transform_version = registry.version<Transform>(e);
    box.gaussian = std::is_same_v<Cloud, GaussianCloud>;
    const glm::dmat4 model = model_matrix(registry.try_get<Transform>(e));
    glm::dvec3 a(std::numeric_limits<double>::max()), b(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : cloud.positions) {
        const glm::dvec3 w = glm::dvec3(model * glm::dvec4(cloud.origin + glm::dvec3(p), 1.0));
        a = glm::min(a, w), b = glm::max(b, w);
    }
    box.any = !cloud.positions.empty();
    box.lo = a, box.hi = b;
    return box;
}

template <class Cloud>
const SceneBoundsCache::Entry* cached_box(const SceneBoundsCache* cache, const ecs::Registry& registry,
                                          ecs::Entity e) {
    if (!cache) return nullptr;
    const bool gaussian = std::is_same_v<Cloud, GaussianCloud>;
    for (const SceneBoundsCache::Entry& c : cache->entries)
        if (c.entity == e && c.gaussian == gaussian)
            return c.cloud_version == registry.version<Cloud>(e) &&
                           c.transform_version == registry.version<Transform>(e)
                       ? &c
                       : nullptr;
    return nullptr;
}

}  // namespace

bool scene_bounds(const ecs::Registry& registry, glm::dvec3& lo, glm::dvec3& hi) {
    bool any = false;
    lo = glm::dvec3(std::numeric_limits<double>::max());
    hi = -lo;
    const SceneBoundsCache* cache = registry.try_resource<SceneBoundsCache>();
    auto add = [&](const SceneBoundsCache::Entry& box) {
        if (box.any) lo = glm::min(lo, box.lo), hi = glm::max(hi, box.hi), any = true;
    };
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        const auto* c = cached_box<SplatCloud>(cache, registry, e);
        add(c ? *c : cloud_box(registry, e, cloud));
    });
    // Gaussians count as the object too: a lattice added to a Gaussian file has them inside.
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& g) {
        const auto* c = cached_box<GaussianCloud>(cache, registry, e);
        add(c ? *c : cloud_box(registry, e, g));
    });
    return any;
}

void update_scene_bounds_cache(ecs::Registry& registry) {
    SceneBoundsCache* cache = registry.try_resource<SceneBoundsCache>();
    if (!cache) cache = &registry.set_resource<SceneBoundsCache>();
    std::vector<SceneBoundsCache::Entry> entries;
    auto keep = [&]<class Cloud>(ecs::Entity e, const Cloud& cloud) {
        if (const auto* c = cached_box<Cloud>(cache, registry, e)) {
            entries.push_back(*c);
        } else {
            entries.push_back(cloud_box(registry, e, cloud));
            ++cache->computed;
        }
    };
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) { keep(e, c); });
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& g) { keep(e, g); });
    cache->entries = std::move(entries);  // gone clouds drop out
}

std::size_t control_points_inside_object(const ecs::Registry& registry, const Lattice& lattice) {
    glm::dvec3 lo, hi;
    if (!scene_bounds(registry, lo, hi)) return 0;
    const auto mask = inside_box_mask(lattice, lo, hi);
    return std::size_t(std::count(mask.begin(), mask.end(), std::uint8_t(1)));
}

const char* entity_kind(const ecs::Registry& registry, ecs::Entity e) {
    if (registry.has<SplatCloud>(e)) return "surface";
    if (registry.has<GaussianCloud>(e)) return "Gaussians";
    if (registry.has<Lattice>(e)) return "lattice";
    if (registry.has<Camera>(e)) return "camera";
    if (registry.has<DirectionalLight>(e) || registry.has<AmbientLight>(e)) return "light";
    return "";
}

EditorState& setup_editor(ecs::Registry& registry, const Viewport& viewport) {
    EditorState* state = registry.try_resource<EditorState>();
    if (!state) state = &registry.set_resource<EditorState>();
    state->viewport = viewport;
    if (!registry.valid(state->camera) || !registry.has<Camera>(state->camera)) {
        state->camera = ecs::null_entity;
        registry.view<Camera>().each([&](ecs::Entity e, Camera&) { state->camera = e; });
    }
    if (!registry.valid(state->camera)) {
        const ecs::Entity e = registry.create();
        registry.emplace<Name>(e, Name{"editor camera"});
        Camera& cam = registry.emplace<Camera>(e);
        glm::dvec3 lo, hi;
        if (scene_bounds(registry, lo, hi)) {
            cam.eye = glm::dvec3(0.35, 0.3, 1.0);  // direction only; framing sets the distance
            const glm::dvec3 corners[2] = {lo, hi};
            frame_points(cam, viewport, corners, 1.05);
            cam.near_plane = float(glm::length(hi - lo) * 1e-3);
        }
        state->camera = e;
    }
    if (!registry.valid(state->active_lattice) || !registry.has<Lattice>(state->active_lattice)) {
        state->active_lattice = ecs::null_entity;
        registry.view<Lattice>().each([&](ecs::Entity e, Lattice&) { state->active_lattice = e; });
    }
    // Paused where the scene was saved (AnimationState::time on loading), so the editor opens on the pose
    // the file holds; a loaded un-keyed edit is the editor's own from here on (status bar, play warning).
    registry.view<AnimationState>().each([&](ecs::Entity e, AnimationState& s) {
        sffd::pause(s);
        if (registry.has<UnkeyedEdit>(e)) state->unkeyed = e;
    });
    return *state;
}

}  // namespace sffd::editor
