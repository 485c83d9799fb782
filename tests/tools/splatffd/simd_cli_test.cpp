// The SIMD target as a user sees it: `splatffd --version` names it, SFFD_SIMD pins it or is refused with
// what this CPU runs, and a render records it (runtime/simd/simd.h), through the built binary.
#include <string>

#include <gtest/gtest.h>

#include "runtime/simd/simd.h"
#include "tests/test_util/run_tool.h"

namespace {

using sffd::test::CliRun;

CliRun with_simd(const std::string& value, const std::string& args) {
    return sffd::test::run_command("SFFD_SIMD=" + value + " " + std::string(SFFD_BINARY_DIR) +
                                   "/tools/splatffd " + args);
}

std::string compiled_list() {
    std::string s;
    for (const auto& t : sffd::simd::compiled()) s += (s.empty() ? "" : ", ") + t.name;
    return s;
}

TEST(SimdCli, VersionPrintsTheChosenTargetAndEveryCompiledOne) {
    const CliRun r = sffd::test::run_command("env -u SFFD_SIMD " + std::string(SFFD_BINARY_DIR) +
                                             "/tools/splatffd --version");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(
        r.out.find("simd: " + sffd::simd::runnable().front().name + " (compiled: " + compiled_list() + ")\n"),
        std::string::npos)
        << r.out;
}

TEST(SimdCli, EveryRunnableTargetAndScalarCanBePinned) {
    for (const auto& t : sffd::simd::runnable()) {
        const CliRun r = with_simd(t.name, "--version");
        ASSERT_EQ(r.code, 0) << t.name << ": " << r.out;
        EXPECT_NE(r.out.find("simd: " + t.name + " ("), std::string::npos) << r.out;
    }
    const CliRun r = with_simd("scalar", "--version");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("simd: " + sffd::simd::compiled().back().name + " ("), std::string::npos) << r.out;
}

TEST(SimdCli, UnknownTargetIsRefusedWithExit2AndWhatTheCpuRuns) {
    for (const std::string cmd : {"--version", "info sphere"}) {
        const CliRun r = with_simd("avx1024", cmd);
        EXPECT_EQ(r.code, 2) << r.out;
        EXPECT_NE(r.out.find("splatffd: SFFD_SIMD: SIMD target 'avx1024' is not compiled into this binary; "
                             "this CPU runs: "),
                  std::string::npos)
            << r.out;
        for (const auto& t : sffd::simd::runnable())
            EXPECT_NE(r.out.find(t.name), std::string::npos) << r.out;
    }
}

TEST(SimdCli, CompiledTargetTheCpuCannotRunIsRefused) {
    int refused = 0;
    for (const auto& t : sffd::simd::compiled()) {
        bool runs = false;
        for (const auto& u : sffd::simd::runnable()) runs |= u.name == t.name;
        if (runs) continue;
        const CliRun r = with_simd(t.name, "--version");
        EXPECT_EQ(r.code, 2) << r.out;
        EXPECT_NE(r.out.find("is compiled in but this CPU cannot run it"), std::string::npos) << r.out;
        ++refused;
    }
    if (refused == 0) GTEST_SKIP() << "this CPU runs every compiled target (" << compiled_list() << ")";
}

}  // namespace
