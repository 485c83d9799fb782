// Clips in scene files (exact round trip through .glb and .gltf) and the demo clip on built-in scenes.
#include <gtest/gtest.h>

#include <filesystem>

#include "runtime/assets/scene.h"
#include "systems/animation/clip_io.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "systems/animation/scene_extension.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/ffd/components.h"

namespace sffd {
namespace {

ecs::Entity only_lattice(ecs::Registry& reg) {
    ecs::Entity found = ecs::null_entity;
    std::size_t n = 0;
    reg.view<Lattice>().each([&](ecs::Entity e, Lattice&) {
        found = e;
        ++n;
    });
    EXPECT_EQ(n, 1u);
    return found;
}

TEST(AnimationScene, BuiltinSphereGetsThePaperDemoClip) {
    ecs::Registry reg;
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, "sphere").ok());
    const ecs::Entity e = only_lattice(reg);
    ASSERT_TRUE(reg.has<AnimationClip>(e));
    ASSERT_TRUE(reg.has<AnimationState>(e));
    EXPECT_EQ(reg.get<Lattice>(e).divisions, glm::ivec3(10));
    EXPECT_EQ(clip_to_string(reg.get<AnimationClip>(e)),
              clip_to_string(make_paper_demo_clip(reg.get<Lattice>(e))));
    EXPECT_TRUE(reg.get<AnimationState>(e).playing);
}

TEST(AnimationScene, WithoutHooksBuiltinsHaveNoClip) {
    ecs::Registry reg;
    reg.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(reg, "sphere").ok());
    EXPECT_EQ(reg.count<AnimationClip>(), 0u);
}

TEST(AnimationScene, ClipsRoundTripThroughSceneFilesExactly) {
    for (const char* ext : {".glb", ".gltf"}) {
        ecs::Registry reg;
        register_animation_scene_hooks(SceneHooks::in(reg));
        ASSERT_TRUE(load_scene(reg, "sphere").ok());
        const ecs::Entity e = only_lattice(reg);
        // Make the clip awkward: an extra twist with many digits, a paused state at another speed.
        AnimationClip& clip = reg.patch<AnimationClip>(e);
        const std::size_t t =
            add_twist_track(clip, "extra", {5, 6, 7}, {1.0 / 3.0, 0.1, -7.25}, glm::dvec3(0.1, 1e-300, -0.0));
        set_key(clip.tracks[t], {0.1, {720.0 + 1.0 / 7.0, 0, 0}, Interpolation::smooth, Easing::ease_out});
        set_key(clip.tracks[t], {2.0 / 3.0, {-1e-12, 0, 0}, Interpolation::step, Easing::none});
        clip.mode = PlayMode::ping_pong;
        clip.speed = 0.3;
        pause(reg.patch<AnimationState>(e));
        reg.patch<AnimationState>(e).speed = 1.7;
        const std::string before = clip_to_string(clip);

        const auto path =
            std::filesystem::path(SFFD_BINARY_DIR) / (std::string("animation_scene_test") + ext);
        Status saved = save_scene(reg, path);
        ASSERT_TRUE(saved.ok()) << saved.message();
        ecs::Registry back;
        register_animation_scene_hooks(SceneHooks::in(back));
        Status loaded = load_scene(back, path.string());
        ASSERT_TRUE(loaded.ok()) << loaded.message();
        const ecs::Entity b = only_lattice(back);
        ASSERT_TRUE(back.has<AnimationClip>(b)) << ext;
        EXPECT_EQ(clip_to_string(back.get<AnimationClip>(b)), before) << ext;
        const AnimationClip& c = back.get<AnimationClip>(b);
        const AnimationTrack& x = c.tracks.back();
        EXPECT_EQ(x.keys[0].value.x, 720.0 + 1.0 / 7.0);
        EXPECT_EQ(x.keys[1].time, 2.0 / 3.0);
        EXPECT_EQ(x.axis.x, 1.0 / 3.0);
        EXPECT_TRUE(std::signbit(x.pivot.z));
        // The pause was the editor's view state: the saved scene plays wherever it is loaded.
        EXPECT_TRUE(back.get<AnimationState>(b).playing);
        EXPECT_EQ(back.get<AnimationState>(b).speed, 1.7);
        std::filesystem::remove(path);
    }
}

