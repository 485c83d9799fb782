// Declared access at the registry level. This binary is compiled with SFFD_CHECK_ACCESS whatever the
// build type, and links only the header-only ECS, so the check is tested in every build.
#include <gtest/gtest.h>

#include "runtime/ecs/registry.h"

#if !defined(SFFD_CHECK_ACCESS)
#error "ecs_access_test is compiled with SFFD_CHECK_ACCESS (tests/runtime/CMakeLists.txt)"
#endif

using namespace sffd::ecs;

namespace {
struct Cloud {
    int points = 0;
};
struct Deformed {
    int points = 0;
};
struct Settings {
    int quality = 1;
};
struct Hidden {};

// Runs fn as system `name` with `access` declared.
template <class Fn>
void as_system(Registry& reg, const char* name, const Access& access, Fn&& fn) {
    const ActiveAccess active{name, &access};
    const AccessScope scope(reg, active);
    fn();
}
}  // namespace

TEST(EcsAccess, DeclarationsListTypesByNameAndWritesImplyReads) {
    const Access a = reads<Cloud, Settings, Deformed>().writes<Deformed>();
    ASSERT_EQ(a.read_types().size(), 2u);
    EXPECT_EQ(a.read_types()[0].name, "{anonymous}::Cloud");
    EXPECT_EQ(a.read_types()[1].name, "{anonymous}::Settings");
    ASSERT_EQ(a.write_types().size(), 1u);
    EXPECT_EQ(a.write_types()[0].name, "{anonymous}::Deformed");
    EXPECT_TRUE(a.can_read(detail::type_id<Deformed>()));
    EXPECT_TRUE(a.can_write(detail::type_id<Deformed>()));
    EXPECT_FALSE(a.can_write(detail::type_id<Cloud>()));
    EXPECT_TRUE(a.declared());
    EXPECT_FALSE(Access().declared());
    EXPECT_TRUE(no_access().declared());
    EXPECT_EQ(detail::type_name<sffd::ecs::Entity>(), "ecs::Entity");
}

TEST(EcsAccess, DeclaredAccessPasses) {
    Registry reg;
    const Entity e = reg.create();
    reg.emplace<Cloud>(e, 3);
    reg.emplace<Deformed>(e);
    reg.set_resource<Settings>();
    int seen = 0;
    as_system(reg, "deform", reads<Cloud, Settings>().writes<Deformed>(), [&] {
        const Registry& creg = reg;
        seen += creg.get<Cloud>(e).points;
        seen += creg.try_resource<Settings>()->quality;
        reg.patch<Deformed>(e).points = 3;
        reg.view<const Cloud, Deformed>().each([&](const Cloud& c, Deformed& d) { d.points += c.points; });
        reg.remove<Deformed>(e);
        reg.emplace<Deformed>(e, 1);
        seen += int(creg.has<Cloud>(e)) + int(creg.version<Cloud>(e) > 0);
    });
    EXPECT_EQ(seen, 6);
    // Outside any system nothing is checked.
    reg.emplace<Hidden>(e);
    EXPECT_TRUE(reg.has<Hidden>(e));
    // An undeclared Access (ad hoc schedules in tests) is not checked either.
    as_system(reg, "anything", Access(), [&] { reg.remove<Hidden>(e); });
    EXPECT_FALSE(reg.has<Hidden>(e));
}

using EcsAccessDeathTest = ::testing::Test;

TEST_F(EcsAccessDeathTest, UndeclaredComponentAbortsNamingSystemAndType) {
    Registry reg;
    const Entity e = reg.create();
    reg.emplace<Cloud>(e);
    reg.emplace<Deformed>(e);
    const Access access = reads<Cloud>().writes<Deformed>();
    EXPECT_DEATH(as_system(reg, "deform", access, [&] { (void)std::as_const(reg).has<Hidden>(e); }),
                 "system 'deform' reads \\{anonymous\\}::Hidden, which it does not declare");
    // Mutable access to a type declared read-only.
    EXPECT_DEATH(as_system(reg, "deform", access, [&] { reg.get<Cloud>(e).points = 2; }),
                 "system 'deform' writes \\{anonymous\\}::Cloud");
    EXPECT_DEATH(as_system(reg, "deform", access, [&] { reg.view<Cloud>().each([](Cloud&) {}); }),
                 "system 'deform' writes \\{anonymous\\}::Cloud");
    EXPECT_DEATH(as_system(reg, "deform", access, [&] { reg.emplace<Hidden>(e); }),
                 "system 'deform' writes \\{anonymous\\}::Hidden");
    EXPECT_DEATH(as_system(reg, "deform", access, [&] { (void)reg.try_resource<Settings>(); }),
                 "system 'deform' writes \\{anonymous\\}::Settings");
    EXPECT_DEATH(as_system(reg, "idle", no_access(), [&] { (void)std::as_const(reg).count<Cloud>(); }),
                 "system 'idle' reads \\{anonymous\\}::Cloud");
}

TEST(EcsAccess, ScopesNestAndRestore) {
    Registry reg;
    const Access outer = reads<Cloud>();
    const ActiveAccess a{"outer", &outer};
    {
        const AccessScope s1(reg, a);
        const Access inner = writes<Deformed>();
        const ActiveAccess b{"inner", &inner};
        {
            const AccessScope s2(reg, b);
            EXPECT_EQ(reg.active_access()->system, "inner");
        }
        EXPECT_EQ(reg.active_access()->system, "outer");
    }
    EXPECT_EQ(reg.active_access(), nullptr);
}

// A signal's listener belongs to whoever connected it: it runs outside the declared access of the system
// whose remove set it off (a clean-up listener must not need every system to declare its types).
TEST(EcsAccess, SignalListenersRunOutsideTheSystemsAccess) {
    Registry reg;
    const Entity e = reg.create();
    reg.emplace<Cloud>(e);
    reg.emplace<Deformed>(e);
    reg.on_destroy<Cloud>().connect([](Registry& r, Entity x) { r.remove<Deformed>(x); });
    as_system(reg, "editor", writes<Cloud>(), [&] {
        reg.remove<Cloud>(e);
        EXPECT_NE(reg.active_access(), nullptr);  // restored after the listener
    });
    EXPECT_FALSE(reg.has<Deformed>(e));
}
