// Progress of long library steps (surface sampling, neighbour searches), reported to whoever shows it:
// `splatffd convert` prints it (tools/splatffd/progress.h), everything else passes an empty function.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

namespace sffd {

// `step` names the step ("sampling the surface"); `fraction` is in [0, 1] and 1 ends the step. Parallel
// loops report from their worker threads, so a reporter must be thread-safe. May be empty.
using ProgressFn = std::function<void(std::string_view step, double fraction)>;

inline void report_progress(const ProgressFn& fn, std::string_view step, double fraction) {
    if (fn) fn(step, fraction);
}

// Counts the items of one step (from any thread) and reports at each further 1 % (at most ~100 calls).
// Reports 0 when made and 1 on done().
class ProgressCounter {
public:
    ProgressCounter(const ProgressFn& fn, std::string_view step, std::size_t total)
        : m_fn(fn), m_step(step), m_total(total == 0 ? 1 : total) {
        report_progress(m_fn, m_step, 0.0);
    }
    void add(std::size_t items) {
        if (!m_fn) return;
        const std::size_t before = m_done.fetch_add(items, std::memory_order_relaxed);
        const std::size_t after = before + items;
        if (after * 100 / m_total != before * 100 / m_total && after < m_total)
            m_fn(m_step, static_cast<double>(after) / static_cast<double>(m_total));
    }
    void done() { report_progress(m_fn, m_step, 1.0); }

private:
    const ProgressFn& m_fn;
    std::string m_step;
    std::size_t m_total;
    std::atomic<std::size_t> m_done{0};
};

}  // namespace sffd
