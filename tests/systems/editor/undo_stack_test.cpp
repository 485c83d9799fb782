#include "systems/editor/undo_stack.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/ffd/components.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

Lattice make_lattice() {
    Lattice l;
    l.divisions = {2, 2, 2};
    for (int i = 0; i <= 2; ++i)
        for (int j = 0; j <= 2; ++j)
            for (int k = 0; k <= 2; ++k) l.rest.push_back(glm::dvec3(i, j, k) * 0.5);
    l.current = l.rest;
    return l;
}

bool bit_equal(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

struct Tag {
    int value = 0;
    bool operator==(const Tag&) const = default;
};

}  // namespace

TEST(UndoStack, UndoRestoresLatticeBitForBitAndRedoReapplies) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, make_lattice());
    const Lattice original = reg.get<Lattice>(e);

    UndoStack undo;
    ASSERT_TRUE(undo.record<Lattice>(reg, e, "stretch", [](Lattice& l) {
        l.current[13] += glm::dvec3(0.1, 1.0 / 3.0, -0.7);  // inexact binary fractions on purpose
    }));
    const Lattice edited = reg.get<Lattice>(e);
    EXPECT_FALSE(bit_equal(edited.current, original.current));

    const auto stamp_before_undo = reg.version<Lattice>(e);
    ASSERT_TRUE(undo.undo(reg));
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(e).current, original.current));
    EXPECT_GT(reg.version<Lattice>(e), stamp_before_undo) << "undo must stamp the change for the deformer";

    ASSERT_TRUE(undo.redo(reg));
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(e).current, edited.current));
    EXPECT_FALSE(undo.redo(reg));
}

TEST(UndoStack, NewStepAfterUndoDropsTheRedoHistory) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Tag>(e, Tag{0});
    UndoStack undo;
    for (int v = 1; v <= 3; ++v) undo.record<Tag>(reg, e, "set", [v](Tag& t) { t.value = v; });
    EXPECT_EQ(undo.size(), 3u);
    undo.undo(reg);
    undo.undo(reg);
    EXPECT_EQ(reg.get<Tag>(e).value, 1);
    EXPECT_TRUE(undo.can_redo());
    undo.record<Tag>(reg, e, "set", [](Tag& t) { t.value = 7; });
    EXPECT_FALSE(undo.can_redo());
    EXPECT_EQ(undo.size(), 2u);
    undo.undo(reg);
    EXPECT_EQ(reg.get<Tag>(e).value, 1);
    undo.undo(reg);
    EXPECT_EQ(reg.get<Tag>(e).value, 0);
    EXPECT_FALSE(undo.undo(reg));
}

TEST(UndoStack, UnchangedStateIsNotAStep) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Tag>(e, Tag{4});
    UndoStack undo;
    EXPECT_FALSE(undo.record<Tag>(reg, e, "noop", [](Tag& t) { t.value = 4; }));
    EXPECT_EQ(undo.size(), 0u);
    EXPECT_FALSE(undo.record<Tag>(reg, reg.create(), "missing", [](Tag&) {}));
}

TEST(UndoStack, AddingAComponentUndoesToAbsent) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    ComponentEdit<Tag> edit(reg, e, "add tag");
    reg.emplace<Tag>(e, Tag{9});
    UndoStack undo;
    ASSERT_TRUE(undo.push(edit.finish(reg)));
    undo.undo(reg);
    EXPECT_FALSE(reg.has<Tag>(e));
    undo.redo(reg);
    ASSERT_TRUE(reg.has<Tag>(e));
    EXPECT_EQ(reg.get<Tag>(e).value, 9);
}

TEST(UndoStack, GroupUndoesItsPartsInReverseOrder) {
    ecs::Registry reg;
    const ecs::Entity a = reg.create(), b = reg.create();
    reg.emplace<Tag>(a, Tag{1});
    reg.emplace<Lattice>(b, make_lattice());
    auto group = std::make_unique<CommandGroup>("resample");
    ComponentEdit<Tag> t(reg, a, "tag");
    ComponentEdit<Lattice> l(reg, b, "lattice");
    reg.patch<Tag>(a).value = 2;
    reg.patch<Lattice>(b).current[0].x = -1.0;
    group->add(t.finish(reg));
    group->add(l.finish(reg));
    ComponentEdit<Tag> unchanged(reg, a, "same");
    group->add(unchanged.finish(reg));  // no-op parts are dropped
    EXPECT_EQ(group->size(), 2u);
    UndoStack undo;
    ASSERT_TRUE(undo.push(std::move(group)));
    undo.undo(reg);
    EXPECT_EQ(reg.get<Tag>(a).value, 1);
    EXPECT_EQ(reg.get<Lattice>(b).current[0].x, 0.0);
    undo.redo(reg);
    EXPECT_EQ(reg.get<Tag>(a).value, 2);
    EXPECT_EQ(reg.get<Lattice>(b).current[0].x, -1.0);
}

TEST(UndoStack, LimitForgetsTheOldestSteps) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Tag>(e, Tag{0});
    UndoStack undo(4);
    for (int v = 1; v <= 10; ++v) undo.record<Tag>(reg, e, "set", [v](Tag& t) { t.value = v; });
    EXPECT_EQ(undo.size(), 4u);
    while (undo.undo(reg)) {
    }
    EXPECT_EQ(reg.get<Tag>(e).value, 6);
}

