#include "systems/animation/scene_extension.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/animation/clip_io.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
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
            entry["clip"] = clip_to_json(clip);
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
        if (!c.contains("clip")) return make_error(where + ".clip: missing");
        Result<AnimationClip> clip = clip_from_json(c["clip"], where + ".clip");
        if (!clip) return clip.error();
        if (Status valid = validate_clip(*clip, registry.get<Lattice>(e).rest.size()); !valid)
            return make_error(where + ": " + valid.message());
        pending.push_back({e, std::move(*clip), playing, speed});
    }
    for (Pending& p : pending) {
        attach_clip(registry, p.lattice, std::move(p.clip), p.playing);
        registry.get<AnimationState>(p.lattice).speed = p.speed;
    }
    return {};
}

void register_animation_scene_hooks() {
    register_scene_extension(kKey, save_animation_extension, load_animation_extension);
    register_builtin_scene_hook(
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

void unregister_animation_scene_hooks() {
    unregister_scene_extension(kKey);
    unregister_builtin_scene_hook(kKey);
}

}  // namespace sffd
