// Proportional editing of lattice control points, driven by replay files through the editor's input
// system (the code `splatffd view --replay` drives): each falloff's neighbour positions against Blender's
// formulas written out here, the wheel and PageUp/PageDown sizing the radius mid-drag, pins, twist and
// scale, one undo step per edit, the overlay's radius circle, and the replay commands' errors.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/input_record.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_system.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

// Blender's proportional weights (transform_generics.c, calculatePropRatio), with u = 1 - d / r.
double blender_weight(const std::string& falloff, double d, double r) {
    if (d > r) return 0.0;
    const double u = 1.0 - d / r;
    if (falloff == "smooth") return 3.0 * u * u - 2.0 * u * u * u;
    if (falloff == "sphere") return std::sqrt(2.0 * u - u * u);
    if (falloff == "linear") return u;
    if (falloff == "sharp") return u * u;
    if (falloff == "constant") return 1.0;
    ADD_FAILURE() << falloff;
    return 0.0;
}

struct Scene {
    ecs::Registry reg;
    ecs::Entity lattice;
    EditorState* state = nullptr;
    std::uint64_t frame = 0;

    // A lattice of 4x4x4 cells over [-1,1]^3 (control points 0.5 apart) and a small sphere of splats at
    // its centre; the camera looks at the front face (z = 1) from +z.
    Scene() {
        lattice = reg.create();
        reg.emplace<Lattice>(
            lattice,
            make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                         {4, 4, 4}));
        const ecs::Entity cloud = reg.create();
        SplatCloud& c = reg.emplace<SplatCloud>(cloud);
        for (int a = 0; a < 24; ++a)
            for (int b = 0; b < 12; ++b) {
                const double th = a * 2 * std::numbers::pi / 24, ph = (b + 0.5) * std::numbers::pi / 12;
                const glm::vec3 n(std::sin(ph) * std::cos(th), std::cos(ph), std::sin(ph) * std::sin(th));
                c.positions.push_back(0.1f * n);
                c.normals.push_back(n);
                const glm::vec3 u = glm::normalize(
                    glm::cross(n, std::abs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
                c.axis_u.push_back(0.03f * u);
                c.axis_v.push_back(0.03f * glm::cross(n, u));
            }
        const ecs::Entity cam = reg.create();
        Camera& camera = reg.emplace<Camera>(cam);
        camera.eye = {1.0, 1.4, 6.0};
        camera.target = {0, 0, 0};
        state = &setup_editor(reg, Viewport{800, 600});
    }
    const Lattice& lat() { return reg.get<Lattice>(lattice); }
    std::uint32_t idx(int i, int j, int k) { return std::uint32_t(lat().index(i, j, k)); }
    std::string pixel(std::uint32_t point) {
        const glm::dvec3 p =
            project_to_pixel(reg.get<Camera>(state->camera), state->viewport, lat().current[point]);
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.17g %.17g", p.x, p.y);
        return buf;
    }
    // One frame of the engine's editor steps: input, then the picking phase.
    void frame_once() {
        const FrameContext f{frame, frame / 60.0, 1 / 60.0};
        editor_input_system(reg, f);
        picking::picking_system(reg, f);
        editor_pick_system(reg, f);
        ++frame;
    }
    // Replays a recording whose frames count from the scene's current frame, until every event ran.
    void replay(const std::string& text) {
        auto events = parse_input_recording(text, "test.txt");
        ASSERT_TRUE(events) << events.message();
        for (InputEvent& e : *events) e.frame += frame;
        state->replay = InputReplayer(std::move(*events));
        while (!state->replay->finished() || !state->deferred.empty()) frame_once();
        frame_once();
    }
};

// The world distance from each control point to the nearest of `selected` (no Transform: lattice space).
double distance_to(const std::vector<glm::dvec3>& points, std::size_t c,
                   const std::vector<std::uint32_t>& selected) {
    double best = 1e300;
    for (std::uint32_t s : selected) best = std::min(best, glm::length(points[c] - points[s]));
    return best;
}

constexpr const char* falloffs[] = {"smooth", "sphere", "linear", "sharp", "constant"};

// Unpins, selects the front face's centre point by a click, turns proportional editing on.
std::string select_front_centre(Scene& s, const std::string& falloff, double radius) {
    return "0 key p\n0 move " + s.pixel(s.idx(2, 2, 4)) + "\n0 press left\n0 release left\n" +
           "1 set proportional.enabled 1\n1 set proportional.radius " + std::to_string(radius) +
           "\n1 set proportional.falloff " + falloff + "\n";
}

}  // namespace

