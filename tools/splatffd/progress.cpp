#include "tools/splatffd/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sffd::cli {

ProgressPrinter::Mode ProgressPrinter::mode_for(bool forced) {
    if (forced) return Mode::lines;
    return isatty(STDERR_FILENO) ? Mode::terminal : Mode::quiet;
}

ProgressPrinter::ProgressPrinter(std::string command, Mode mode)
    : m_command(std::move(command)), m_mode(mode), m_start(Clock::now()) {}

ProgressFn ProgressPrinter::fn() {
    return [this](std::string_view step, double fraction) { report(step, fraction); };
}

void ProgressPrinter::close_step(Clock::time_point now, bool finished) {
    if (m_step.empty()) return;
    const double seconds = std::chrono::duration<double>(now - m_step_start).count();
    if (finished && m_mode == Mode::lines)
        std::fprintf(stderr, "%s: %s: 100%% in %.2f s\n", m_command.c_str(), m_step.c_str(), seconds);
    if (m_line_open)
        std::fprintf(stderr, "\r\033[K%s: %s: %s in %.2f s\n", m_command.c_str(), m_step.c_str(),
                     finished ? "100%" : "stopped", seconds);
    m_line_open = false;
    m_times.emplace_back(m_step, seconds);
    m_step.clear();
}

void ProgressPrinter::report(std::string_view step, double fraction) {
    std::lock_guard lock(m_mutex);
    const Clock::time_point now = Clock::now();
    if (step != m_step) {
        close_step(now, false);
        m_step = std::string(step);
        m_step_start = m_last_draw = now;
        m_last_decile = -1;
    }
    fraction = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
    if (fraction >= 1.0) {
        close_step(now, true);
        return;
    }
    const int percent = static_cast<int>(fraction * 100.0);
    if (m_mode == Mode::lines) {
        if (percent / 10 > m_last_decile) {
            m_last_decile = percent / 10;
            std::fprintf(stderr, "%s: %s: %d%%\n", m_command.c_str(), m_step.c_str(), percent);
        }
    } else if (m_mode == Mode::terminal) {
        // Only steps that run over a second, redrawn at most five times a second.
        if (now - m_step_start >= std::chrono::seconds(1) &&
            (!m_line_open || now - m_last_draw >= std::chrono::milliseconds(200))) {
            std::fprintf(stderr, "\r\033[K%s: %s: %d%% (%.0f s)", m_command.c_str(), m_step.c_str(), percent,
                         std::chrono::duration<double>(now - m_step_start).count());
            std::fflush(stderr);
            m_line_open = true;
            m_last_draw = now;
        }
    }
}

void ProgressPrinter::summary() {
    std::lock_guard lock(m_mutex);
    const Clock::time_point now = Clock::now();
    close_step(now, false);
    std::string steps;
    for (const auto& [name, seconds] : m_times) {
        char buf[64];
        std::snprintf(buf, sizeof buf, " %.2f s", seconds);
        steps += (steps.empty() ? ": " : ", ") + name + buf;
    }
    std::fprintf(stderr, "%s: done in %.2f s%s\n", m_command.c_str(),
                 std::chrono::duration<double>(now - m_start).count(), steps.c_str());
}

}  // namespace sffd::cli
