#include "systems/animation/evaluate.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sffd {

double apply_easing(Easing easing, double u) {
    switch (easing) {
        case Easing::none: return u;
        case Easing::ease_in: return u * u;
        case Easing::ease_out: return 1.0 - (1.0 - u) * (1.0 - u);
        case Easing::ease_in_out: return u * u * (3.0 - 2.0 * u);
    }
    return u;
}

namespace {

// Catmull-Rom tangent at key i (value per second); zero at the end keys.
glm::dvec3 tangent(const std::vector<Keyframe>& keys, std::size_t i) {
    if (i == 0 || i + 1 >= keys.size()) return glm::dvec3(0.0);
    return (keys[i + 1].value - keys[i - 1].value) / (keys[i + 1].time - keys[i - 1].time);
}

}  // namespace

glm::dvec3 evaluate_track(const AnimationTrack& track, double clip_time) {
    const std::vector<Keyframe>& keys = track.keys;
    if (keys.empty()) return glm::dvec3(0.0);
    if (!(clip_time > keys.front().time)) return keys.front().value;  // also catches NaN time
    if (clip_time >= keys.back().time) return keys.back().value;
    // First key with time > t; the segment starts at the key before it.
    const auto next = std::upper_bound(keys.begin(), keys.end(), clip_time,
                                       [](double t, const Keyframe& k) { return t < k.time; });
    const std::size_t b = static_cast<std::size_t>(next - keys.begin());
    const std::size_t a = b - 1;
    const Keyframe& ka = keys[a];
    const Keyframe& kb = keys[b];
    const double span = kb.time - ka.time;
    const double u = apply_easing(ka.easing, (clip_time - ka.time) / span);
    switch (ka.interpolation) {
        case Interpolation::step: return ka.value;
        case Interpolation::linear: return ka.value + (kb.value - ka.value) * u;
        case Interpolation::smooth: {
            const double u2 = u * u, u3 = u2 * u;
            const double h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
            const double h10 = u3 - 2.0 * u2 + u;
            const double h01 = -2.0 * u3 + 3.0 * u2;
            const double h11 = u3 - u2;
            return h00 * ka.value + (h10 * span) * tangent(keys, a) + h01 * kb.value +
                   (h11 * span) * tangent(keys, b);
        }
    }
    return ka.value;
}

double clip_raw_time(const AnimationClip& clip, const AnimationState& state, double clock_time) {
    if (!state.playing) return state.anchor_time;
    return state.anchor_time + (clock_time - state.anchor_clock) * state.speed * clip.speed;
}

double map_clip_time(const AnimationClip& clip, double raw_time) {
    const double d = clip.duration;
    if (!(d > 0.0) || !std::isfinite(raw_time)) return 0.0;
    switch (clip.mode) {
        case PlayMode::once: return std::clamp(raw_time, 0.0, d);
        case PlayMode::loop: {
            double r = std::fmod(raw_time, d);  // exact
            if (r < 0.0) r += d;
            return r >= d ? 0.0 : r;
        }
        case PlayMode::ping_pong: {
            const double period = 2.0 * d;
            double r = std::fmod(raw_time, period);
            if (r < 0.0) r += period;
            if (r >= period) r = 0.0;
            return r > d ? period - r : r;
        }
    }
    return 0.0;
}

glm::dvec3 track_pivot(const AnimationTrack& track, const std::vector<glm::dvec3>& rest) {
    if (track.has_pivot) return track.pivot;
    glm::dvec3 sum(0.0);
    std::size_t n = 0;
    for (std::uint32_t idx : track.points) {
        if (idx >= rest.size()) continue;
        sum += rest[idx];
        ++n;
    }
    return n ? sum / double(n) : sum;
}

namespace {

// One twist as a rotation ready to apply: sines and cosines once per track, not per point.
struct Twist {
    bool identity = true;
    glm::dvec3 pivot{0.0}, k{0.0};
    double c = 1.0, s = 0.0;

