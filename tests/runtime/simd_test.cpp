// The SIMD target list, the dispatch's own report of what it runs, and pinning (runtime/simd/simd.h).
#include <algorithm>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "runtime/simd/simd.h"
#include "tests/test_util/simd_targets.h"

namespace sffd::simd {
namespace {

bool has(const std::vector<Target>& ts, const std::string& name) {
    return std::any_of(ts.begin(), ts.end(), [&](const Target& t) { return t.name == name; });
}

// Highway's portable target: emu128, or scalar where the compiler's emu128 code is known bad.
std::string portable() { return compiled().back().name; }

TEST(Simd, PortableTargetIsCompiledAndRunsAnywhere) {
    EXPECT_TRUE(portable() == "emu128" || portable() == "scalar") << portable();
    EXPECT_EQ(runnable().back().name, portable());  // best first: the portable target is the last resort
#if defined(__x86_64__)
    EXPECT_TRUE(has(compiled(), "sse4"));
    EXPECT_TRUE(has(compiled(), "avx2"));
    EXPECT_TRUE(has(compiled(), "avx3"));
#elif defined(__aarch64__)
    EXPECT_TRUE(has(compiled(), "neon"));
#endif
}

TEST(Simd, RunnableIsTheCompiledTargetsThisCpuHasBestFirst) {
    const auto all = compiled(), run = runnable();
    ASSERT_FALSE(run.empty());
    for (const Target& t : run) EXPECT_TRUE(has(all, t.name)) << t.name;
    for (std::size_t i = 1; i < run.size(); ++i) EXPECT_LT(run[i - 1].bits, run[i].bits);
}

TEST(Simd, UnpinnedDispatchRunsTheBestRunnableTarget) {
    unpin();
    EXPECT_EQ(chosen(), runnable().front().name);
}

TEST(Simd, VersionLineNamesTheChosenAndCompiledTargets) {
    unpin();
    std::string want = "simd: " + runnable().front().name + " (compiled: ";
    const auto all = compiled();
    for (std::size_t i = 0; i < all.size(); ++i) want += (i ? ", " : "") + all[i].name;
    EXPECT_EQ(version_line(), want + ")");
}

TEST(Simd, PinningAKnownTargetMovesTheDispatchAndUnpinRestores) {
    for (const Target& t : runnable()) {
        ASSERT_TRUE(pin(t.name)) << t.name;
        EXPECT_EQ(chosen(), t.name);
    }
    ASSERT_TRUE(pin("SCALAR"));  // any case; scalar names the portable target
    EXPECT_EQ(chosen(), portable());
    unpin();
    EXPECT_EQ(chosen(), runnable().front().name);
}

TEST(Simd, UnknownOrUnrunnableTargetsAreRefusedWithWhatTheCpuRuns) {
    unpin();
    const Status st = pin("avx9000");
    ASSERT_FALSE(st);
    EXPECT_NE(st.message().find("'avx9000' is not compiled into this binary"), std::string::npos)
        << st.message();
    for (const Target& t : runnable())
        EXPECT_NE(st.message().find(t.name), std::string::npos) << st.message();
    EXPECT_EQ(chosen(), runnable().front().name);  // a refusal changes nothing
    for (const Target& t : compiled()) {
        if (has(runnable(), t.name)) continue;
        const Status no = pin(t.name);
        ASSERT_FALSE(no) << t.name;
        EXPECT_NE(no.message().find("this CPU cannot run it"), std::string::npos) << no.message();
    }
}

TEST(Simd, EnvironmentValueIsCheckedAndNamed) {
    unpin();
    ::setenv("SFFD_SIMD", "nonsense", 1);
    const Status st = pin_from_environment();
    ::unsetenv("SFFD_SIMD");
    ASSERT_FALSE(st);
    EXPECT_EQ(st.message().rfind("SFFD_SIMD: SIMD target 'nonsense'", 0), 0u) << st.message();
    ::setenv("SFFD_SIMD", "scalar", 1);
    EXPECT_TRUE(pin_from_environment());
    ::unsetenv("SFFD_SIMD");
    EXPECT_EQ(chosen(), portable());
    unpin();
}

class SimdScope : public test::EverySimdTarget {};

TEST_P(SimdScope, EachTargetIsPinnedForItsTestAndTheScopeRestores) {
    EXPECT_EQ(chosen(), GetParam().name);
    {
        const ScopedTarget inner(runnable().back());
        EXPECT_EQ(chosen(), runnable().back().name);
    }
    EXPECT_EQ(chosen(), GetParam().name);
}
SFFD_INSTANTIATE_EVERY_SIMD_TARGET(SimdScope);

}  // namespace
}  // namespace sffd::simd
