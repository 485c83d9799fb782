// Pure evaluation: track values, interpolation modes, easing, twist turns, composition order, play modes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "tests/systems/animation/test_util.h"

namespace sffd {
namespace {

AnimationTrack track_with(Interpolation interp, Easing easing) {
    AnimationTrack t;
    const double times[] = {0.0, 0.4, 1.1, 1.5, 3.0};
    const glm::dvec3 values[] = {
        {0.0, 1.0, -2.0}, {0.3, -0.7, 5.0}, {-1.25, 2.0, 0.1}, {4.0, 0.0, 0.0}, {0.1, 0.2, 0.3}};
    for (int i = 0; i < 5; ++i) t.keys.push_back({times[i], values[i], interp, easing});
    return t;
}

const Interpolation all_interps[] = {Interpolation::step, Interpolation::linear, Interpolation::smooth};
const Easing all_easings[] = {Easing::none, Easing::ease_in, Easing::ease_out, Easing::ease_in_out};

TEST(AnimationEvaluate, ValuesAtKeysAreExact) {
    for (Interpolation interp : all_interps)
        for (Easing easing : all_easings) {
            const AnimationTrack t = track_with(interp, easing);
            for (const Keyframe& k : t.keys)
                EXPECT_TRUE(test::same_bits(evaluate_track(t, k.time), k.value))
                    << "interp " << int(interp) << " easing " << int(easing) << " t " << k.time;
        }
}

TEST(AnimationEvaluate, ClampsOutsideTheKeysAndEmptyTrackIsZero) {
    const AnimationTrack t = track_with(Interpolation::smooth, Easing::none);
    EXPECT_EQ(evaluate_track(t, -5.0), t.keys.front().value);
    EXPECT_EQ(evaluate_track(t, 99.0), t.keys.back().value);
    EXPECT_EQ(evaluate_track(AnimationTrack{}, 1.0), glm::dvec3(0.0));
}

TEST(AnimationEvaluate, StepHoldsTheLeftKey) {
    const AnimationTrack t = track_with(Interpolation::step, Easing::none);
    for (std::size_t i = 0; i + 1 < t.keys.size(); ++i)
        for (double f : {0.0, 0.25, 0.5, 0.999}) {
            const double time = t.keys[i].time + f * (t.keys[i + 1].time - t.keys[i].time);
            EXPECT_EQ(evaluate_track(t, time), t.keys[i].value);
        }
}

TEST(AnimationEvaluate, LinearAndEasingAgainstClosedForms) {
    AnimationTrack t;
    t.keys = {{1.0, glm::dvec3(2.0), Interpolation::linear, Easing::none},
              {3.0, glm::dvec3(6.0), Interpolation::linear, Easing::none}};
    EXPECT_DOUBLE_EQ(evaluate_track(t, 2.0).x, 4.0);
    EXPECT_DOUBLE_EQ(evaluate_track(t, 1.5).y, 3.0);
    t.keys[0].easing = Easing::ease_in;  // u^2: at u = 0.5 a quarter of the way
    EXPECT_DOUBLE_EQ(evaluate_track(t, 2.0).x, 3.0);
    t.keys[0].easing = Easing::ease_out;  // 1-(1-u)^2: at u = 0.5 three quarters
    EXPECT_DOUBLE_EQ(evaluate_track(t, 2.0).x, 5.0);
    t.keys[0].easing = Easing::ease_in_out;  // smoothstep(0.25) = 0.15625
    EXPECT_DOUBLE_EQ(evaluate_track(t, 1.5).z, 2.0 + 4.0 * 0.15625);
    EXPECT_DOUBLE_EQ(evaluate_track(t, 2.0).z, 4.0);
}

TEST(AnimationEvaluate, SmoothMatchesUniformCatmullRomOnInteriorSegments) {
    // Uniform keys: the documented tangents reduce to the textbook Catmull-Rom matrix form.
    AnimationTrack t;
    const double p[] = {0.0, 1.0, 3.0, -2.0, 0.5};
    for (int i = 0; i < 5; ++i)
        t.keys.push_back({0.5 * i, glm::dvec3(p[i], 2 * p[i], 0.0), Interpolation::smooth, Easing::none});
    for (int seg = 1; seg <= 2; ++seg)
        for (double u : {0.1, 0.3, 0.5, 0.77, 0.95}) {
            const double p0 = p[seg - 1], p1 = p[seg], p2 = p[seg + 1], p3 = p[seg + 2];
            const double ref = 0.5 * (2 * p1 + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u * u +
                                      (-p0 + 3 * p1 - 3 * p2 + p3) * u * u * u);
            const glm::dvec3 v = evaluate_track(t, 0.5 * (seg + u));
            EXPECT_NEAR(v.x, ref, 1e-12);
            EXPECT_NEAR(v.y, 2 * ref, 1e-12);
        }
    // End keys have zero tangent: the first segment leaves key 0 flat.
    const double h = 1e-6;
    EXPECT_NEAR((evaluate_track(t, h).x - p[0]) / h, 0.0, 1e-4);
}

// Dense sampling: no jump larger than a Lipschitz bound derived from the keys, for every mode except
// step (whose only jumps are at key times, tested above).
TEST(AnimationEvaluate, InterpolationIsContinuous) {
    for (Interpolation interp : {Interpolation::linear, Interpolation::smooth})
        for (Easing easing : all_easings) {
            const AnimationTrack t = track_with(interp, easing);
            double max_slope = 0.0;  // steepest secant between consecutive keys
            for (std::size_t i = 0; i + 1 < t.keys.size(); ++i)
                max_slope = std::max(max_slope, glm::length(t.keys[i + 1].value - t.keys[i].value) /
                                                    (t.keys[i + 1].time - t.keys[i].time));
            // Easing doubles the slope at most; Hermite with Catmull-Rom tangents stays within a few times
            // the steepest secant. A discontinuity of even 1e-3 would show as a slope of 1e3/dt.
            const double bound = 8.0 * max_slope;
            const double dt = 1e-4;
            glm::dvec3 prev = evaluate_track(t, -0.1);
            for (double time = -0.1 + dt; time <= 3.1; time += dt) {
                const glm::dvec3 v = evaluate_track(t, time);
                ASSERT_LE(glm::length(v - prev), bound * dt * 1.0001)
                    << "interp " << int(interp) << " easing " << int(easing) << " at t=" << time;
                prev = v;
            }
        }
}

TEST(AnimationEvaluate, StepJumpsAtKeysOnly) {
    const AnimationTrack t = track_with(Interpolation::step, Easing::none);
    const double eps = 1e-9;
    EXPECT_EQ(evaluate_track(t, 0.4 - eps), t.keys[0].value);
    EXPECT_EQ(evaluate_track(t, 0.4), t.keys[1].value);
}

TEST(AnimationEvaluate, TwistMatchesQuaternionRotation) {
    const glm::dvec3 axis = glm::normalize(glm::dvec3(1.0, 2.0, -0.5));
    const glm::dvec3 pivot(0.3, -1.0, 2.0), p(1.5, 0.25, -0.75);
    for (double deg : {-170.0, -30.0, 10.0, 45.0, 123.4, 300.0}) {
        const glm::dquat q = glm::angleAxis(deg * std::numbers::pi / 180.0, axis);
        const glm::dvec3 ref = pivot + q * (p - pivot);
        const glm::dvec3 got = twist_point(p, pivot, axis * 3.0, deg);  // axis length does not matter
        EXPECT_NEAR(glm::length(got - ref), 0.0, 1e-12) << deg;
    }
}

// A 720-degree twist: two full turns, unbounded angles, several turns between keys.
TEST(AnimationEvaluate, TwistOf720DegreesTurnsTwice) {
    Lattice lattice = test::make_lattice({1, 1, 1});
    AnimationClip clip;
    clip.duration = 2.0;
    // Point 4 is (1,-1,-1): twist it about z through an explicit pivot at the origin.
    const std::size_t ti = add_twist_track(clip, "spin", {4}, {0, 0, 1}, glm::dvec3(0.0));
    set_key(clip.tracks[ti], {0.0, {0, 0, 0}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[ti], {2.0, {720, 0, 0}, Interpolation::linear, Easing::none});
    const glm::dvec3 start = lattice.rest[4];
    ASSERT_EQ(start, glm::dvec3(1, -1, -1));
    auto at = [&](double time) { return evaluate_pose(clip, lattice, time)[4]; };
    EXPECT_TRUE(test::same_bits(at(1.0), start));  // 360: back at the start, bit for bit
    EXPECT_TRUE(test::same_bits(at(2.0), start));  // 720
    EXPECT_EQ(at(0.5), glm::dvec3(-1, 1, -1));     // 180: opposite
    EXPECT_EQ(at(1.5), glm::dvec3(-1, 1, -1));     // 540: opposite again
    EXPECT_EQ(at(0.25), glm::dvec3(1, 1, -1));     // 90
    // Other points are untouched.
    EXPECT_EQ(evaluate_pose(clip, lattice, 0.3)[0], lattice.rest[0]);

    // With an intermediate key (0 -> 300 -> 720, smooth) the angle keeps increasing through two turns:
    // follow the point and unwrap its polar angle; it must track the key curve, not the shortest path.
    AnimationTrack& track = clip.tracks[ti];
    track.keys.clear();
    set_key(track, {0.0, {0, 0, 0}, Interpolation::smooth, Easing::none});
    set_key(track, {0.8, {300, 0, 0}, Interpolation::smooth, Easing::none});
    set_key(track, {2.0, {720, 0, 0}, Interpolation::smooth, Easing::none});
    double unwrapped = std::atan2(start.y, start.x), prev_angle = evaluate_track(track, 0.0).x;
    const double start_polar = unwrapped;
    for (double time = 0.005; time <= 2.0 + 1e-12; time += 0.005) {
        const double angle = evaluate_track(track, time).x;
        EXPECT_GE(angle, prev_angle - 1e-9) << "angle decreased at t=" << time;
        prev_angle = angle;
        const glm::dvec3 q = at(time);
        double polar = std::atan2(q.y, q.x);
        while (polar - unwrapped > std::numbers::pi) polar -= 2 * std::numbers::pi;
        while (polar - unwrapped < -std::numbers::pi) polar += 2 * std::numbers::pi;
        unwrapped = polar;
        EXPECT_NEAR((unwrapped - start_polar) * 180.0 / std::numbers::pi, angle, 1e-9) << time;
    }
    EXPECT_NEAR((unwrapped - start_polar) * 180.0 / std::numbers::pi, 720.0, 1e-9);
    EXPECT_TRUE(test::same_bits(at(2.0), start));
}

// Tracks compose in track order on the running positions; the default twist pivot is the centroid of
// the bound REST points (not of the stretched ones).
TEST(AnimationEvaluate, TracksComposeInTrackOrder) {
    Lattice lattice = test::make_lattice({1, 1, 1});
    const glm::dvec3 v(0.5, 0.0, 0.25);
    auto make = [&](bool stretch_first) {
        AnimationClip clip;
        clip.duration = 1.0;
        auto add_stretch = [&] {
            const std::size_t s = add_stretch_track(clip, "s", {4, 5, 6});
            set_key(clip.tracks[s], {0.0, v, Interpolation::step, Easing::none});
        };
        auto add_twist = [&] {
            const std::size_t t = add_twist_track(clip, "t", {5, 6, 7}, {0, 0, 1});  // default pivot
            set_key(clip.tracks[t], {0.0, {90, 0, 0}, Interpolation::step, Easing::none});
        };
        if (stretch_first) {
            add_stretch();
            add_twist();
        } else {
            add_twist();
            add_stretch();
        }
        return clip;
    };
    // Rest points 4..7: (1,-1,-1) (1,-1,1) (1,1,-1) (1,1,1); twist pivot = centroid of 5,6,7 at rest.
    const glm::dvec3 pivot = (lattice.rest[5] + lattice.rest[6] + lattice.rest[7]) / 3.0;
    auto rot = [&](const glm::dvec3& p) {  // 90 degrees about z through pivot, independent formula
        const glm::dvec3 d = p - pivot;
        return pivot + glm::dvec3(-d.y, d.x, d.z);
    };
    const std::vector<glm::dvec3> a = evaluate_pose(make(true), lattice, 0.5);
    const std::vector<glm::dvec3> b = evaluate_pose(make(false), lattice, 0.5);
    const auto& r = lattice.rest;
    const double tol = 1e-14;
    // stretch then twist
    EXPECT_NEAR(glm::length(a[4] - (r[4] + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(a[5] - rot(r[5] + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(a[6] - rot(r[6] + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(a[7] - rot(r[7])), 0.0, tol);
    // twist then stretch
    EXPECT_NEAR(glm::length(b[4] - (r[4] + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(b[5] - (rot(r[5]) + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(b[6] - (rot(r[6]) + v)), 0.0, tol);
    EXPECT_NEAR(glm::length(b[7] - rot(r[7])), 0.0, tol);
    EXPECT_GT(glm::length(a[5] - b[5]), 0.1);  // the order matters
    for (int i = 0; i < 4; ++i) {              // unbound points stay at rest
        EXPECT_EQ(a[std::size_t(i)], r[std::size_t(i)]);
        EXPECT_EQ(b[std::size_t(i)], r[std::size_t(i)]);
    }
}

TEST(AnimationEvaluate, PoseIsRebuiltFromRestEveryTime) {
    Lattice lattice = test::make_lattice({2, 2, 2});
    AnimationClip clip;
    clip.duration = 1.0;
    const std::size_t s = add_stretch_track(clip, "s", {13});
    set_key(clip.tracks[s], {0.0, {0, 0, 0}, Interpolation::smooth, Easing::none});
    set_key(clip.tracks[s], {1.0, {1, 2, 3}, Interpolation::smooth, Easing::none});
    lattice.current[13] = glm::dvec3(100.0);  // whatever is in current does not matter
    const auto first = evaluate_pose(clip, lattice, 0.37);
    for (double time : {0.1, 0.9, 0.37, 0.5}) (void)evaluate_pose(clip, lattice, time);
    EXPECT_EQ(evaluate_pose(clip, lattice, 0.37), first);
    EXPECT_EQ(evaluate_pose(clip, lattice, 0.0), lattice.rest);
}

TEST(AnimationEvaluate, PlayModesMapTime) {
    AnimationClip clip;
    clip.duration = 2.0;
    clip.mode = PlayMode::loop;
    EXPECT_EQ(map_clip_time(clip, 0.5), 0.5);
    EXPECT_EQ(map_clip_time(clip, 2.0), 0.0);
    EXPECT_EQ(map_clip_time(clip, 4.5), 0.5);
    EXPECT_EQ(map_clip_time(clip, -0.5), 1.5);
    clip.mode = PlayMode::once;
    EXPECT_EQ(map_clip_time(clip, 0.5), 0.5);
    EXPECT_EQ(map_clip_time(clip, 7.0), 2.0);
    EXPECT_EQ(map_clip_time(clip, -1.0), 0.0);
    clip.mode = PlayMode::ping_pong;
    EXPECT_EQ(map_clip_time(clip, 0.5), 0.5);
    EXPECT_EQ(map_clip_time(clip, 2.0), 2.0);
    EXPECT_EQ(map_clip_time(clip, 2.5), 1.5);
    EXPECT_EQ(map_clip_time(clip, 3.75), 0.25);
    EXPECT_EQ(map_clip_time(clip, 4.5), 0.5);
    EXPECT_EQ(map_clip_time(clip, -0.5), 0.5);
}

TEST(AnimationEvaluate, SpeedScalesClockTime) {
    AnimationClip clip;
    clip.duration = 10.0;
    clip.speed = 2.0;
    AnimationState state;
    EXPECT_EQ(clip_raw_time(clip, state, 1.5), 3.0);
    state.speed = -0.5;  // backwards at half speed (times the clip's 2x)
    EXPECT_EQ(clip_raw_time(clip, state, 1.5), -1.5);
    EXPECT_EQ(map_clip_time(clip, clip_raw_time(clip, state, 1.5)), 8.5);
    state.playing = false;
    state.anchor_time = 4.0;
    EXPECT_EQ(clip_raw_time(clip, state, 123.0), 4.0);
}

TEST(AnimationEvaluate, ValidateReportsProblems) {
    AnimationClip clip;
    clip.name = "c";
    clip.duration = 1.0;
    EXPECT_TRUE(validate_clip(clip, 8).ok());
    add_stretch_track(clip, "s", {3, 8});
    Status s = validate_clip(clip, 8);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message(), "clip 'c': tracks[0]: control point 8 out of range (lattice has 8)");
    clip.tracks[0].points = {3};
    clip.tracks[0].keys = {{0.5, {}, Interpolation::linear, Easing::none},
                           {0.5, {}, Interpolation::linear, Easing::none}};
    s = validate_clip(clip, 8);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message(), "clip 'c': tracks[0].keys[1]: times not increasing");
    clip.tracks[0].keys.pop_back();
    add_twist_track(clip, "t", {1}, glm::dvec3(0.0));
    s = validate_clip(clip, 8);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message(), "clip 'c': tracks[1]: twist axis must be finite and non-zero");
    clip.tracks[1].axis = {0, 1, 0};
    clip.duration = 0.0;
    EXPECT_FALSE(validate_clip(clip, 8).ok());
}

}  // namespace
}  // namespace sffd