// `g x 0.3 Enter` with each falloff: every control point moves by blender_weight(d / r) * 0.3 along x.
TEST(Proportional, TypedMoveMovesNeighboursByEachFalloff) {
    for (const char* falloff : falloffs) {
        SCOPED_TRACE(falloff);
        Scene s;
        const double r = 0.8;
        s.replay(select_front_centre(s, falloff, r));
        const std::uint32_t centre = s.idx(2, 2, 4);
        ASSERT_EQ(s.reg.get<picking::LatticeSelection>(s.lattice).indices,
                  std::vector<std::uint32_t>{centre});
        ASSERT_TRUE(s.state->proportional.enabled);
        const std::vector<glm::dvec3> rest = s.lat().current;
        const std::size_t steps = s.state->undo.size();
        s.replay("0 key g\n0 key x\n0 key 0\n0 key period\n0 key 3\n0 key enter\n");
        const std::vector<glm::dvec3>& now = s.lat().current;
        std::size_t moved = 0;
        for (std::size_t c = 0; c < rest.size(); ++c) {
            const double w = blender_weight(falloff, distance_to(rest, c, {centre}), r);
            EXPECT_NEAR(now[c].x, rest[c].x + w * 0.3, 1e-12) << c;
            EXPECT_EQ(now[c].y, rest[c].y) << c;
            EXPECT_EQ(now[c].z, rest[c].z) << c;
            moved += now[c] != rest[c];
        }
        // d = 0.5 (4 points in the face, 1 behind) and 0.707 (4 in the face, 4 behind) are inside 0.8.
        EXPECT_EQ(moved, 14u);
        EXPECT_EQ(s.state->undo.size(), steps + 1) << "one undo step";
        s.replay("0 key z ctrl\n");
        EXPECT_EQ(std::memcmp(s.lat().current.data(), rest.data(), rest.size() * sizeof(glm::dvec3)), 0);
        // A proportional edit that moved neighbours cannot be keyed as a track; it says so.
        s.replay("0 key z ctrl+shift\n0 key k\n");
        EXPECT_NE(s.state->status.find("cannot key"), std::string::npos) << s.state->status;
    }
}

// `r z 90 Enter`: neighbours turn by w * 90 degrees about z through the pivot (the selected point).
TEST(Proportional, TypedTwistTurnsNeighboursByTheirWeight) {
    Scene s;
    const double r = 0.9;
    s.replay(select_front_centre(s, "sphere", r));
    const std::uint32_t centre = s.idx(2, 2, 4);
    const std::vector<glm::dvec3> rest = s.lat().current;
    s.replay("0 key r\n0 key z\n0 key 9\n0 key 0\n0 key enter\n");
    const glm::dvec3 pivot = rest[centre];
    for (std::size_t c = 0; c < rest.size(); ++c) {
        const double w = blender_weight("sphere", distance_to(rest, c, {centre}), r);
        const glm::dmat4 rot = glm::rotate(glm::dmat4(1.0), w * std::numbers::pi / 2, glm::dvec3(0, 0, 1));
        const glm::dvec3 expected = pivot + glm::dvec3(rot * glm::dvec4(rest[c] - pivot, 0.0));
        EXPECT_NEAR(glm::length(s.lat().current[c] - expected), 0.0, 1e-12) << c;
    }
    EXPECT_NE(s.lat().current[s.idx(3, 2, 4)], rest[s.idx(3, 2, 4)]);
}

