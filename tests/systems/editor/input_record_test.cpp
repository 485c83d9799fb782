#include "systems/editor/input_record.h"

#include <gtest/gtest.h>

using namespace sffd::editor;

TEST(InputRecord, ParsesEveryEventKind) {
    const char* text =
        "# a comment\n"
        "0 move 10.5 20\n"
        "\n"
        "1 press left shift\n"
        "1 move 30 40   # trailing comment\n"
        "2 release left\n"
        "3 scroll -2 ctrl\n"
        "4 key z ctrl+shift\n"
        "5 text 0.25, 1, -3\n"
        "5 key f12\n"
        "6 set material.specular 0.75\n";
    auto parsed = parse_input_recording(text, "session.txt");
    ASSERT_TRUE(parsed.ok()) << parsed.message();
    const auto& e = *parsed;
    ASSERT_EQ(e.size(), 9u);
    EXPECT_EQ(e[0].kind, InputKind::move);
    EXPECT_EQ(e[0].position, glm::dvec2(10.5, 20));
    EXPECT_EQ(e[1].kind, InputKind::press);
    EXPECT_EQ(e[1].button, MouseButton::left);
    EXPECT_EQ(e[1].modifiers, mods::shift);
    EXPECT_EQ(e[3].kind, InputKind::release);
    EXPECT_EQ(e[4].scroll, -2.0);
    EXPECT_EQ(e[4].modifiers, mods::ctrl);
    EXPECT_EQ(e[5].key, "z");
    EXPECT_EQ(e[5].modifiers, mods::ctrl | mods::shift);
    EXPECT_EQ(e[6].kind, InputKind::text);
    EXPECT_EQ(e[6].key, "0.25, 1, -3");
    EXPECT_EQ(e[7].frame, 5u);
    EXPECT_EQ(e[8].kind, InputKind::set);
    EXPECT_EQ(e[8].key, "material.specular");
    EXPECT_EQ(e[8].value, 0.75);
}

TEST(InputRecord, RoundTripsExactly) {
    std::vector<InputEvent> events;
    InputEvent m;
    m.frame = 3;
    m.position = {0.1, 1.0 / 3.0};
    events.push_back(m);
    InputEvent k;
    k.frame = 4;
    k.kind = InputKind::key;
    k.key = "delete";
    k.modifiers = mods::alt | mods::ctrl;
    events.push_back(k);
    InputEvent s;
    s.frame = 9;
    s.kind = InputKind::scroll;
    s.scroll = -0.7;
    events.push_back(s);
    InputEvent t;
    t.frame = 9;
    t.kind = InputKind::text;
    t.key = "45";
    events.push_back(t);
    InputEvent v;
    v.frame = 10;
    v.kind = InputKind::set;
    v.key = "material.base_color.b";
    v.value = 0.1;
    events.push_back(v);
    auto back = parse_input_recording(format_input_recording(events), "x");
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(*back, events);
}

TEST(InputRecord, ErrorsNameTheFileAndLine) {
    struct Case {
        const char* text;
        const char* message;
    } cases[] = {
        {"0 move 1\n", "bad.txt:1: 'move' takes x y"},
        {"0 move 1 2\n\nx key a\n", "bad.txt:3: bad frame number 'x'"},
        {"5 key a\n4 key b\n", "bad.txt:2: frame 4 is before frame 5"},
        {"0 press thumb\n", "bad.txt:1: unknown mouse button 'thumb' (left, right, middle)"},
        {"0 key hyper\n", "bad.txt:1: unknown key 'hyper'"},
        {"0 key a super\n", "bad.txt:1: bad modifiers 'super' (shift, ctrl, alt joined by +)"},
        {"0 move nan 3\n", "bad.txt:1: bad cursor position"},
        {"0 jump\n", "bad.txt:1: unknown event 'jump' (move, press, release, scroll, key, text, set)"},
        {"0 set material.roughness 1\n",
         "bad.txt:1: unknown field 'material.roughness' (material.specular, material.shininess, "
         "material.base_color.r, material.base_color.g, material.base_color.b, material.base_color.a, "
         "proportional.enabled, proportional.radius, proportional.falloff, point.mode, point.brush_radius, "
         "point.sphere_radius, point.colour_tolerance, point.grow_distance, weight.radius, weight.falloff, "
         "view.lattice, view.weights)"},
        {"0 set material.specular\n", "bad.txt:1: 'set' takes a field and a value"},
        {"0 set material.specular x\n", "bad.txt:1: bad value 'x'"},
        {"0\n", "bad.txt:1: expected '<frame> <event> ...'"},
    };
    for (const auto& c : cases) {
        auto r = parse_input_recording(c.text, "bad.txt");
        ASSERT_FALSE(r.ok()) << c.text;
        EXPECT_EQ(r.message(), c.message);
    }
    auto missing = load_input_recording("/nonexistent/rec.txt");
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.message().rfind("/nonexistent/rec.txt: cannot open input recording", 0), 0u)
        << missing.message();
}

TEST(InputRecord, ReplayerHandsOutEventsPerFrame) {
    auto parsed = parse_input_recording("0 key a\n2 key b\n2 key c\n7 key d\n", "r");
    ASSERT_TRUE(parsed.ok());
    InputReplayer replay(*parsed);
    EXPECT_EQ(replay.take(0).size(), 1u);
    EXPECT_TRUE(replay.take(1).empty());
    EXPECT_EQ(replay.take(2).size(), 2u);
    EXPECT_FALSE(replay.finished());
    EXPECT_EQ(replay.last_frame(), 7u);
    EXPECT_EQ(replay.take(10).size(), 1u);  // a skipped frame still delivers its events
    EXPECT_TRUE(replay.finished());
}
