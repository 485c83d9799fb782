// Animation components: plain data. Owned by the animation system (systems/animation); the editor's
// timeline edits them through systems/animation/editing.h, the scene file stores them (clip_io.h).
//
// An AnimationClip sits on a lattice entity (next to its Lattice). Each track is bound to a set of control
// points (indices into Lattice::rest / Lattice::current) and carries keyframes:
//   stretch  key value = displacement vector (lattice world units), paper eq. (23): P' = P + V
//   twist    key value.x = angle in DEGREES, unbounded (720 is two turns), paper eq. (24):
//            P' = C + R(axis, angle) (P - C), C = pivot (default: centroid of the bound REST points)
// Every frame the pose is rebuilt from Lattice::rest (no drift): tracks are applied in track order, each
// one transforming the running positions of its points (see evaluate.h).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace sffd {

// How the segment that STARTS at a key is interpolated (the last key's mode is unused).
enum class Interpolation : std::uint8_t {
    step,    // hold this key's value until the next key
    linear,  // straight line to the next key
    smooth,  // cubic Hermite, Catmull-Rom tangents (evaluate.h documents the tangents)
};

// Reparametrisation of the segment's normalised time u in [0,1] before interpolating (f(0)=0, f(1)=1).
enum class Easing : std::uint8_t {
    none,         // u
    ease_in,      // u^2           (starts slow)
    ease_out,     // 1-(1-u)^2     (ends slow)
    ease_in_out,  // 3u^2 - 2u^3   (smoothstep: slow at both ends)
};

enum class TrackKind : std::uint8_t { stretch, twist };

enum class PlayMode : std::uint8_t {
    loop,       // time wraps to 0 at duration
    once,       // time clamps to [0, duration]
    ping_pong,  // forward to duration, back to 0, forward again...
};

struct Keyframe {
    double time = 0.0;      // seconds of clip time
    glm::dvec3 value{0.0};  // stretch: displacement; twist: value.x = angle in degrees (y, z unused, 0)
    Interpolation interpolation = Interpolation::smooth;
    Easing easing = Easing::none;
};

struct AnimationTrack {
    std::string name;
    TrackKind kind = TrackKind::stretch;
    std::vector<std::uint32_t> points;  // control-point flat indices, (i*(m+1)+j)*(n+1)+k
    std::vector<Keyframe> keys;         // sorted by time, distinct times (editing.h keeps it so)
    // Twist only. The axis need not be unit length (normalised at evaluation) but must be non-zero.
    glm::dvec3 axis{0.0, 0.0, 1.0};
    bool has_pivot = false;  // false: pivot = centroid of the bound rest points
    glm::dvec3 pivot{0.0};
};

struct AnimationClip {
    std::string name;
    std::vector<AnimationTrack> tracks;  // applied in this order
    double duration = 1.0;               // seconds of clip time (> 0)
    PlayMode mode = PlayMode::loop;
    double speed = 1.0;  // clip-time seconds per playback second
};

// Playback state of the clip on the same entity. The clip time is a pure function of the frame clock:
//   raw = anchor_time + (frame.time - anchor_clock) * speed * clip.speed   (playing)
//   raw = anchor_time                                                      (paused)
//   clip time = raw mapped by the clip's PlayMode into [0, duration]
// so in a fixed-step run frame k evaluates the same pose whether rendered alone or in a sequence.
// editing.h's play/pause/scrub move the anchor; the system fills in anchor_clock on the next frame.
struct AnimationState {
    bool playing = true;
    double speed = 1.0;         // playback speed multiplier (negative plays backwards)
    double anchor_time = 0.0;   // raw clip time at clock time anchor_clock
    double anchor_clock = 0.0;  // frame-clock seconds
    bool rebase = false;        // set by play/scrub: the next frame sets anchor_clock = frame.time

    // Derived, written by animation_system (read by the timeline; never authored):
    double time = 0.0;                  // mapped clip time of the last evaluated frame
    double raw_time = 0.0;              // unmapped clip time of the last evaluated frame
    std::vector<glm::dvec3> last_pose;  // the control points last written into Lattice::current
    std::string error;                  // why the clip is not applied (invalid for this lattice), or empty
};

// A pose edited by hand and not keyed, on a lattice with a clip (authored, like the clip). It belongs to
// one clip time: wherever the clip time is `time` (within key_time_epsilon, editing.h) the lattice shows
// `points` instead of the clip's pose, and the clip's pose at every other time. Every command follows
// the same rule because the animation system applies it: render shows it at that time's frames, view
// opens there, and a scene file keeps it with its time (scene_extension.h). One per lattice; keying the
// edit removes it.
struct UnkeyedEdit {
    double time = 0.0;               // clip time (mapped, in [0, duration])
    std::vector<glm::dvec3> points;  // the whole lattice's control points at that time
};

}  // namespace sffd
