// The editor's operations behind the shortcuts and panels: undo/redo, selection, numeric edits, framing,
// animation keys and playback.
#include "systems/editor/editor_system_detail.h"

#include "systems/animation/unkeyed_edit.h"
#include "systems/editor/unkeyed_undo.h"

namespace sffd::editor {

using namespace detail;

namespace {

// An undo or redo may have re-created entities (entity_undo.h): the editor's own references follow them.
void follow_recreated(EditorState& state) {
    for (ecs::Entity* e :
         {&state.active_lattice, &state.selected_entity, &state.unkeyed, &state.last_edit.lattice})
        *e = state.undo.resolve(*e);
}

}  // namespace

void undo(ecs::Registry& registry, EditorState& state) {
    if (state.drag.kind != Drag::Kind::none) return;
    const std::size_t at = state.undo.position();
    if (state.undo.undo(registry)) say(state, "undo " + state.undo.at(at - 1).label());
    else say(state, "nothing to undo");
    follow_recreated(state);
    keep_an_active_lattice(registry, state);
}

void redo(ecs::Registry& registry, EditorState& state) {
    if (state.drag.kind != Drag::Kind::none) return;
    const std::size_t at = state.undo.position();
    if (state.undo.redo(registry)) say(state, "redo " + state.undo.at(at).label());
    else say(state, "nothing to redo");
    follow_recreated(state);
    keep_an_active_lattice(registry, state);
}

void select_all(ecs::Registry& registry, EditorState& state) {
    const Lattice* lattice = active_lattice(registry, state);
    if (!lattice) return;
    std::vector<std::uint32_t> all(lattice->current.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    set_selection(registry, state, state.active_lattice, std::move(all), "select all");
}

void clear_selection(ecs::Registry& registry, EditorState& state) {
    if (active_lattice(registry, state)) set_selection(registry, state, state.active_lattice, {}, "deselect");
}

bool apply_stretch(ecs::Registry& registry, EditorState& state, const glm::dvec3& displacement) {
    Camera* camera = camera_of(registry, state);
    if (!camera || state.drag.kind != Drag::Kind::none) return false;
    const Tool tool = state.tool;
    state.tool = Tool::move;
    Drag drag;
    const bool ok = begin_tool_drag(registry, state, *camera, drag);
    state.tool = tool;
    if (!ok) return false;
    drag.displacement_world = displacement;
    apply_drag(registry, drag);
    finish_tool_drag(registry, state, drag);
    return true;
}

bool apply_twist(ecs::Registry& registry, EditorState& state, double degrees) {
    Camera* camera = camera_of(registry, state);
    if (!camera || state.drag.kind != Drag::Kind::none) return false;
    const Tool tool = state.tool;
    state.tool = Tool::twist;
    Drag drag;
    const bool ok = begin_tool_drag(registry, state, *camera, drag);
    state.tool = tool;
    if (!ok) return false;
    drag.angle = glm::radians(degrees);
    apply_drag(registry, drag);
    finish_tool_drag(registry, state, drag);
    return true;
}

bool apply_scale(ecs::Registry& registry, EditorState& state, const glm::dmat3& scale_world) {
    Camera* camera = camera_of(registry, state);
    if (!camera || state.drag.kind != Drag::Kind::none) return false;
    const Tool tool = state.tool;
    state.tool = Tool::scale;
    Drag drag;
    const bool ok = begin_tool_drag(registry, state, *camera, drag);
    state.tool = tool;
    if (!ok) return false;
    drag.scale_world = scale_world;
    apply_drag(registry, drag);
    finish_tool_drag(registry, state, drag);
    return true;
}

void toggle_proportional(EditorState& state) {
    state.proportional.enabled = !state.proportional.enabled;
    say(state,
        state.proportional.enabled
            ? log::str("proportional editing on (", falloff_name(state.proportional.falloff), ", radius ",
                       state.proportional.radius, "; wheel or PageUp/PageDown while dragging)")
            : std::string("proportional editing off"));
}

void cycle_falloff(EditorState& state) {
    state.proportional.falloff = Falloff((int(state.proportional.falloff) + 1) % falloff_count);
    say(state, log::str("proportional falloff: ", falloff_name(state.proportional.falloff)));
}

void reset_lattice(ecs::Registry& registry, EditorState& state) {
    if (!active_lattice(registry, state)) return;
    const ecs::Entity e = state.active_lattice;
    if (animated_lattice(registry, e)) {  // the animation owns current: the rest pose is an un-keyed edit
        const std::optional<UnkeyedEdit> before = ComponentEdit<UnkeyedEdit>::snapshot(registry, e);
        set_unkeyed_pose(registry, e,
                         UnkeyedEdit{registry.get<AnimationState>(e).time, registry.get<Lattice>(e).rest});
        if (state.undo.push(unkeyed_edit_change("reset", registry, e, before,
                                                ComponentEdit<UnkeyedEdit>::snapshot(registry, e)))) {
            state.unkeyed = e, state.play_warned = false;
            say(state, "lattice reset to rest at this clip time (un-keyed)");
        }
        return;
    }
    if (state.undo.record<Lattice>(registry, e, "reset", [](Lattice& l) { l.current = l.rest; }))
        say(state, "lattice reset to rest");
}

void frame_selection(ecs::Registry& registry, EditorState& state) {
    Camera* camera = camera_of(registry, state);
    if (!camera) return;
    std::vector<glm::dvec3> points;
    if (const Lattice* lattice = active_lattice(registry, state)) {
        const glm::dmat4 model = lattice_model(registry, state.active_lattice);
        for (std::uint32_t i : selection_of(registry, state.active_lattice))
            if (i < lattice->current.size())
                points.push_back(glm::dvec3(model * glm::dvec4(lattice->current[i], 1.0)));
    }
    if (points.size() < 2) {
        glm::dvec3 lo, hi;
        if (scene_bounds(registry, lo, hi)) points.push_back(lo), points.push_back(hi);
    }
    frame_points(*camera, state.viewport, points, 1.2);
}

double clip_time(const ecs::Registry& registry, const EditorState& state) {
    if (registry.valid(state.active_lattice))
        if (const auto* s = registry.try_get<AnimationState>(state.active_lattice)) return s->time;
    return 0.0;
}

void scrub_to(ecs::Registry& registry, EditorState& state, double time) {
    if (AnimationState* s = animation_state(registry, state)) {
        const auto* clip = registry.try_get<AnimationClip>(state.active_lattice);
        const double duration = clip ? clip->duration : 1.0;
        sffd::scrub(registry.patch<AnimationState>(state.active_lattice), std::clamp(time, 0.0, duration));
        (void)s;
    }
}

void toggle_play(ecs::Registry& registry, EditorState& state) {
    bool any_playing = false;
    registry.view<AnimationState>().each([&](ecs::Entity, AnimationState& s) { any_playing |= s.playing; });
    // Playing poses the lattice from its clip: an un-keyed stretch/twist would silently vanish.
    const ecs::Entity unkeyed = state.unkeyed;
    if (!any_playing && registry.valid(unkeyed) && registry.has<AnimationClip>(unkeyed) &&
        registry.has<Lattice>(unkeyed)) {
        if (!state.play_warned) {
            const Name* n = registry.try_get<Name>(unkeyed);
            const UnkeyedEdit* held = registry.try_get<UnkeyedEdit>(unkeyed);
            const AnimationState* s = registry.try_get<AnimationState>(unkeyed);
            const double unkeyed_time = held ? held->time : s ? s->time : 0.0;
            say(state, "playing shows the clip's pose: the un-keyed edit of " +
                           (n && !n->value.empty() ? n->value : std::string("the lattice")) +
                           log::str(" shows at ", unkeyed_time,
                                    " s only; k keys it, n turns auto-key on, space again plays anyway"));
            state.play_warned = true;
            return;
        }
        state.unkeyed = ecs::null_entity;  // played anyway: the clip's pose replaces it
        state.play_warned = false;
    }
    registry.view<AnimationState>().each([&](ecs::Entity e, AnimationState&) {
        AnimationState& s = registry.patch<AnimationState>(e);
        if (any_playing) sffd::pause(s);
        else sffd::play(s);
    });
    say(state, any_playing ? "paused" : "playing");
}

bool key_last_edit(ecs::Registry& registry, EditorState& state) {
    const LastEdit& edit = state.last_edit;
    if (!edit.not_keyable.empty()) {
        say(state, "set key: " + edit.not_keyable);
        return false;
    }
    if (edit.kind == LastEdit::Kind::none || !registry.valid(edit.lattice) ||
        !registry.has<Lattice>(edit.lattice)) {
        say(state, "set key: stretch or twist something first");
        return false;
    }
    const ecs::Entity e = edit.lattice;
    auto group = std::make_unique<CommandGroup>("set key");
    // Keyed, the edit is the clip's pose at this time: a held un-keyed pose there would hide later key
    // changes, so it goes. Its part of the step is made first, against the clip before the key (undo
    // restores the clip before it brings the edit back: unkeyed_undo.h).
    bool drop_held = false;
    if (const UnkeyedEdit* held = registry.try_get<UnkeyedEdit>(e);
        held && registry.has<AnimationState>(e) &&
        shows_unkeyed_edit(*held, registry.get<AnimationState>(e).time)) {
        group->add(unkeyed_edit_change("set key", registry, e, *held, std::nullopt));
        drop_held = true;
    }
    ComponentEdit<AnimationClip> clip_edit(registry, e, "clip");
    ComponentEdit<AnimationState> state_edit(registry, e, "animation state");
    if (!registry.has<AnimationClip>(e)) {
        AnimationClip clip;
        clip.name = "editor";
        attach_clip(registry, e, std::move(clip), false);
    }
    const double time = registry.get<AnimationState>(e).time;
    AnimationClip& clip = registry.patch<AnimationClip>(e);
    const TrackKind kind = edit.kind == LastEdit::Kind::stretch ? TrackKind::stretch : TrackKind::twist;
    // A twist keys the track of the same points, axis and pivot. The pivot is the selection's centroid,
    // recomputed after each edit, so a rotation moves it by rounding: equal within a millionth of the
    // lattice's diagonal (the unit axis within 1e-9), or keys at two times would land on two one-key tracks
    // that never animate.
    const Lattice& lattice = registry.get<Lattice>(e);
    const double size = glm::length(lattice.axes[0] + lattice.axes[1] + lattice.axes[2]);
    const auto near = [](const glm::dvec3& a, const glm::dvec3& b, double tolerance) {
        return glm::length(a - b) <= tolerance;
    };
    std::size_t track = clip.tracks.size();
    for (std::size_t t = 0; t < clip.tracks.size(); ++t) {
        const AnimationTrack& tr = clip.tracks[t];
        if (tr.kind == kind && tr.points == edit.points &&
            (kind == TrackKind::stretch ||
             (near(tr.axis, edit.axis, 1e-9) && tr.has_pivot && near(tr.pivot, edit.pivot, 1e-6 * size))))
            track = t;
    }
    if (track == clip.tracks.size()) {
        track = kind == TrackKind::stretch
                    ? add_stretch_track(clip, "stretch " + std::to_string(clip.tracks.size()), edit.points)
                    : add_twist_track(clip, "twist " + std::to_string(clip.tracks.size()), edit.points,
                                      edit.axis, edit.pivot);
    }
    Keyframe key;
    key.time = time;
    key.value =
        kind == TrackKind::stretch ? edit.displacement : glm::dvec3(glm::degrees(edit.angle), 0.0, 0.0);
    sffd::set_key(clip.tracks[track], key);
    clip.duration = std::max(clip.duration, time);
    group->add(clip_edit.finish(registry));
    group->add(state_edit.finish(registry));
    if (drop_held) registry.remove<UnkeyedEdit>(e);
    state.undo.push(std::move(group));
    if (state.unkeyed == e) state.unkeyed = ecs::null_entity, state.play_warned = false;
    say(state, log::str("key set at ", time, " s on track ", clip.tracks[track].name));
    return true;
}

bool delete_keys_at_time(ecs::Registry& registry, EditorState& state) {
    const ecs::Entity e = state.active_lattice;
    if (!registry.valid(e) || !registry.has<AnimationClip>(e) || !registry.has<AnimationState>(e))
        return false;
    const double time = registry.get<AnimationState>(e).time;
    ComponentEdit<AnimationClip> clip_edit(registry, e, "delete key");
    bool removed = false;
    AnimationClip& clip = registry.patch<AnimationClip>(e);
    for (AnimationTrack& track : clip.tracks) removed |= sffd::delete_key(track, time);
    if (removed) state.undo.push(clip_edit.finish(registry));
    say(state, removed ? log::str("deleted keys at ", time, " s") : log::str("no key at ", time, " s"));
    return removed;
}

}  // namespace sffd::editor
