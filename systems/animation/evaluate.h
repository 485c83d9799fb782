// Pure evaluation of animation data: no registry, no state. The animation system and the tests call these.
//
// Track value at clip time t (keys sorted by time):
//   t <= first key: first key's value;  t >= last key: last key's value;  no keys: zero (no effect).
//   Between keys a and b (t in [ta, tb)): u = easing_a((t - ta) / (tb - ta)), then a's interpolation:
//     step    value = va
//     linear  value = va + (vb - va) u
//     smooth  cubic Hermite  h00(u) va + h10(u) (tb-ta) ma + h01(u) vb + h11(u) (tb-ta) mb  with
//             Catmull-Rom tangents (value per second) m_i = (v[i+1] - v[i-1]) / (t[i+1] - t[i-1]) at interior
//             keys and m = 0 at the first and last key (the motion starts and ends at rest, no overshoot
//             past the end keys). C1 across interior keys when both neighbouring segments are smooth
//             without easing.
//   At a key time the value is that key's value exactly (u = 0 makes every other term an exact zero).
//
// Clip pose at clip time t: start from Lattice::rest, then apply the tracks IN TRACK ORDER, each one a
// transform of the running positions of its bound points:
//   stretch  p += value
//   twist    p = C + R(axis, value.x degrees) (p - C), C = track pivot or centroid of the bound REST points
// So a stretch followed by a twist on the same points rotates the stretched points about the rest
// centroid; the reverse order translates the rotated points. Angles are reduced modulo 360 exactly in
// degrees first: a twist by any multiple of 360 degrees leaves the points bit-for-bit unchanged, and
// 90/180/270 use exact sines and cosines.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "systems/animation/components.h"
#include "systems/ffd/components.h"

namespace sffd {

double apply_easing(Easing easing, double u);
glm::dvec3 evaluate_track(const AnimationTrack& track, double clip_time);

// Unmapped clip time at a frame-clock time (see AnimationState), then mapped by the clip's PlayMode.
double clip_raw_time(const AnimationClip& clip, const AnimationState& state, double clock_time);
double map_clip_time(const AnimationClip& clip, double raw_time);

// Twist pivot of a track: its explicit pivot, or the centroid of its bound rest points.
glm::dvec3 track_pivot(const AnimationTrack& track, const std::vector<glm::dvec3>& rest);
// C + R(axis, degrees)(p - C); axis need not be unit length (must be non-zero).
glm::dvec3 twist_point(const glm::dvec3& p, const glm::dvec3& pivot, const glm::dvec3& axis, double degrees);

// Writes the lattice's control points at clip time t into `out` (resized to lattice.rest.size()).
// Indices out of range are skipped (validate_clip reports them).
void evaluate_pose(const AnimationClip& clip, const Lattice& lattice, double clip_time,
                   std::vector<glm::dvec3>& out);
std::vector<glm::dvec3> evaluate_pose(const AnimationClip& clip, const Lattice& lattice, double clip_time);

// Checks a clip against a lattice of `point_count` control points: finite numbers, duration > 0,
// keys sorted with distinct times, point indices in range, non-zero twist axes.
// Errors read "clip 'name': tracks[2].keys[1]: times not increasing".
Status validate_clip(const AnimationClip& clip, std::size_t point_count);

}  // namespace sffd
