// Editor-facing API (the editor's timeline panel calls these). Plain functions over the
// components: the caller gets them with registry.patch<AnimationClip>(e) / patch<AnimationState>(e) so
// change stamps move. Every edit keeps a track's keys sorted with distinct times; the animation system
// re-evaluates the pose on the next frame (also while paused).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/animation/components.h"

namespace sffd {

// Two key times closer than this are the same key (set_key replaces, delete_key/find_key match).
inline constexpr double key_time_epsilon = 1e-6;

// Inserts `key`, or replaces the key already at key.time (within key_time_epsilon; the existing key's
// time is kept so repeated edits at a frame do not drift). Returns the key's index.
std::size_t set_key(AnimationTrack& track, const Keyframe& key);
// Removes the key at `time`; false if there is none.
bool delete_key(AnimationTrack& track, double time);
// Index of the key at `time`, if any.
std::optional<std::size_t> find_key(const AnimationTrack& track, double time);

// Every key of a clip for the timeline: sorted by time, then track index.
struct KeyRef {
    std::size_t track = 0;
    std::size_t key = 0;
    double time = 0.0;
};
std::vector<KeyRef> list_keys(const AnimationClip& clip);

// Tracks. Return the new track's index.
std::size_t add_stretch_track(AnimationClip& clip, std::string name, std::vector<std::uint32_t> points);
std::size_t add_twist_track(AnimationClip& clip, std::string name, std::vector<std::uint32_t> points,
                            const glm::dvec3& axis, std::optional<glm::dvec3> pivot = std::nullopt);

// Playback. Scrub sets the clip time shown from the next frame on (playing continues from there).
void play(AnimationState& state);
void pause(AnimationState& state);
void scrub(AnimationState& state, double clip_time);
// Changes the playback speed from the current frame on (the clip time does not jump).
void set_speed(AnimationState& state, double speed);

// Puts a clip and a fresh playing state on a lattice entity (replacing any previous clip and its
// un-keyed edit).
void attach_clip(ecs::Registry& registry, ecs::Entity lattice_entity, AnimationClip clip,
                 bool playing = true);

}  // namespace sffd
