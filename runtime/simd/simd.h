// Which SIMD target the CPU kernels run on. Every kernel is compiled once per Highway target
// (hwy/foreach_target.h) and picks one at run time (HWY_DYNAMIC_DISPATCH): the best one the CPU runs,
// unless a target is pinned, by SFFD_SIMD=<name> or by a test. One binary then runs on any x86-64
// (SSE4, AVX2, AVX-512 = Highway's avx3) or aarch64 (NEON) CPU, and on anything else through Highway's
// portable C++ target: emu128, or scalar with GCC before 12.3 (Debian 12's GCC 12.2), on which Highway
// avoids emu128. SFFD_SIMD=scalar names that portable target either way.
//
// Names are Highway's target names in lower case ("avx3", "avx2", "sse4", "neon", "scalar"). Kernel
// translation units include hwy/ through this library, whose compile definitions decide which targets
// exist; every unit that includes Highway must agree on them, so they are set once, on sffd_simd.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::simd {

// Highway target bits, best first, and their names.
struct Target {
    std::int64_t bits = 0;
    std::string name;
};

// Every target this binary has code for, best first.
std::vector<Target> compiled();
// The compiled targets this CPU can run, best first (never empty: the portable target runs anywhere).
std::vector<Target> runnable();
// The target the kernels dispatch to now: the pinned one, or the best runnable one.
std::string chosen();
// "simd: avx3 (compiled: avx3, avx2, sse4, scalar)", the line `splatffd --version` prints.
std::string version_line();

// Pins the kernels to one compiled target the CPU runs ("scalar": the portable one, the last compiled).
// Refuses an unknown name or one this CPU cannot run; the message lists what it can run.
Status pin(std::string_view name);
// Back to the best runnable target.
void unpin();

// SFFD_SIMD, checked: unset or empty is fine; otherwise pin()'s refusal, naming the variable.
Status pin_from_environment();
// Applies SFFD_SIMD once per process (the kernels call it before they dispatch, so benchmarks and tests
// honour the variable too); a bad value is left for the command's start-up check to refuse.
void honour_environment();

// Pins a target for a scope (tests): the previous pin comes back on destruction.
class ScopedTarget {
public:
    explicit ScopedTarget(const Target& t);
    ~ScopedTarget();
    ScopedTarget(const ScopedTarget&) = delete;
    ScopedTarget& operator=(const ScopedTarget&) = delete;

private:
    std::int64_t m_previous = 0;
};

}  // namespace sffd::simd