    Twist(const glm::dvec3& pivot_, const glm::dvec3& axis, double degrees) : pivot(pivot_) {
        // Reduce in degrees (fmod is exact) so whole turns are exactly the identity.
        double r = std::fmod(degrees, 360.0);
        if (r < 0.0) r += 360.0;
        const double len = glm::length(axis);
        if (r >= 360.0 || r == 0.0 || !std::isfinite(r) || !(len > 0.0)) return;
        identity = false;
        k = axis / len;
        if (r == 90.0) {
            c = 0.0;
            s = 1.0;
        } else if (r == 180.0) {
            c = -1.0;
            s = 0.0;
        } else if (r == 270.0) {
            c = 0.0;
            s = -1.0;
        } else {
            const double rad = r * (std::numbers::pi / 180.0);
            c = std::cos(rad);
            s = std::sin(rad);
        }
    }
    glm::dvec3 apply(const glm::dvec3& p) const {
        if (identity) return p;
        const glm::dvec3 d = p - pivot;
        // Rodrigues' rotation formula.
        return pivot + d * c + glm::cross(k, d) * s + k * (glm::dot(k, d) * (1.0 - c));
    }
};

}  // namespace

glm::dvec3 twist_point(const glm::dvec3& p, const glm::dvec3& pivot, const glm::dvec3& axis, double degrees) {
    return Twist(pivot, axis, degrees).apply(p);
}

void evaluate_pose(const AnimationClip& clip, const Lattice& lattice, double clip_time,
                   std::vector<glm::dvec3>& out) {
    out = lattice.rest;
    for (const AnimationTrack& track : clip.tracks) {
        if (track.points.empty() || track.keys.empty()) continue;
        const glm::dvec3 value = evaluate_track(track, clip_time);
        if (track.kind == TrackKind::stretch) {
            if (value == glm::dvec3(0.0)) continue;
            for (std::uint32_t idx : track.points)
                if (idx < out.size()) out[idx] += value;
        } else {
            const Twist twist(track_pivot(track, lattice.rest), track.axis, value.x);
            if (twist.identity) continue;
            for (std::uint32_t idx : track.points)
                if (idx < out.size()) out[idx] = twist.apply(out[idx]);
        }
    }
}

std::vector<glm::dvec3> evaluate_pose(const AnimationClip& clip, const Lattice& lattice, double clip_time) {
    std::vector<glm::dvec3> out;
    evaluate_pose(clip, lattice, clip_time, out);
    return out;
}

namespace {
bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
}  // namespace

Status validate_clip(const AnimationClip& clip, std::size_t point_count) {
    const std::string where = "clip '" + clip.name + "': ";
    if (!(clip.duration > 0.0) || !std::isfinite(clip.duration))
        return make_error(where + "duration must be a positive finite number");
    if (!std::isfinite(clip.speed)) return make_error(where + "speed must be finite");
    for (std::size_t t = 0; t < clip.tracks.size(); ++t) {
        const AnimationTrack& track = clip.tracks[t];
        const std::string tw = where + "tracks[" + std::to_string(t) + "]";
        for (std::uint32_t idx : track.points)
            if (idx >= point_count)
                return make_error(tw + ": control point " + std::to_string(idx) +
                                  " out of range (lattice has " + std::to_string(point_count) + ")");
        if (track.kind == TrackKind::twist) {
            if (!finite3(track.axis) || glm::length(track.axis) == 0.0)
                return make_error(tw + ": twist axis must be finite and non-zero");
            if (track.has_pivot && !finite3(track.pivot)) return make_error(tw + ": pivot must be finite");
        }
        for (std::size_t k = 0; k < track.keys.size(); ++k) {
            const Keyframe& key = track.keys[k];
            const std::string kw = tw + ".keys[" + std::to_string(k) + "]";
            if (!std::isfinite(key.time) || !finite3(key.value))
                return make_error(kw + ": non-finite time or value");
            if (k > 0 && !(key.time > track.keys[k - 1].time))
                return make_error(kw + ": times not increasing");
        }
    }
    return {};
}

}  // namespace sffd