// An un-keyed edit is saved with its clip time and loads as the same UnkeyedEdit, the lattice's control
// points as they were shown; a file of an older version (no "time") with control points off the clip's
// pose at 0 s loads them as an edit at 0 s, which is when its editor showed them.
TEST(AnimationScene, UnkeyedEditsRoundTripWithTheirClipTime) {
    ecs::Registry reg;
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, "sphere").ok());
    const ecs::Entity e = only_lattice(reg);
    pause(reg.patch<AnimationState>(e));
    reg.patch<AnimationState>(e).time = 0.5;  // the editor's timeline stood there
    const std::vector<glm::dvec3> pose = evaluate_pose(reg.get<AnimationClip>(e), reg.get<Lattice>(e), 0.5);
    std::vector<glm::dvec3> edited = pose;
    edited[600] += glm::dvec3(0.0, 1.0 / 3.0, 0.0);
    reg.patch<Lattice>(e).current = edited;
    const auto path = std::filesystem::path(SFFD_BINARY_DIR) / "animation_scene_unkeyed.glb";
    ASSERT_TRUE(save_scene(reg, path).ok());

    ecs::Registry back;
    register_animation_scene_hooks(SceneHooks::in(back));
    ASSERT_TRUE(load_scene(back, path.string()).ok());
    const ecs::Entity b = only_lattice(back);
    ASSERT_TRUE(back.has<UnkeyedEdit>(b));
    EXPECT_EQ(back.get<UnkeyedEdit>(b).time, 0.5);
    EXPECT_EQ(back.get<UnkeyedEdit>(b).points, edited);
    EXPECT_EQ(back.get<Lattice>(b).current, edited);
    EXPECT_EQ(back.get<AnimationState>(b).time, 0.5) << "loaded at the time it was saved at";
    EXPECT_TRUE(back.get<AnimationState>(b).playing) << "and still plays from 0 s";
    const auto reports = unkeyed_edits(back);
    ASSERT_EQ(reports.size(), 1u);
    EXPECT_EQ(reports[0].points, 1u);
    EXPECT_EQ(reports[0].name, "'sphere.lattice'");

    // Saved again at another time (scrubbed away): the edit keeps its own time and points.
    back.patch<AnimationState>(b).time = 1.0;
    back.patch<Lattice>(b).current = evaluate_pose(back.get<AnimationClip>(b), back.get<Lattice>(b), 1.0);
    ASSERT_TRUE(save_scene(back, path).ok());
    ecs::Registry again;
    register_animation_scene_hooks(SceneHooks::in(again));
    ASSERT_TRUE(load_scene(again, path.string()).ok());
    const ecs::Entity a = only_lattice(again);
    ASSERT_TRUE(again.has<UnkeyedEdit>(a));
    EXPECT_EQ(again.get<UnkeyedEdit>(a).time, 0.5);
    EXPECT_EQ(again.get<UnkeyedEdit>(a).points, edited);
    EXPECT_EQ(again.get<AnimationState>(a).time, 1.0);
    std::filesystem::remove(path);

    // An older file: no "time", control points off the clip's pose at 0 s.
    ecs::Registry old;
    const ecs::Entity lat = old.create();
    Lattice l = reg.get<Lattice>(e);
    l.current = l.rest;
    l.current[3] += glm::dvec3(0.25, 0.0, 0.0);
    old.emplace<Lattice>(lat, l);
    AnimationClip clip = reg.get<AnimationClip>(e);
    const std::string text =
        "{\"version\": 1, \"clips\": [{\"lattice\": 0, \"clip\": " + clip_to_string(clip) + "}]}";
    ASSERT_TRUE(
        load_animation_extension(old, text, [&](int id) { return id == 0 ? lat : ecs::null_entity; }).ok());
    ASSERT_TRUE(old.has<UnkeyedEdit>(lat));
    EXPECT_EQ(old.get<UnkeyedEdit>(lat).time, 0.0);
    EXPECT_EQ(old.get<UnkeyedEdit>(lat).points, l.current);
}

TEST(AnimationScene, BadExtensionDataIsRefused) {
    ecs::Registry reg;
    const ecs::Entity lat = reg.create();
    Lattice l;
    l.divisions = {1, 1, 1};
    l.rest.assign(8, glm::dvec3(0.0));
    l.current = l.rest;
    reg.emplace<Lattice>(lat, l);
    const ecs::Entity other = reg.create();
    auto entity_of = [&](int id) { return id == 0 ? lat : id == 1 ? other : ecs::null_entity; };
    auto load = [&](const std::string& text) {
        Status s = load_animation_extension(reg, text, entity_of);
        return s.ok() ? std::string("ok") : s.message();
    };
    EXPECT_EQ(load(R"({"version": 1, "clips": [{"lattice": 1, "clip": {"duration": 1}}]})"),
              "clips[0].lattice: 1 is not a lattice of this scene");
    EXPECT_EQ(load(R"({"version": 2, "clips": []})"), "'version' must be 1");
    EXPECT_EQ(load(R"({"version": 1, "clips": [{"lattice": 0, "clip": {"duration": -1}}]})"),
              "clips[0].clip: duration: must be > 0");
    EXPECT_EQ(load(R"({"version": 1, "clips": [{"lattice": 0, "clip": {"duration": 1,
                 "tracks": [{"kind": "stretch", "points": [8]}]}}]})"),
              "clips[0]: clip '': tracks[0]: control point 8 out of range (lattice has 8)");
    EXPECT_EQ(reg.count<AnimationClip>(), 0u);  // nothing attached on failure
    EXPECT_EQ(load(R"({"version": 1, "clips": [{"lattice": 0, "playing": 1, "clip": {"duration": 1}}]})"),
              "clips[0].playing: expected true or false");
    // A file saved while the editor was paused (older versions wrote the pause) still animates.
    EXPECT_EQ(load(R"({"version": 1, "clips": [{"lattice": 0, "playing": false, "clip": {"duration": 1}}]})"),
              "ok");
    EXPECT_TRUE(reg.has<AnimationClip>(lat));
    EXPECT_TRUE(reg.get<AnimationState>(lat).playing);
}

}  // namespace
}  // namespace sffd
