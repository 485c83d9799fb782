#include "runtime/app/clock.h"

#include <algorithm>
#include <cmath>

namespace sffd {

Clock::Clock(ClockSettings settings) : m_settings(settings), m_time(settings.start_time) {}

void Clock::seek(double time) {
    if (m_settings.fixed_dt > 0.0) {
        const double steps = std::max(0.0, std::round((time - m_settings.start_time) / m_settings.fixed_dt));
        m_steps = static_cast<std::uint64_t>(steps);
        m_time = m_settings.start_time + double(m_steps) * m_settings.fixed_dt;
    } else {
        m_time = time;
    }
}

FrameContext Clock::tick() {
    const auto now = std::chrono::steady_clock::now();
    double elapsed = 0.0;
    if (m_started) elapsed = std::chrono::duration<double>(now - m_last).count();
    m_started = true;
    m_last = now;
    return tick(elapsed);
}

FrameContext Clock::tick(double elapsed_seconds) {
    // Frame 0 shows the start time; later frames advance unless paused (a pending step advances once).
    const bool advance = m_frame > 0 && (!m_paused || m_step_pending);
    m_step_pending = false;
    const double previous = m_time;
    if (advance) {
        if (m_settings.fixed_dt > 0.0) {
            // Multiply, never accumulate: frame k of a sequence has exactly the time of frame k alone.
            ++m_steps;
            m_time = m_settings.start_time + double(m_steps) * m_settings.fixed_dt;
        } else {
            m_time += m_paused ? 1.0 / 60.0 : std::clamp(elapsed_seconds, 0.0, m_settings.max_dt);
        }
    }
    FrameContext ctx{m_frame, m_time, m_time - previous};
    ++m_frame;
    return ctx;
}

}  // namespace sffd