// `s 2 Enter`: a neighbour goes w of the way to where the scale by 2 about the pivot puts it.
TEST(Proportional, TypedScaleMovesNeighboursPartOfTheWay) {
    Scene s;
    const double r = 1.2;
    s.replay(select_front_centre(s, "linear", r));
    // Two selected points: the distance is to the nearest of them, and the pivot is their centroid.
    s.replay("0 move " + s.pixel(s.idx(3, 2, 4)) + "\n0 press left shift\n0 release left shift\n");
    const std::vector<std::uint32_t> sel = {s.idx(2, 2, 4), s.idx(3, 2, 4)};
    ASSERT_EQ(s.reg.get<picking::LatticeSelection>(s.lattice).indices.size(), 2u);
    const std::vector<glm::dvec3> rest = s.lat().current;
    s.replay("0 key s\n0 key 2\n0 key enter\n");
    const glm::dvec3 pivot = 0.5 * (rest[sel[0]] + rest[sel[1]]);
    for (std::size_t c = 0; c < rest.size(); ++c) {
        const double w = blender_weight("linear", distance_to(rest, c, sel), r);
        const glm::dvec3 scaled = pivot + 2.0 * (rest[c] - pivot);
        EXPECT_NEAR(glm::length(s.lat().current[c] - (rest[c] + w * (scaled - rest[c]))), 0.0, 1e-12) << c;
    }
}

// A mouse drag: the wheel mid-drag makes the radius 1.1 times larger (scroll -1) and applies it at once;
// PageUp/PageDown do the same; the whole drag is one undo step; the overlay draws the radius's circle.
TEST(Proportional, WheelAndPageKeysSizeTheRadiusWhileDragging) {
    Scene s;
    const double r = 0.8;
    s.replay(select_front_centre(s, "smooth", r));
    const std::uint32_t centre = s.idx(2, 2, 4), corner = s.idx(3, 3, 3);  // corner: d = 0.866 > 0.8
    const std::vector<glm::dvec3> rest = s.lat().current;
    const std::size_t steps = s.state->undo.size();
    const glm::dvec3 p =
        project_to_pixel(s.reg.get<Camera>(s.state->camera), s.state->viewport, rest[centre]);
    const auto at = [&](double dx) { return std::to_string(p.x + dx) + " " + std::to_string(p.y); };
    s.replay("0 key g\n0 key escape\n0 move " + at(0) + "\n0 press left\n1 move " + at(30) + "\n");
    ASSERT_EQ(s.state->drag.kind, Drag::Kind::move);
    EXPECT_EQ(s.lat().current[corner], rest[corner]) << "outside the radius";
    // The overlay's circle: 64 segments at the radius about the pivot, facing the view.
    {
        const OverlayGeometry g = build_lattice_overlay(s.reg, *s.state, s.lattice);
        std::size_t on_circle = 0;
        const glm::dvec3 view = glm::normalize(s.state->drag.camera.target - s.state->drag.camera.eye);
        for (const OverlayVertex& v : g.lines) {
            const glm::dvec3 w = g.anchor + glm::dvec3(v.position) - s.state->drag.pivot_world;
            if (v.color == overlay_proportional && std::abs(glm::length(w) - r) < 1e-5 &&
                std::abs(glm::dot(w, view)) < 1e-5)
                ++on_circle;
        }
        EXPECT_EQ(on_circle, 128u);
    }
    s.replay("0 scroll -1\n");
    EXPECT_DOUBLE_EQ(s.state->drag.proportional.radius, r * 1.1);
    EXPECT_NE(s.lat().current[corner], rest[corner]) << "inside the larger radius at once";
    EXPECT_EQ(s.reg.get<Camera>(s.state->camera).eye, glm::dvec3(1.0, 1.4, 6.0)) << "no zoom while sizing";
    s.replay("0 key pageup\n0 key pageup\n0 key pagedown\n1 move " + at(40) + "\n2 release left\n");
    const double radius = r * 1.1 * 1.1 * 1.1 / 1.1;  // the wheel, then up, up, down
    EXPECT_NEAR(s.state->proportional.radius, radius, 1e-15) << "the next edit starts with it";
    EXPECT_EQ(s.state->undo.size(), steps + 1) << "one undo step for the drag";
    const glm::dvec3 moved = s.lat().current[centre] - rest[centre];
    EXPECT_GT(moved.x, 0.05);
    for (std::size_t c = 0; c < rest.size(); ++c) {
        const double w = blender_weight("smooth", distance_to(rest, c, {centre}), radius);
        EXPECT_NEAR(glm::length(s.lat().current[c] - (rest[c] + w * moved)), 0.0, 1e-12) << c;
    }
    // After the drag the wheel zooms again.
    s.replay("0 scroll 1\n");
    EXPECT_NE(s.reg.get<Camera>(s.state->camera).eye, glm::dvec3(1.0, 1.4, 6.0));
    s.replay("0 key z ctrl\n");
    EXPECT_EQ(std::memcmp(s.lat().current.data(), rest.data(), rest.size() * sizeof(glm::dvec3)), 0);
}

