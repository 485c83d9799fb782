#include "systems/editor/undo_stack.h"

#include <cstring>

#include <gtest/gtest.h>

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
