#include <gtest/gtest.h>

#include <set>

#include "runtime/ecs/registry.h"

using namespace sffd::ecs;

namespace {
struct Position { float x = 0, y = 0; };
struct Velocity { float dx = 0, dy = 0; };
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
        static_assert(std::is_const_v<std::remove_reference_t<decltype(v)>>, "const view yields read-only refs");
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
