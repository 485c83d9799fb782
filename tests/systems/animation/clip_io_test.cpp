// Clip storage: exact round trip (bit for bit) and clear errors on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <nlohmann/json.hpp>

#include "systems/animation/clip_io.h"
#include "systems/animation/editing.h"
#include "systems/animation/paper_demo.h"
#include "tests/systems/animation/test_util.h"

namespace sffd {
namespace {

void expect_same(const AnimationClip& a, const AnimationClip& b) {
    EXPECT_EQ(a.name, b.name);
    EXPECT_TRUE(std::memcmp(&a.duration, &b.duration, sizeof(double)) == 0);
    EXPECT_TRUE(std::memcmp(&a.speed, &b.speed, sizeof(double)) == 0);
    EXPECT_EQ(a.mode, b.mode);
    ASSERT_EQ(a.tracks.size(), b.tracks.size());
    for (std::size_t t = 0; t < a.tracks.size(); ++t) {
        const AnimationTrack &x = a.tracks[t], &y = b.tracks[t];
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.kind, y.kind);
        EXPECT_EQ(x.points, y.points);
        EXPECT_EQ(x.has_pivot, y.has_pivot);
        if (x.kind == TrackKind::twist) {
            EXPECT_TRUE(test::same_bits(x.axis, y.axis));
            if (x.has_pivot) {
                EXPECT_TRUE(test::same_bits(x.pivot, y.pivot));
            }
        }
        ASSERT_EQ(x.keys.size(), y.keys.size());
        for (std::size_t k = 0; k < x.keys.size(); ++k) {
            EXPECT_TRUE(std::memcmp(&x.keys[k].time, &y.keys[k].time, sizeof(double)) == 0) << t << "/" << k;
            EXPECT_TRUE(test::same_bits(x.keys[k].value, y.keys[k].value)) << t << "/" << k;
            EXPECT_EQ(x.keys[k].interpolation, y.keys[k].interpolation);
            EXPECT_EQ(x.keys[k].easing, y.keys[k].easing);
        }
    }
}

AnimationClip awkward_clip() {
    AnimationClip clip;
    clip.name = "awkward \"quoted\" ünïcode";
    clip.duration = 1.0 / 3.0;
    clip.mode = PlayMode::ping_pong;
    clip.speed = -0.1;
    const std::size_t s = add_stretch_track(clip, "s", {0, 7, 4000000000u});
    set_key(clip.tracks[s], {0.0, {0.1, -1e-310, 6.02214076e23}, Interpolation::step, Easing::ease_in});
    set_key(
        clip.tracks[s],
        {std::nextafter(0.1, 1.0), {std::numbers::pi, -0.0, 1e-17}, Interpolation::smooth, Easing::ease_out});
    set_key(clip.tracks[s],
            {0.3,
             {std::numeric_limits<double>::max(), std::numeric_limits<double>::denorm_min(), 2.0 / 3.0},
             Interpolation::linear,
             Easing::ease_in_out});
    const std::size_t t = add_twist_track(clip, "t", {3}, {1.0 / 7.0, 0.0, -2.5}, glm::dvec3(0.1, 0.2, 0.3));
    set_key(clip.tracks[t], {0.0, {720.0, 0, 0}, Interpolation::smooth, Easing::none});
    set_key(clip.tracks[t], {0.25, {-1e3 / 3.0, 0, 0}, Interpolation::linear, Easing::none});
    add_twist_track(clip, "no keys, default pivot", {1, 2}, {0, 0, 1});
    return clip;
}

TEST(AnimationClipIo, RoundTripIsExact) {
    const AnimationClip clip = awkward_clip();
    const std::string text = clip_to_string(clip);
    Result<AnimationClip> back = parse_clip(text, "mem");
    ASSERT_TRUE(back.ok()) << back.message();
    expect_same(clip, *back);
    EXPECT_EQ(clip_to_string(*back), text);  // and the text is stable
}

TEST(AnimationClipIo, PaperDemoRoundTripsThroughAFile) {
    const Lattice lattice =
        test::make_lattice({10, 10, 10}, glm::dvec3(-0.7, -0.3, 0.1), glm::dvec3(1.4, 1.1, 0.9));
    const AnimationClip clip = make_paper_demo_clip(lattice);
    const std::filesystem::path path = std::filesystem::path(SFFD_BINARY_DIR) / "animation_clip_io_test.json";
    ASSERT_TRUE(save_clip(clip, path).ok());
    Result<AnimationClip> back = load_clip(path);
    ASSERT_TRUE(back.ok()) << back.message();
    expect_same(clip, *back);
    std::filesystem::remove(path);
}

TEST(AnimationClipIo, BadInputNamesTheSourceAndTheProblem) {
    auto error = [](const std::string& text) {
        Result<AnimationClip> r = parse_clip(text, "scene.gltf");
        return r.ok() ? std::string("ok") : r.message();
    };
    EXPECT_EQ(error("{").rfind("scene.gltf: not valid JSON (", 0), 0u) << error("{");
    EXPECT_EQ(error("[]"), "scene.gltf: clip: expected an object");
    EXPECT_EQ(error("{}"), "scene.gltf: duration: missing");
    EXPECT_EQ(error(R"({"duration": "x"})"), "scene.gltf: duration: expected a number");
    EXPECT_EQ(error(R"({"duration": 0})"), "scene.gltf: duration: must be > 0");
    EXPECT_EQ(error(R"({"duration": 1, "mode": "sideways"})"),
              "scene.gltf: clip.mode: unknown value 'sideways' (expected loop, once, ping_pong)");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "bend"}]})"),
              "scene.gltf: tracks[0].kind: unknown value 'bend' (expected stretch, twist)");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "stretch", "points": [1, -2]}]})"),
              "scene.gltf: tracks[0].points[1]: expected a control-point index");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "twist", "points": [1]}]})"),
              "scene.gltf: tracks[0].axis: missing (twist tracks need an axis)");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "twist", "axis": [0, 0, 0]}]})"),
              "scene.gltf: tracks[0].axis: must be non-zero");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "twist", "axis": [0, 1]}]})"),
              "scene.gltf: tracks[0].axis: expected an array of 3 numbers");
    EXPECT_EQ(
        error(R"({"duration": 1, "tracks": [{"kind": "stretch", "keys": [{"time": 1, "value": [0, 0, 0]},
                                                                          {"time": 0.5, "value": [0, 0, 0]}]}]})"),
        "scene.gltf: tracks[0].keys[1].time: key times must be strictly increasing");
    EXPECT_EQ(
        error(
            R"({"duration": 1, "tracks": [{"kind": "stretch", "keys": [{"time": 1, "value": [0, null, 0]}]}]})"),
        "scene.gltf: tracks[0].keys[0].value[1]: expected a number");
    EXPECT_EQ(
        error(R"({"duration": 1, "tracks": [{"kind": "twist", "axis": [0,0,1], "keys": [{"time": 1}]}]})"),
        "scene.gltf: tracks[0].keys[0].angle: missing");
    EXPECT_EQ(error(R"({"duration": 1, "tracks": [{"kind": "stretch", "keys": [{"time": 1, "value": [0,0,0],
                                                                             "easing": "bouncy"}]}]})"),
              "scene.gltf: tracks[0].keys[0].easing: unknown value 'bouncy' (expected none, ease_in, "
              "ease_out, ease_in_out)");
    EXPECT_EQ(error(R"({"duration": 1e999})").rfind("scene.gltf: not valid JSON (", 0), 0u);  // overflow
}

TEST(AnimationClipIo, MissingFileIsAnError) {
    Result<AnimationClip> r = load_clip("/nonexistent/dir/clip.json");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message().rfind("/nonexistent/dir/clip.json: cannot open", 0), 0u) << r.message();
}

}  // namespace
}  // namespace sffd
