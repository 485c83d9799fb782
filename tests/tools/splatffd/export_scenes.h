// Scenes the export tests make: one saved at a frame's clip time (what the editor saves there), and a small
// Gaussian scene with the paper demo clip, made through the binary and the scene library.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/app/clock.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "systems/engine/engine_frame.h"
#include "tests/test_util/run_tool.h"

namespace sffd::test::export_scenes {

namespace fs = std::filesystem;

inline CliRun tool(const std::string& args) { return run_headless(args); }

constexpr double kFps = 24.0;

// `in` loaded, every lattice posed by its clip at the clip time of frame `frame` (render's clock time
// for the frame, then evaluate.h directly, not the animation system export runs), saved as `out`: the scene a
// user saves in the editor at that time. `demo_clip`: lattices without a clip get the paper demo clip first;
// `empty_clip`: a clip without keys.
inline void save_at_frame(const std::string& in, const fs::path& out, long frame, bool demo_clip = false,
                          bool empty_clip = false) {
    sffd::ecs::Registry r;
    sffd::use_engine_scene_hooks(r);
    ASSERT_TRUE(sffd::load_scene(r, in)) << in;
    std::vector<sffd::ecs::Entity> lattices;
    r.each_entity([&](sffd::ecs::Entity e) {
        if (r.has<sffd::Lattice>(e)) lattices.push_back(e);
    });
    for (sffd::ecs::Entity e : lattices) {
        if (empty_clip) {
            sffd::AnimationClip c;
            c.name = "empty";
            c.duration = 2.0;
            sffd::attach_clip(r, e, c);
        } else if (demo_clip && !r.has<sffd::AnimationClip>(e)) {
            sffd::attach_clip(r, e, sffd::make_paper_demo_clip(r.get<sffd::Lattice>(e)));
        }
        if (!r.has<sffd::AnimationClip>(e)) continue;
        const sffd::AnimationClip& clip = r.get<sffd::AnimationClip>(e);
        sffd::Clock clock(sffd::ClockSettings{.fixed_dt = 1.0 / kFps});
        clock.seek(double(frame) / kFps);
        const double clock_time = clock.tick().time;
        const double t =
            sffd::map_clip_time(clip, sffd::clip_raw_time(clip, r.get<sffd::AnimationState>(e), clock_time));
        r.patch<sffd::Lattice>(e).current = sffd::evaluate_pose(clip, r.get<sffd::Lattice>(e), t);
        r.patch<sffd::AnimationState>(e).time = t;
    }
    ASSERT_TRUE(sffd::save_scene(r, out)) << out;
}

// A small Gaussian scene with the paper demo clip: the sphere as 6000 Gaussians in a fitted 10^3 lattice.
inline fs::path gaussian_scene(const fs::path& dir) {
    const fs::path g = dir / "g.ply", fitted = dir / "g_fit.glb", scene = dir / "g_clip.glb";
    if (fs::exists(scene)) return scene;
    CliRun r = tool("convert sphere " + g.string() + " --gaussians --splats 6000");
    EXPECT_EQ(r.code, 0) << r.out;
    r = tool("convert " + g.string() + " " + fitted.string() + " --lattice fit");
    EXPECT_EQ(r.code, 0) << r.out;
    save_at_frame(fitted.string(), scene, 0, true);
    return scene;
}

}  // namespace sffd::test::export_scenes
