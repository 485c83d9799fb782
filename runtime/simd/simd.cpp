// Compiled once per target, like every kernel: DispatchedTarget below is how the kernels' dispatch
// itself reports the target it picks.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "runtime/simd/simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace sffd::simd::HWY_NAMESPACE {
std::int64_t DispatchedTarget() { return HWY_TARGET; }
}  // namespace sffd::simd::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <mutex>

#include <hwy/targets.h>

#include "runtime/simd/simd.h"

namespace sffd::simd {

HWY_EXPORT(DispatchedTarget);

namespace {

// The pinned target's bits, 0 when none (Highway's own mock holds the same; this copy lets a scope
// restore what it replaced).
std::atomic<std::int64_t> g_pinned{0};

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::vector<Target> targets_in(std::int64_t mask) {
    std::vector<Target> out;
    // Highway numbers better targets with lower bits.
    for (std::int64_t m = mask; m != 0; m &= m - 1) {
        const std::int64_t bit = m & -m;
        out.push_back({bit, lower(hwy::TargetName(bit))});
    }
    return out;
}

// What the CPU runs, whatever is pinned: the pin is Highway's test mock, so lift it for the question.
std::int64_t cpu_targets() {
    const std::int64_t pinned = g_pinned.load();
    if (pinned == 0) return hwy::SupportedTargets();
    hwy::SetSupportedTargetsForTest(0);
    const std::int64_t cpu = hwy::SupportedTargets();
    hwy::SetSupportedTargetsForTest(pinned);
    return cpu;
}

void set_pin(std::int64_t bits) {
    g_pinned = bits;
    // Also resets the dispatch tables' chosen target, so the next HWY_DYNAMIC_DISPATCH picks again.
    hwy::SetSupportedTargetsForTest(bits);
}

std::string join(const std::vector<Target>& ts) {
    std::string s;
    for (const Target& t : ts) s += (s.empty() ? "" : ", ") + t.name;
    return s;
}

}  // namespace

std::vector<Target> compiled() { return targets_in(HWY_TARGETS); }

std::vector<Target> runnable() { return targets_in(cpu_targets() & HWY_TARGETS); }

std::string chosen() { return lower(hwy::TargetName(HWY_DYNAMIC_DISPATCH(DispatchedTarget)())); }

std::string version_line() { return "simd: " + chosen() + " (compiled: " + join(compiled()) + ")"; }

Status pin(std::string_view name) {
    // "scalar" names the portable target whichever Highway builds: emu128, or scalar itself with GCC before
    // 12.3 (whose emu128 code Highway avoids).
    std::string want = lower(std::string(name));
    if (want == "scalar") want = compiled().back().name;
    for (const Target& t : runnable())
        if (t.name == want) {
            set_pin(t.bits);
            return {};
        }
    bool known = false;
    for (const Target& t : compiled()) known |= t.name == want;
    return make_error(
        "SIMD target '" + std::string(name) + "' " +
        (known ? "is compiled in but this CPU cannot run it" : "is not compiled into this binary") +
        "; this CPU runs: " + join(runnable()) +
        (compiled().back().name == "scalar" ? "" : " (or scalar, the portable one)"));
}

void unpin() { set_pin(0); }

Status pin_from_environment() {
    const char* v = std::getenv("SFFD_SIMD");
    if (v == nullptr || *v == '\0') return {};
    if (Status st = pin(v); !st) return make_error("SFFD_SIMD: " + st.message());
    return {};
}

void honour_environment() {
    static std::once_flag once;
    std::call_once(once, [] { (void)pin_from_environment(); });
}

ScopedTarget::ScopedTarget(const Target& t) {
    honour_environment();  // first, so a later first kernel call does not re-apply SFFD_SIMD over this scope
    m_previous = g_pinned.load();
    set_pin(t.bits);
}
ScopedTarget::~ScopedTarget() { set_pin(m_previous); }

}  // namespace sffd::simd

#endif  // HWY_ONCE
