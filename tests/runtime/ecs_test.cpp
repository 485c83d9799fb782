#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <vector>

#include "runtime/ecs/registry.h"

using namespace sffd::ecs;

namespace {
struct Position {
    float x = 0, y = 0;
};
struct Velocity {
    float dx = 0, dy = 0;
};
struct Tag {};
}  // namespace

TEST(Ecs, StaleHandleIsDetectedAfterReuse) {
    Registry reg;
    Entity a = reg.create();
    reg.emplace<Position>(a, 1.f, 2.f);
    reg.destroy(a);
    EXPECT_FALSE(reg.valid(a));
    Entity b = reg.create();  // reuses a's index with a new generation
    EXPECT_EQ(b.index, a.index);
    EXPECT_NE(b.generation, a.generation);
    EXPECT_TRUE(reg.valid(b));
    EXPECT_FALSE(reg.valid(a));
    EXPECT_FALSE(reg.has<Position>(b));
}

TEST(Ecs, ViewVisitsExactlyTheEntitiesWithAllComponents) {
    Registry reg;
    std::set<std::uint32_t> expected;
    for (int i = 0; i < 100; ++i) {
        Entity e = reg.create();
        reg.emplace<Position>(e, float(i), 0.f);
        if (i % 3 == 0) {
            reg.emplace<Velocity>(e, 1.f, 1.f);
            expected.insert(e.index);
        }
    }
    std::set<std::uint32_t> seen;
    reg.view<const Velocity, Position>().each([&](Entity e, const Velocity& v, Position& p) {
        p.x += v.dx;
        seen.insert(e.index);
    });
    EXPECT_EQ(seen, expected);
    std::set<std::uint32_t> seen_range;
    for (auto [e, v, p] : reg.view<const Velocity, Position>()) {
        static_assert(std::is_const_v<std::remove_reference_t<decltype(v)>>,
                      "const view yields read-only refs");
        seen_range.insert(e.index);
        (void)p;
    }
    EXPECT_EQ(seen_range, expected);
}

TEST(Ecs, DestroyingCurrentEntityWhileIteratingIsSafe) {
    Registry reg;
    for (int i = 0; i < 1000; ++i) reg.emplace<Position>(reg.create(), float(i), 0.f);
    int visited = 0;
    reg.view<Position>().each([&](Entity e, Position& p) {
        ++visited;
        if (int(p.x) % 2 == 0) reg.destroy(e);
    });
    EXPECT_EQ(visited, 1000);
    EXPECT_EQ(reg.count<Position>(), 500u);
    reg.view<const Position>().each([](const Position& p) { EXPECT_EQ(int(p.x) % 2, 1); });
}

TEST(Ecs, DeferredDestructionAppliesOnFlush) {
    Registry reg;
    std::vector<Entity> all;
    for (int i = 0; i < 10; ++i) all.push_back(reg.create()), reg.emplace<Tag>(all.back());
    reg.view<Tag>().each([&](Entity e, Tag&) { reg.destroy_later(e); });
    EXPECT_EQ(reg.alive(), 10u);
    reg.flush();
    EXPECT_EQ(reg.alive(), 0u);
    for (Entity e : all) EXPECT_FALSE(reg.valid(e));
}

TEST(Ecs, ChangeStampsLetSystemsSkipUnchangedData) {
    Registry reg;
    Entity a = reg.create(), b = reg.create();
    reg.emplace<Position>(a);
    reg.emplace<Position>(b);
    const auto seen_a = reg.version<Position>(a);
    const auto seen_storage = reg.storage_version<Position>();
    EXPECT_EQ(reg.storage_version<Position>(), seen_storage);  // nothing changed yet
    reg.patch<Position>(b).x = 5.f;
    EXPECT_GT(reg.storage_version<Position>(), seen_storage);
    EXPECT_EQ(reg.version<Position>(a), seen_a);
    EXPECT_GT(reg.version<Position>(b), seen_a);
    EXPECT_EQ(reg.version<Velocity>(a), 0u);
}

TEST(Ecs, Resources) {
    Registry reg;
    EXPECT_EQ(reg.try_resource<Position>(), nullptr);
    reg.set_resource<Position>(3.f, 4.f);
    EXPECT_EQ(reg.resource<Position>().y, 4.f);
    reg.erase_resource<Position>();
    EXPECT_EQ(reg.try_resource<Position>(), nullptr);
}

