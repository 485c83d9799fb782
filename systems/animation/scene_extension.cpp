#include "systems/animation/scene_extension.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/animation/clip_io.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/ffd/components.h"

namespace sffd {

using nlohmann::json;

namespace {
constexpr const char* kKey = "animation";
constexpr int kVersion = 1;
}  // namespace

Result<std::string> save_animation_extension(const ecs::Registry& registry,
                                             const std::function<int(ecs::Entity)>& id_of) {
    // Deterministic order: by scene id.
    std::vector<std::pair<int, json>> entries;
    registry.view<const AnimationClip, const Lattice>().each(
        [&](ecs::Entity e, const AnimationClip& clip, const Lattice&) {
            const int id = id_of(e);
            if (id < 0) return;  // the file does not hold this lattice
            json entry;
            entry["lattice"] = id;
            const AnimationState* state = registry.try_get<AnimationState>(e);
            // Not `playing`: the editor's pause is view state, not scene content, so a saved scene animates
            // wherever it is rendered (`view` pauses clips on load by itself).
            entry["speed"] = state ? state->speed : 1.0;
            // The clip time the file's control points were shown at: commands without a clock (deform,
            // convert, pick, info) use those points, and `view` opens there.
            entry["time"] = state ? state->time : 0.0;
            entry["clip"] = clip_to_json(clip);
            if (std::optional<UnkeyedEdit> edit = current_unkeyed_edit(registry, e)) {
                json points = json::array();
                for (const glm::dvec3& p : edit->points) points.push_back(json::array({p.x, p.y, p.z}));
                entry["unkeyed_edit"] = json{{"time", edit->time}, {"control_points", std::move(points)}};
            }
            entries.emplace_back(id, std::move(entry));
        });
    if (entries.empty()) return std::string();
    std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    json clips = json::array();
    for (auto& [id, entry] : entries) clips.push_back(std::move(entry));
    return json{{"version", kVersion}, {"clips", std::move(clips)}}.dump();
}

Status load_animation_extension(ecs::Registry& registry, std::string_view text,
                                const std::function<ecs::Entity(int)>& entity_of) {
    json j;
    try {
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {
        return make_error(std::string("not valid JSON (") + e.what() + ")");
    }
    if (!j.is_object() || !j.contains("clips") || !j["clips"].is_array())
        return make_error("expected an object with a 'clips' array");
    if (!j.contains("version") || !j["version"].is_number_integer() ||
        j["version"].get<long long>() != kVersion)
        return make_error("'version' must be " + std::to_string(kVersion));
    const json& clips = j["clips"];
    // Parse and check everything before touching the registry.
    struct Pending {
        ecs::Entity lattice;
        AnimationClip clip;
        bool playing;
        double speed;
        double time;
        std::optional<UnkeyedEdit> edit;
    };
    std::vector<Pending> pending;
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const json& c = clips[i];
        const std::string where = "clips[" + std::to_string(i) + "]";
        if (!c.is_object()) return make_error(where + ": expected an object");
        if (!c.contains("lattice") || !c["lattice"].is_number_integer())
            return make_error(where + ".lattice: expected an entity id");
        const long long id = c["lattice"].get<long long>();
        const ecs::Entity e =
            (id >= 0 && id <= 1'000'000'000) ? entity_of(static_cast<int>(id)) : ecs::null_entity;
        if (!registry.valid(e) || !registry.has<Lattice>(e))
            return make_error(where + ".lattice: " + std::to_string(id) + " is not a lattice of this scene");
        bool playing = true;
        double speed = 1.0;
        // Files from before the pause became view state may carry "playing": still checked, but a clip
        // loaded from a scene always plays.
        if (c.contains("playing") && !c["playing"].is_boolean())
            return make_error(where + ".playing: expected true or false");
        if (c.contains("speed")) {
            if (!c["speed"].is_number() || !std::isfinite(c["speed"].get<double>()))
                return make_error(where + ".speed: expected a finite number");
            speed = c["speed"].get<double>();
        }
        const auto clip_time = [&](const json& t, const std::string& path, double& out) -> Status {
            if (!t.is_number() || !std::isfinite(t.get<double>()) || t.get<double>() < 0.0)
                return make_error(path + ": expected a clip time in seconds (a finite number >= 0)");
            out = t.get<double>();
            return {};
        };
        double time = 0.0;
        if (c.contains("time"))
            if (Status st = clip_time(c["time"], where + ".time", time); !st) return st;
        if (!c.contains("clip")) return make_error(where + ".clip: missing");
        Result<AnimationClip> clip = clip_from_json(c["clip"], where + ".clip");
        if (!clip) return clip.error();
        const Lattice& lattice = registry.get<Lattice>(e);
        if (Status valid = validate_clip(*clip, lattice.rest.size()); !valid)
            return make_error(where + ": " + valid.message());
        std::optional<UnkeyedEdit> edit;
        if (c.contains("unkeyed_edit")) {
            const json& u = c["unkeyed_edit"];
            const std::string at = where + ".unkeyed_edit";
            if (!u.is_object() || !u.contains("time") || !u.contains("control_points"))
                return make_error(at + ": expected an object with 'time' and 'control_points'");
            edit.emplace();
            if (Status st = clip_time(u["time"], at + ".time", edit->time); !st) return st;
            const json& points = u["control_points"];
            if (!points.is_array() || points.size() != lattice.rest.size())
                return make_error(
                    at + ".control_points: expected " + std::to_string(lattice.rest.size()) +
                    " points (the lattice's), got " +
                    (points.is_array() ? std::to_string(points.size()) : std::string("no array")));
            for (std::size_t k = 0; k < points.size(); ++k) {
                const json& p = points[k];
                const auto finite = [](const json& v) {
                    return v.is_number() && std::isfinite(v.get<double>());
                };
                if (!p.is_array() || p.size() != 3 || !finite(p[0]) || !finite(p[1]) || !finite(p[2]))
                    return make_error(at + ".control_points[" + std::to_string(k) +
                                      "]: expected [x, y, z] (finite numbers)");
                edit->points.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
            }
        } else if (!c.contains("time") && lattice.current.size() == lattice.rest.size() &&
                   lattice.current != evaluate_pose(*clip, lattice, 0.0)) {
            // Files from before the time was saved: their editor opened clips at 0 s, so control points
            // off the clip's pose there are an un-keyed edit made at 0 s.
            edit = UnkeyedEdit{0.0, lattice.current};
        }
        pending.push_back({e, std::move(*clip), playing, speed, time, std::move(edit)});
    }
    for (Pending& p : pending) {
        attach_clip(registry, p.lattice, std::move(p.clip), p.playing);
        AnimationState& state = registry.get<AnimationState>(p.lattice);
        state.speed = p.speed;
        // The loaded control points are the pose at the saved time (a pause there, e.g. the editor's on
        // opening, holds it); playing still starts the clip at 0 s.
        state.time = state.raw_time = p.time;
        if (p.edit) registry.emplace<UnkeyedEdit>(p.lattice, std::move(*p.edit));
    }
    return {};
}

void register_animation_scene_hooks(SceneHooks& hooks) {
    hooks.add_extension(kKey, save_animation_extension, load_animation_extension);
    hooks.add_builtin_hook(
        kKey, [](ecs::Registry& registry, const std::string&, const std::vector<ecs::Entity>& created) {
            for (ecs::Entity e : created) {
                const Lattice* lattice = registry.try_get<Lattice>(e);
                if (!lattice || registry.has<AnimationClip>(e)) continue;
                const glm::ivec3 d = lattice->divisions;
                if (d.x < 4 || d.y < 4 || d.z < 4) continue;
                attach_clip(registry, e, make_paper_demo_clip(*lattice));
            }
        });
}

}  // namespace sffd
