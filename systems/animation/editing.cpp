#include "systems/animation/editing.h"

#include <algorithm>
#include <cmath>

namespace sffd {

std::optional<std::size_t> find_key(const AnimationTrack& track, double time) {
    for (std::size_t i = 0; i < track.keys.size(); ++i)
        if (std::abs(track.keys[i].time - time) <= key_time_epsilon) return i;
    return std::nullopt;
}

std::size_t set_key(AnimationTrack& track, const Keyframe& key) {
    if (auto i = find_key(track, key.time)) {
        const double kept = track.keys[*i].time;
        track.keys[*i] = key;
        track.keys[*i].time = kept;
        return *i;
    }
    const auto pos = std::upper_bound(track.keys.begin(), track.keys.end(), key.time,
                                      [](double t, const Keyframe& k) { return t < k.time; });
    const auto inserted = track.keys.insert(pos, key);  // may reallocate: take begin() afterwards
    return static_cast<std::size_t>(inserted - track.keys.begin());
}

bool delete_key(AnimationTrack& track, double time) {
    const auto i = find_key(track, time);
    if (!i) return false;
    track.keys.erase(track.keys.begin() + static_cast<std::ptrdiff_t>(*i));
    return true;
}

std::vector<KeyRef> list_keys(const AnimationClip& clip) {
    std::vector<KeyRef> refs;
    for (std::size_t t = 0; t < clip.tracks.size(); ++t)
        for (std::size_t k = 0; k < clip.tracks[t].keys.size(); ++k)
            refs.push_back({t, k, clip.tracks[t].keys[k].time});
    std::stable_sort(refs.begin(), refs.end(),
                     [](const KeyRef& a, const KeyRef& b) { return a.time < b.time; });
    return refs;
}

std::size_t add_stretch_track(AnimationClip& clip, std::string name, std::vector<std::uint32_t> points) {
    AnimationTrack track;
    track.name = std::move(name);
    track.kind = TrackKind::stretch;
    track.points = std::move(points);
    clip.tracks.push_back(std::move(track));
    return clip.tracks.size() - 1;
}

std::size_t add_twist_track(AnimationClip& clip, std::string name, std::vector<std::uint32_t> points,
                            const glm::dvec3& axis, std::optional<glm::dvec3> pivot) {
    AnimationTrack track;
    track.name = std::move(name);
    track.kind = TrackKind::twist;
    track.points = std::move(points);
    track.axis = axis;
    track.has_pivot = pivot.has_value();
    track.pivot = pivot.value_or(glm::dvec3(0.0));
    clip.tracks.push_back(std::move(track));
    return clip.tracks.size() - 1;
}

void play(AnimationState& state) {
    if (state.playing) return;
    // Paused, the raw time is anchor_time; continue from it at the next frame's clock time.
    state.playing = true;
    state.rebase = true;
}

void pause(AnimationState& state) {
    if (!state.playing) return;
    // Freeze at the last shown frame, unless a scrub is pending (then anchor_time already holds it).
    if (!state.rebase) state.anchor_time = state.raw_time;
    state.playing = false;
    state.rebase = false;
}

void scrub(AnimationState& state, double clip_time) {
    state.anchor_time = clip_time;
    state.rebase = state.playing;
}

void set_speed(AnimationState& state, double speed) {
    if (state.playing && !state.rebase) {
        state.anchor_time = state.raw_time;
        state.rebase = true;
    }
    state.speed = speed;
}

void attach_clip(ecs::Registry& registry, ecs::Entity lattice_entity, AnimationClip clip, bool playing) {
    if (registry.has<AnimationClip>(lattice_entity)) registry.remove<AnimationClip>(lattice_entity);
    if (registry.has<AnimationState>(lattice_entity)) registry.remove<AnimationState>(lattice_entity);
    // An un-keyed edit was made over the old clip's pose; it means nothing over another clip.
    if (registry.has<UnkeyedEdit>(lattice_entity)) registry.remove<UnkeyedEdit>(lattice_entity);
    registry.emplace<AnimationClip>(lattice_entity, std::move(clip));
    AnimationState state;
    state.playing = playing;
    registry.emplace<AnimationState>(lattice_entity, std::move(state));
}

}  // namespace sffd