TEST(Ecs, OneMillionEntities) {
    Registry reg;
    constexpr int n = 1'000'000;
    for (int i = 0; i < n; ++i) {
        Entity e = reg.create();
        reg.emplace<Position>(e, float(i), 0.f);
        if (i % 2 == 0) reg.emplace<Velocity>(e, 1.f, 0.f);
    }
    double sum = 0;
    std::size_t count = 0;
    reg.view<const Position, const Velocity>().each([&](const Position& p, const Velocity&) {
        sum += double(p.x);
        ++count;
    });
    EXPECT_EQ(count, std::size_t(n / 2));
    EXPECT_DOUBLE_EQ(sum, double(n / 2 - 1) * double(n / 2));  // sum of even numbers below n
}

TEST(Ecs, StaleHandleNeverReachesTheNewEntitysComponents) {
    Registry reg;
    Entity a = reg.create();
    reg.emplace<Position>(a, 1.f, 1.f);
    reg.destroy(a);
    Entity b = reg.create();
    reg.emplace<Position>(b, 2.f, 2.f);
    ASSERT_EQ(a.index, b.index);
    EXPECT_FALSE(reg.has<Position>(a));
    EXPECT_EQ(reg.try_get<Position>(a), nullptr);
    reg.remove<Position>(a);  // a no-op through a stale handle
    EXPECT_TRUE(reg.has<Position>(b));
    reg.destroy_later(a);  // ignored at flush: a is stale
    reg.flush();
    EXPECT_TRUE(reg.valid(b));
    // Generations keep counting across many reuses of one index.
    Entity last = b;
    for (int i = 0; i < 5; ++i) {
        reg.destroy(last);
        Entity next = reg.create();
        EXPECT_EQ(next.index, b.index);
        EXPECT_EQ(next.generation, last.generation + 1);
        EXPECT_FALSE(reg.valid(last));
        last = next;
    }
    EXPECT_FALSE(Registry().valid(null_entity));
}

TEST(Ecs, RemovingTheCurrentComponentWhileIteratingARangeIsSafe) {
    Registry reg;
    for (int i = 0; i < 200; ++i) {
        Entity e = reg.create();
        reg.emplace<Position>(e, float(i), 0.f);
        reg.emplace<Velocity>(e, 1.f, 0.f);
    }
    int visited = 0;
    for (auto [e, p, v] : reg.view<Position, const Velocity>()) {
        ++visited;
        (void)v;
        if (int(p.x) % 4 == 0) reg.remove<Velocity>(e);  // leaves the view
        else if (int(p.x) % 4 == 1) reg.destroy(e);      // leaves everything
    }
    EXPECT_EQ(visited, 200);
    EXPECT_EQ(reg.count<Velocity>(), 100u);
    EXPECT_EQ(reg.count<Position>(), 150u);
    std::set<int> left;
    reg.view<const Position, const Velocity>().each(
        [&](const Position& p, const Velocity&) { left.insert(int(p.x)); });
    EXPECT_EQ(left.size(), 100u);
    for (int x : left) EXPECT_GE(x % 4, 2);
}

TEST(Ecs, DeferredCommandsRunAtFlushInOrder) {
    Registry reg;
    Entity a = reg.create();
    reg.emplace<Position>(a);
    // Adding components to other entities during iteration goes through defer().
    reg.view<Position>().each([&](Entity e, Position&) {
        reg.defer([e](Registry& r) { r.emplace<Velocity>(e, 3.f, 0.f); });
        reg.defer([](Registry& r) { r.emplace<Position>(r.create(), 9.f, 9.f); });
    });
    EXPECT_FALSE(reg.has<Velocity>(a));
    EXPECT_EQ(reg.count<Position>(), 1u);
    reg.flush();
    EXPECT_EQ(reg.get<Velocity>(a).dx, 3.f);
    EXPECT_EQ(reg.count<Position>(), 2u);
    reg.flush();  // nothing pending: no change
    EXPECT_EQ(reg.count<Position>(), 2u);
}

