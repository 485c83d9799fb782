// Runs a CPU-kernel test once per SIMD target this machine can run (runtime/simd/simd.h), the portable
// one (scalar or emu128) included:
//   class MyKernel : public sffd::test::EverySimdTarget {};
//   TEST_P(MyKernel, Case) { ... }       // the target is pinned for the test's body
//   SFFD_INSTANTIATE_EVERY_SIMD_TARGET(MyKernel);
// Test names end in the target (MyKernel/Case/avx2), so a failure says which code path failed.
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include <gtest/gtest.h>

#include "runtime/simd/simd.h"

namespace sffd::simd {

// gtest prints a parameter through PrintTo: the target's name, not its bytes (ctest's test list shows it).
inline void PrintTo(const Target& t, std::ostream* os) { *os << t.name; }

}  // namespace sffd::simd

namespace sffd::test {

class EverySimdTarget : public ::testing::TestWithParam<simd::Target> {
protected:
    void SetUp() override { m_pin = std::make_unique<simd::ScopedTarget>(GetParam()); }
    void TearDown() override { m_pin.reset(); }

private:
    std::unique_ptr<simd::ScopedTarget> m_pin;
};

inline std::string simd_target_name(const ::testing::TestParamInfo<simd::Target>& info) {
    return info.param.name;
}

}  // namespace sffd::test

#define SFFD_INSTANTIATE_EVERY_SIMD_TARGET(suite)                                        \
    INSTANTIATE_TEST_SUITE_P(Simd, suite, ::testing::ValuesIn(::sffd::simd::runnable()), \
                             ::sffd::test::simd_target_name)
