// The web player tests' scene: the built-in sphere as 3D Gaussians (through the binary: convert
// --gaussians, then --lattice fit:4,4,4), with a global twist clip keyed in code as the built-in demo keys
// its own (systems/animation/paper_demo.cpp): every layer of control points along the lattice's T axis
// turns about the central axis, -60 degrees at the bottom to +60 at the top, linear 0 -> peak at 1 s -> 0
// at 2 s, looping.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include <glm/gtc/quaternion.hpp>
#include "runtime/scene/lattice.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/engine/engine_frame.h"
#include "tests/test_util/run_tool.h"

namespace sffd::test {

// Writes DIR/g.ply (no lattice), DIR/gs.glb (a lattice, no clip), DIR/twist.glb (the clip) and
// DIR/twist_bspline.glb (the same with a B-spline lattice) and DIR/twist_moved.glb (the lattice in the same
// place with a Transform of its own); returns an error text, empty on success.
inline std::string make_web_test_scenes(const std::filesystem::path& dir) {
    const std::string g = (dir / "g.ply").string(), gs = (dir / "gs.glb").string();
    if (auto r = run("convert sphere " + g + " --gaussians"); r.code != 0) return r.out;
    if (auto r = run("convert " + g + " " + gs + " --lattice fit:4,4,4"); r.code != 0) return r.out;
    ecs::Registry reg;
    use_engine_scene_hooks(reg);
    if (Status st = load_scene(reg, gs); !st) return st.message();
    int lattices = 0;
    reg.view<Lattice>().each([&](ecs::Entity e, Lattice& l) {
        if (lattices++) return;
        AnimationClip clip;
        clip.name = "twist";
        clip.duration = 2.0;
        const glm::ivec3 d = l.divisions;
        const glm::dvec3 centre = l.origin + 0.5 * (l.axes[0] + l.axes[1] + l.axes[2]);
        for (int j = 0; j <= d.y; ++j) {
            std::vector<std::uint32_t> pts;
            for (int i = 0; i <= d.x; ++i)
                for (int k = 0; k <= d.z; ++k) pts.push_back(std::uint32_t(l.index(i, j, k)));
            const std::size_t t = add_twist_track(clip, "layer " + std::to_string(j), pts, l.axes[1], centre);
            const double peak = (2.0 * j / d.y - 1.0) * 60.0;
            set_key(clip.tracks[t], {0.0, glm::dvec3(0.0), Interpolation::linear, Easing::none});
            set_key(clip.tracks[t], {1.0, glm::dvec3(peak, 0.0, 0.0), Interpolation::linear, Easing::none});
            set_key(clip.tracks[t], {2.0, glm::dvec3(0.0), Interpolation::linear, Easing::none});
        }
        reg.emplace<AnimationClip>(e, std::move(clip));
        reg.emplace<AnimationState>(e, AnimationState{});
    });
    if (lattices != 1) return gs + ": expected one lattice, found " + std::to_string(lattices);
    if (Status st = save_scene(reg, dir / "twist.glb"); !st) return st.message();
    // The same lattice in the same place in the world, but given its own Transform: the cloud's turned by
    // 30 degrees about y and moved, with box, points, twist axes and pivots mapped back by its inverse.
    {
        ecs::Registry moved;
        use_engine_scene_hooks(moved);
        if (Status st = load_scene(moved, (dir / "twist.glb").string()); !st) return st.message();
        const glm::dquat q = glm::angleAxis(glm::radians(30.0), glm::dvec3(0.0, 1.0, 0.0));
        const glm::dvec3 t(0.2, -0.1, 0.15);
        const glm::dquat qi = glm::inverse(q);
        auto back = [&](const glm::dvec3& p) { return qi * (p - t); };  // T^-1, T = translate(t) rotate(q)
        moved.view<Lattice, AnimationClip, Transform>().each(
            [&](Lattice& l, AnimationClip& c, Transform& tr) {
                l.origin = back(l.origin);
                for (glm::dvec3& a : l.axes) a = qi * a;
                for (glm::dvec3& p : l.rest) p = back(p);
                for (glm::dvec3& p : l.current) p = back(p);
                for (AnimationTrack& k : c.tracks) {
                    k.axis = qi * k.axis;
                    if (k.has_pivot) k.pivot = back(k.pivot);
                    for (Keyframe& key : k.keys)
                        if (k.kind == TrackKind::stretch) key.value = qi * key.value;
                }
                tr.translation = tr.translation + tr.rotation * (tr.scale * t);  // C T
                tr.rotation = tr.rotation * q;
            });
        if (Status st = save_scene(moved, dir / "twist_moved.glb"); !st) return st.message();
    }
    reg.view<Lattice>().each([](Lattice& l) { l.basis = LatticeBasis::bspline; });
    if (Status st = save_scene(reg, dir / "twist_bspline.glb"); !st) return st.message();
    return {};
}

// The control for the browser test: the twist scene's Gaussians deformed on the CPU at `clip_time`
// (the lattice posed and saved, then `convert` writes the cloud deformed by it as saved), given a fresh
// lattice and a clip that keys no motion (a twist of 0 degrees): the same picture as the twisted frame,
// drawn by the player without any deformation, through `camera` (the twist scene's: its own framing would
// follow the baked bounds). Writes DIR/baked.glb; returns an error text, or empty.
inline std::string make_web_baked_scene(const std::filesystem::path& dir, double clip_time,
                                        const Camera& camera) {
    {
        ecs::Registry reg;
        use_engine_scene_hooks(reg);
        if (Status st = load_scene(reg, (dir / "twist.glb").string()); !st) return st.message();
        std::vector<ecs::Entity> posed;
        reg.view<Lattice, const AnimationClip>().each([&](ecs::Entity e, Lattice& l, const AnimationClip& c) {
            l.current = evaluate_pose(c, l, map_clip_time(c, clip_time));
            posed.push_back(e);
        });
        if (posed.size() != 1) return "twist.glb: expected one animated lattice";
        reg.remove<AnimationClip>(posed[0]);
        reg.remove<AnimationState>(posed[0]);
        if (Status st = save_scene(reg, dir / "posed.glb"); !st) return st.message();
    }
    const std::string baked = (dir / "baked.ply").string(), fitted = (dir / "baked_fit.glb").string();
    if (auto r = run("convert " + (dir / "posed.glb").string() + " " + baked); r.code != 0) return r.out;
    if (auto r = run("convert " + baked + " " + fitted + " --lattice fit:4,4,4"); r.code != 0) return r.out;
    ecs::Registry reg;
    use_engine_scene_hooks(reg);
    if (Status st = load_scene(reg, fitted); !st) return st.message();
    int lattices = 0;
    reg.view<Lattice>().each([&](ecs::Entity e, Lattice& l) {
        if (lattices++) return;
        AnimationClip clip;
        clip.name = "still";
        clip.duration = 2.0;
        const std::size_t t = add_twist_track(clip, "none", {0u}, l.axes[1]);
        set_key(clip.tracks[t], {0.0, glm::dvec3(0.0), Interpolation::linear, Easing::none});
        set_key(clip.tracks[t], {1.0, glm::dvec3(0.0), Interpolation::linear, Easing::none});
        reg.emplace<AnimationClip>(e, std::move(clip));
        reg.emplace<AnimationState>(e, AnimationState{});
    });
    if (lattices != 1) return fitted + ": expected one lattice";
    bool has_camera = false;
    reg.view<Camera>().each([&](Camera& c) { c = camera, has_camera = true; });
    if (!has_camera) reg.emplace<Camera>(reg.create(), camera);
    if (Status st = save_scene(reg, dir / "baked.glb"); !st) return st.message();
    return {};
}

}  // namespace sffd::test