TEST(Ecs, ChangeStampsCoverAddReplaceRemoveAndDestroy) {
    // The pattern the deformer uses: remember the stamps it consumed, redo work only when one moved.
    Registry reg;
    Entity lattice = reg.create(), other = reg.create();
    reg.emplace<Position>(lattice);
    reg.emplace<Position>(other);
    std::uint64_t seen = reg.version<Position>(lattice);
    std::uint64_t seen_any = reg.storage_version<Position>();
    // Read-only access does not count as a change.
    (void)reg.get<Position>(lattice);
    reg.view<const Position>().each([](const Position&) {});
    EXPECT_EQ(reg.version<Position>(lattice), seen);
    EXPECT_EQ(reg.storage_version<Position>(), seen_any);
    // An edit of another entity moves the storage stamp only.
    reg.patch<Position>(other).x = 1.f;
    EXPECT_EQ(reg.version<Position>(lattice), seen);
    EXPECT_GT(reg.storage_version<Position>(), seen_any);
    seen_any = reg.storage_version<Position>();
    // Replacing by emplace is an edit.
    reg.emplace<Position>(lattice, 4.f, 4.f);
    EXPECT_GT(reg.version<Position>(lattice), seen);
    seen = reg.version<Position>(lattice);
    reg.mark_changed<Position>(lattice);
    EXPECT_GT(reg.version<Position>(lattice), seen);
    // Removal and destruction move the storage stamp (a system iterating the set must look again).
    seen_any = reg.storage_version<Position>();
    reg.remove<Position>(other);
    EXPECT_GT(reg.storage_version<Position>(), seen_any);
    seen_any = reg.storage_version<Position>();
    reg.destroy(lattice);
    EXPECT_GT(reg.storage_version<Position>(), seen_any);
    EXPECT_EQ(reg.version<Position>(lattice), 0u);
    // Stamps are shared across types and never go back.
    reg.emplace<Velocity>(reg.create());
    EXPECT_GT(reg.storage_version<Velocity>(), reg.storage_version<Position>());
}

TEST(Ecs, ComponentsAndResourcesConstructTheSameWayWhenAddedOrReplaced) {
    Registry reg;
    Entity e = reg.create();
    // Non-aggregates use their constructors (three ones), aggregates use braces.
    EXPECT_EQ(reg.emplace<std::vector<int>>(e, 3u, 1), (std::vector<int>{1, 1, 1}));
    EXPECT_EQ(reg.emplace<std::vector<int>>(e, 2u, 7), (std::vector<int>{7, 7}));
    EXPECT_EQ(reg.set_resource<std::vector<int>>(4u, 2).size(), 4u);
    EXPECT_EQ(reg.emplace<Position>(e, 1.f, 2.f).y, 2.f);
    EXPECT_EQ(reg.emplace<Position>(e, 5.f).x, 5.f);
    EXPECT_EQ(reg.get<Position>(e).y, 0.f);  // replaced, not merged
    // Replacing a resource replaces its value; try_resource through a const registry.
    reg.set_resource<Position>(1.f, 1.f);
    reg.set_resource<Position>(2.f, 3.f);
    const Registry& cref = reg;
    ASSERT_NE(cref.try_resource<Position>(), nullptr);
    EXPECT_EQ(cref.resource<Position>().y, 3.f);
}

TEST(Ecs, MoveOnlyComponentsAndSwapRemoveKeepData) {
    Registry reg;
    std::vector<Entity> es;
    for (int i = 0; i < 5; ++i) {
        es.push_back(reg.create());
        reg.emplace<std::unique_ptr<int>>(es.back(), std::make_unique<int>(i));
    }
    reg.remove<std::unique_ptr<int>>(es[1]);  // the last element moves into the hole
    reg.destroy(es[0]);
    for (int i = 2; i < 5; ++i) EXPECT_EQ(*reg.get<std::unique_ptr<int>>(es[std::size_t(i)]), i);
    EXPECT_EQ(reg.count<std::unique_ptr<int>>(), 3u);
}

// --- storage signals --------------------------------------------------------------------------------