// With the outer layer pinned, the falloff moves no pinned point; `o` toggles, shift+o cycles.
TEST(Proportional, PinnedPointsStayAndKeysToggle) {
    Scene s;
    const std::uint32_t inner = s.idx(2, 2, 3);  // (0, 0, 0.5): its neighbour (0, 0, 1) is pinned
    s.replay("0 move " + s.pixel(inner) + "\n0 press left\n0 release left\n1 key o\n");
    ASSERT_EQ(s.reg.get<picking::LatticeSelection>(s.lattice).indices, std::vector<std::uint32_t>{inner});
    EXPECT_TRUE(s.state->proportional.enabled);
    s.replay("0 key o shift\n");
    EXPECT_EQ(s.state->proportional.falloff, Falloff::sphere);
    s.replay(
        "0 set proportional.radius 0.6\n0 key g\n0 key y\n0 key 0\n0 key period\n0 key 2\n0 key enter\n");
    const Lattice& l = s.lat();
    const std::vector<glm::dvec3> rest = l.rest;
    EXPECT_EQ(l.current[s.idx(2, 2, 4)], rest[s.idx(2, 2, 4)]) << "pinned";
    EXPECT_NEAR(l.current[inner].y - rest[inner].y, 0.2, 1e-12);
    const double w = blender_weight("sphere", 0.5, 0.6);
    EXPECT_NEAR(l.current[s.idx(2, 2, 2)].y - rest[s.idx(2, 2, 2)].y, w * 0.2, 1e-12);
    EXPECT_NEAR(l.current[s.idx(1, 2, 3)].y - rest[s.idx(1, 2, 3)].y, w * 0.2, 1e-12);
    s.replay("0 key o\n");
    EXPECT_FALSE(s.state->proportional.enabled);
    // Off: only the selection moves, as before.
    s.replay("0 key g\n0 key y\n0 key 0\n0 key period\n0 key 2\n0 key enter\n");
    EXPECT_NEAR(l.current[s.idx(2, 2, 2)].y - rest[s.idx(2, 2, 2)].y, w * 0.2, 1e-12);
    EXPECT_NEAR(l.current[inner].y - rest[inner].y, 0.4, 1e-12);
}

TEST(Proportional, ReplayCommandsRoundTripAndBadOnesAreNamed) {
    const std::string text =
        "3 set proportional.enabled 1\n4 set proportional.radius 0.25\n5 set proportional.falloff sharp\n";
    auto events = parse_input_recording(text, "p.txt");
    ASSERT_TRUE(events) << events.message();
    ASSERT_EQ(events->size(), 3u);
    EXPECT_EQ((*events)[2].value, double(int(Falloff::sharp)));
    auto again = parse_input_recording(format_input_recording(*events), "again.txt");
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, *events);
    auto bad = parse_input_recording("0 key g\n1 set proportional.falloff bumpy\n", "bad.txt");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.message().find("bad.txt:2: unknown falloff 'bumpy'"), std::string::npos) << bad.message();
    auto field = parse_input_recording("1 set proportional.size 2\n", "f.txt");
    ASSERT_FALSE(field);
    EXPECT_NE(field.message().find("f.txt:1: unknown field"), std::string::npos) << field.message();
}