TEST(UndoStack, DestroyedEntityIsSkipped) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Tag>(e, Tag{0});
    UndoStack undo;
    undo.record<Tag>(reg, e, "set", [](Tag& t) { t.value = 1; });
    reg.destroy(e);
    const ecs::Entity reused = reg.create();  // same index, new generation
    reg.emplace<Tag>(reused, Tag{5});
    EXPECT_TRUE(undo.undo(reg));
    EXPECT_EQ(reg.get<Tag>(reused).value, 5);
}

// A step holds what it changed: moving 8 control points of an 11³ lattice deforming a 1M-point cloud is
// a few hundred bytes (two snapshots of the lattice would be 4 · 1331 · 24 = 128 KB), and undo/redo of
// the compact step are as exact as of snapshots.
TEST(UndoStack, MovingEightControlPointsOfAMillionPointCloudCostsUnderOneKilobyte) {
    ecs::Registry reg;
    const ecs::Entity lattice = reg.create();
    reg.emplace<Lattice>(
        lattice,
        sffd::make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                           {10, 10, 10}));
    const ecs::Entity cloud = reg.create();
    SplatCloud& points = reg.emplace<SplatCloud>(cloud);
    points.positions.assign(1'000'000, glm::vec3(0.25f));
    reg.emplace<Deformers>(cloud, Deformers{{lattice}});
    const Lattice original = reg.get<Lattice>(lattice);

    UndoStack undo;
    const std::size_t empty_stack = undo.bytes();
    const std::uint32_t moved[8] = {0, 17, 121, 500, 665, 666, 1000, 1330};
    ASSERT_TRUE(undo.record<Lattice>(reg, lattice, "stretch", [&](Lattice& l) {
        for (std::uint32_t i : moved) l.current[i] += glm::dvec3(0.1, -1.0 / 3.0, 0.7);
    }));
    const std::size_t step = undo.bytes() - empty_stack;
    RecordProperty("step_bytes", int(step));
    EXPECT_LT(step, 1024u);
    EXPECT_GT(step, 8u * 2u * sizeof(glm::dvec3)) << "the step must still hold the 8 points before and after";
    const auto& change = dynamic_cast<const ComponentChange<Lattice>&>(undo.at(0));
    EXPECT_TRUE(change.sparse());

    const Lattice edited = reg.get<Lattice>(lattice);
    ASSERT_TRUE(undo.undo(reg));
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(lattice).current, original.current));
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(lattice).rest, original.rest));
    ASSERT_TRUE(undo.redo(reg));
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(lattice).current, edited.current));
}

// A change of the lattice's frame (a refit, a resample: new divisions) cannot be a list of moved points:
// it keeps both snapshots, and undo brings the old grid back whole.
TEST(UndoStack, ResampledLatticeKeepsWholeSnapshots) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, make_lattice());
    const Lattice original = reg.get<Lattice>(e);
    UndoStack undo;
    ASSERT_TRUE(undo.record<Lattice>(reg, e, "resample", [](Lattice& l) {
        l = sffd::make_lattice(glm::dvec3(0.0),
                               {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}, {3, 3, 3});
    }));
    const auto& change = dynamic_cast<const ComponentChange<Lattice>&>(undo.at(0));
    EXPECT_FALSE(change.sparse());
    EXPECT_GT(undo.bytes(), (27u + 64u) * 2u * sizeof(glm::dvec3));
    undo.undo(reg);
    EXPECT_EQ(reg.get<Lattice>(e).divisions, original.divisions);
    EXPECT_TRUE(bit_equal(reg.get<Lattice>(e).current, original.current));
    undo.redo(reg);
    EXPECT_EQ(reg.get<Lattice>(e).divisions, glm::ivec3(3));
}

// Bit-for-bit comparison: a point moved from 0.0 to -0.0 is a change, kept and undone exactly.
TEST(UndoStack, SignOfZeroIsAChange) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, make_lattice());
    UndoStack undo;
    ASSERT_TRUE(undo.record<Lattice>(reg, e, "nudge", [](Lattice& l) { l.current[0].x = -0.0; }));
    EXPECT_TRUE(std::signbit(reg.get<Lattice>(e).current[0].x));
    undo.undo(reg);
    EXPECT_FALSE(std::signbit(reg.get<Lattice>(e).current[0].x));
}

// An un-keyed pose (the whole lattice's points at a clip time) is stored as what moved, with its time.
TEST(UndoStack, UnkeyedPoseChangeKeepsTheMovedPointsAndTheTime) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    const Lattice l = make_lattice();
    reg.emplace<UnkeyedEdit>(e, UnkeyedEdit{0.5, l.current});
    UndoStack undo;
    ASSERT_TRUE(undo.record<UnkeyedEdit>(reg, e, "set pose", [](UnkeyedEdit& u) {
        u.time = 1.25;
        u.points[4].y += 0.5;
    }));
    EXPECT_LT(undo.bytes(), 1024u);
    undo.undo(reg);
    EXPECT_EQ(reg.get<UnkeyedEdit>(e).time, 0.5);
    EXPECT_TRUE(bit_equal(reg.get<UnkeyedEdit>(e).points, l.current));
    undo.redo(reg);
    EXPECT_EQ(reg.get<UnkeyedEdit>(e).time, 1.25);
    EXPECT_EQ(reg.get<UnkeyedEdit>(e).points[4].y, l.current[4].y + 0.5);
}