TEST(EcsSignals, ConstructFiresOnAddNotOnReplaceAndDestroyFiresBeforeRemoval) {
    Registry reg;
    std::vector<std::pair<char, float>> log;  // ('c' | 'd', the component's x when told)
    reg.on_construct<Position>().connect([&](Registry& r, Entity e) {
        log.push_back({'c', r.get<Position>(e).x});
    });
    reg.on_destroy<Position>().connect([&](Registry& r, Entity e) {
        ASSERT_TRUE(r.has<Position>(e));  // still there: a listener reads what goes away
        log.push_back({'d', r.get<Position>(e).x});
    });
    const Entity a = reg.create();
    reg.emplace<Position>(a, 1.f, 0.f);
    reg.emplace<Position>(a, 2.f, 0.f);  // replaces: no second construct
    reg.emplace<Velocity>(a);            // another type: not told
    reg.remove<Position>(a);
    reg.remove<Position>(a);  // absent: not told
    const std::vector<std::pair<char, float>> want{{'c', 1.f}, {'d', 2.f}};
    EXPECT_EQ(log, want);
}

TEST(EcsSignals, DestroyAndClearTellEveryComponentsListener) {
    Registry reg;
    std::vector<std::uint32_t> pos_gone, vel_gone;
    reg.on_destroy<Position>().connect([&](Registry&, Entity e) { pos_gone.push_back(e.index); });
    reg.on_destroy<Velocity>().connect([&](Registry&, Entity e) { vel_gone.push_back(e.index); });
    const Entity a = reg.create(), b = reg.create(), c = reg.create();
    reg.emplace<Position>(a);
    reg.emplace<Velocity>(a);
    reg.emplace<Position>(b);
    reg.emplace<Velocity>(c);
    reg.destroy(a);
    EXPECT_EQ(pos_gone, std::vector<std::uint32_t>{a.index});
    EXPECT_EQ(vel_gone, std::vector<std::uint32_t>{a.index});
    reg.destroy_later(c);
    reg.flush();
    EXPECT_EQ(vel_gone, (std::vector<std::uint32_t>{a.index, c.index}));
    reg.storage<Position>().clear();
    EXPECT_EQ(pos_gone, (std::vector<std::uint32_t>{a.index, b.index}));
    EXPECT_EQ(reg.count<Position>(), 0u);
}

TEST(EcsSignals, DisconnectStopsAListenerEvenFromInsideACall) {
    Registry reg;
    int first = 0, second = 0;
    Connection c1;
    c1 = reg.on_construct<Tag>().connect([&](Registry&, Entity) {
        ++first;
        c1.disconnect();  // itself, during the call
    });
    Connection c2 = reg.on_construct<Tag>().connect([&](Registry&, Entity) { ++second; });
    EXPECT_TRUE(c2.connected());
    reg.emplace<Tag>(reg.create());
    reg.emplace<Tag>(reg.create());
    EXPECT_EQ(first, 1);
    EXPECT_EQ(second, 2);
    EXPECT_FALSE(c1.connected());
    c2.disconnect();
    EXPECT_FALSE(c2.connected());
    reg.emplace<Tag>(reg.create());
    EXPECT_EQ(second, 2);
    {
        ScopedConnection scoped = reg.on_construct<Tag>().connect([&](Registry&, Entity) { ++second; });
        reg.emplace<Tag>(reg.create());
    }
    reg.emplace<Tag>(reg.create());
    EXPECT_EQ(second, 3);
}

TEST(EcsSignals, ListenersMayChangeTheRegistryAndOutliveIt) {
    Connection late;
    {
        Registry reg;
        // A side component cleaned up by its owner's destroy signal: one clean-up place, no loop.
        reg.on_destroy<Position>().connect([](Registry& r, Entity e) { r.remove<Velocity>(e); });
        // A listener that adds components of its own type moves the packed data: emplace still
        // returns the right one.
        reg.on_construct<Position>().connect([](Registry& r, Entity e) {
            if (r.get<Position>(e).x > 0) r.emplace<Position>(r.create(), -1.f, 0.f);
        });
        const Entity a = reg.create();
        Position& p = reg.emplace<Position>(a, 5.f, 0.f);
        EXPECT_EQ(p.x, 5.f);
        EXPECT_EQ(reg.count<Position>(), 2u);
        reg.emplace<Velocity>(a);
        reg.remove<Position>(a);
        EXPECT_FALSE(reg.has<Velocity>(a));
        late = reg.on_destroy<Tag>().connect([](Registry&, Entity) {});
        EXPECT_TRUE(late.connected());
    }
    EXPECT_FALSE(late.connected());
    late.disconnect();  // the registry is gone: nothing to do, nothing to crash
}
