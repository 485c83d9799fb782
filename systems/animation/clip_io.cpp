#include "systems/animation/clip_io.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include <array>

namespace sffd {

using nlohmann::json;

namespace {

const char* to_string(PlayMode m) {
    switch (m) {
        case PlayMode::loop: return "loop";
        case PlayMode::once: return "once";
        case PlayMode::ping_pong: return "ping_pong";
    }
    return "loop";
}
const char* to_string(TrackKind k) { return k == TrackKind::twist ? "twist" : "stretch"; }
const char* to_string(Interpolation i) {
    switch (i) {
        case Interpolation::step: return "step";
        case Interpolation::linear: return "linear";
        case Interpolation::smooth: return "smooth";
    }
    return "smooth";
}
const char* to_string(Easing e) {
    switch (e) {
        case Easing::none: return "none";
        case Easing::ease_in: return "ease_in";
        case Easing::ease_out: return "ease_out";
        case Easing::ease_in_out: return "ease_in_out";
    }
    return "none";
}

json vec3(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

// Reader with error context: every failure names the source and the JSON path.
struct Reader {
    const std::string& source;
    std::string error;

    bool fail(const std::string& path, const std::string& problem) {
        if (error.empty()) error = source + ": " + path + ": " + problem;
        return false;
    }
    bool number(const json& j, const std::string& path, double& out) {
        if (!j.is_number()) return fail(path, "expected a number");
        out = j.get<double>();
        if (!std::isfinite(out)) return fail(path, "not a finite number");
        return true;
    }
    bool vec(const json& j, const std::string& path, glm::dvec3& out) {
        if (!j.is_array() || j.size() != 3) return fail(path, "expected an array of 3 numbers");
        for (int c = 0; c < 3; ++c)
            if (!number(j[std::size_t(c)], path + "[" + std::to_string(c) + "]", out[c])) return false;
        return true;
    }
    bool string(const json& j, const std::string& path, std::string& out) {
        if (!j.is_string()) return fail(path, "expected a string");
        out = j.get<std::string>();
        return true;
    }
    template <class E, std::size_t N>
    bool enumeration(const json& obj, const char* key, const std::string& path, E& out,
                     const std::array<E, N>& values, E fallback) {
        out = fallback;
        if (!obj.contains(key)) return true;
        std::string name;
        if (!string(obj[key], path + "." + key, name)) return false;
        for (E v : values)
            if (name == to_string(v)) {
                out = v;
                return true;
            }
        std::string allowed;
        for (E v : values) allowed += std::string(allowed.empty() ? "" : ", ") + to_string(v);
        return fail(path + "." + key, "unknown value '" + name + "' (expected " + allowed + ")");
    }
};

}  // namespace

json clip_to_json(const AnimationClip& clip) {
    json tracks = json::array();
    for (const AnimationTrack& track : clip.tracks) {
        json t;
        t["name"] = track.name;
        t["kind"] = to_string(track.kind);
        t["points"] = track.points;
        if (track.kind == TrackKind::twist) {
            t["axis"] = vec3(track.axis);
            if (track.has_pivot) t["pivot"] = vec3(track.pivot);
        }
        json keys = json::array();
        for (const Keyframe& key : track.keys) {
            json k;
            k["time"] = key.time;
            if (track.kind == TrackKind::twist) k["angle"] = key.value.x;
            else k["value"] = vec3(key.value);
            k["interpolation"] = to_string(key.interpolation);
            k["easing"] = to_string(key.easing);
            keys.push_back(std::move(k));
        }
        t["keys"] = std::move(keys);
        tracks.push_back(std::move(t));
    }
    json j;
    j["name"] = clip.name;
    j["duration"] = clip.duration;
    j["mode"] = to_string(clip.mode);
    j["speed"] = clip.speed;
    j["tracks"] = std::move(tracks);
    return j;
}

Result<AnimationClip> clip_from_json(const json& j, const std::string& source) {
    Reader r{source, {}};
    AnimationClip clip;
    auto failed = [&]() -> Result<AnimationClip> { return make_error(r.error); };
    if (!j.is_object()) {
        r.fail("clip", "expected an object");
        return failed();
    }
    if (j.contains("name") && !r.string(j["name"], "name", clip.name)) return failed();
    if (!j.contains("duration")) {
        r.fail("duration", "missing");
        return failed();
    }
    if (!r.number(j["duration"], "duration", clip.duration)) return failed();
    if (!(clip.duration > 0.0)) {
        r.fail("duration", "must be > 0");
        return failed();
    }
    if (j.contains("speed") && !r.number(j["speed"], "speed", clip.speed)) return failed();
    if (!r.enumeration(j, "mode", "clip", clip.mode,
                       std::array{PlayMode::loop, PlayMode::once, PlayMode::ping_pong}, PlayMode::loop))
        return failed();
    if (!j.contains("tracks")) return clip;
    const json& tracks = j["tracks"];
    if (!tracks.is_array()) {
        r.fail("tracks", "expected an array");
        return failed();
    }
    for (std::size_t ti = 0; ti < tracks.size(); ++ti) {
        const json& t = tracks[ti];
        const std::string tp = "tracks[" + std::to_string(ti) + "]";
        if (!t.is_object()) {
            r.fail(tp, "expected an object");
            return failed();
        }
        AnimationTrack track;
        if (t.contains("name") && !r.string(t["name"], tp + ".name", track.name)) return failed();
        if (!t.contains("kind")) {
            r.fail(tp + ".kind", "missing");
            return failed();
        }
        if (!r.enumeration(t, "kind", tp, track.kind, std::array{TrackKind::stretch, TrackKind::twist},
                           TrackKind::stretch))
            return failed();
        if (t.contains("points")) {
            const json& pts = t["points"];
            if (!pts.is_array()) {
                r.fail(tp + ".points", "expected an array");
                return failed();
            }
            for (std::size_t pi = 0; pi < pts.size(); ++pi) {
                if (!pts[pi].is_number_unsigned() || pts[pi].get<std::uint64_t>() > 0xffffffffu) {
                    r.fail(tp + ".points[" + std::to_string(pi) + "]", "expected a control-point index");
                    return failed();
                }
                track.points.push_back(pts[pi].get<std::uint32_t>());
            }
        }
        if (track.kind == TrackKind::twist) {
            if (!t.contains("axis")) {
                r.fail(tp + ".axis", "missing (twist tracks need an axis)");
                return failed();
            }
            if (!r.vec(t["axis"], tp + ".axis", track.axis)) return failed();
            if (track.axis == glm::dvec3(0.0)) {
                r.fail(tp + ".axis", "must be non-zero");
                return failed();
            }
            if (t.contains("pivot")) {
                if (!r.vec(t["pivot"], tp + ".pivot", track.pivot)) return failed();
                track.has_pivot = true;
            }
        }
        if (t.contains("keys")) {
            const json& keys = t["keys"];
            if (!keys.is_array()) {
                r.fail(tp + ".keys", "expected an array");
                return failed();
            }
            for (std::size_t ki = 0; ki < keys.size(); ++ki) {
                const json& k = keys[ki];
                const std::string kp = tp + ".keys[" + std::to_string(ki) + "]";
                if (!k.is_object()) {
                    r.fail(kp, "expected an object");
                    return failed();
                }
                Keyframe key;
                if (!k.contains("time")) {
                    r.fail(kp + ".time", "missing");
                    return failed();
                }
                if (!r.number(k["time"], kp + ".time", key.time)) return failed();
                if (track.kind == TrackKind::twist) {
                    if (!k.contains("angle")) {
                        r.fail(kp + ".angle", "missing");
                        return failed();
                    }
                    if (!r.number(k["angle"], kp + ".angle", key.value.x)) return failed();
                } else {
                    if (!k.contains("value")) {
                        r.fail(kp + ".value", "missing");
                        return failed();
                    }
                    if (!r.vec(k["value"], kp + ".value", key.value)) return failed();
                }
                if (!r.enumeration(
                        k, "interpolation", kp, key.interpolation,
                        std::array{Interpolation::step, Interpolation::linear, Interpolation::smooth},
                        Interpolation::smooth))
                    return failed();
                if (!r.enumeration(
                        k, "easing", kp, key.easing,
                        std::array{Easing::none, Easing::ease_in, Easing::ease_out, Easing::ease_in_out},
                        Easing::none))
                    return failed();
                if (!track.keys.empty() && !(key.time > track.keys.back().time)) {
                    r.fail(kp + ".time", "key times must be strictly increasing");
                    return failed();
                }
                track.keys.push_back(key);
            }
        }
        clip.tracks.push_back(std::move(track));
    }
    return clip;
}

std::string clip_to_string(const AnimationClip& clip) { return clip_to_json(clip).dump(2) + "\n"; }

Result<AnimationClip> parse_clip(std::string_view text, const std::string& source) {
    if (Status s = check_json_depth(text, source); !s) return s.error();  // nlohmann's parser recurses
    json j;
    try {
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {  // caught here: no exception leaves the loader
        return make_error(source + ": not valid JSON (" + e.what() + ")");
    }
    return clip_from_json(j, source);
}

Status save_clip(const AnimationClip& clip, const std::filesystem::path& path) {
    return write_file_atomic(path, clip_to_string(clip));
}

Result<AnimationClip> load_clip(const std::filesystem::path& path) {
    auto text =
        read_file(path, kMaxJsonFileBytes);  // runtime/core/file_io.h: regular files only, size budget
    if (!text) return text.error();
    return parse_clip(*text, path.string());
}

}  // namespace sffd
