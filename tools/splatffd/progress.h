// Progress of a long command on stderr (`convert --splats 1000000` once ran 67 s without a word).
//   terminal  (stderr is a tty): a step running over a second gets one line, rewritten in place with its
//             percentage, ended with its time;
//   lines     (--progress): every step, one line at its start, one per further 10 %, one at its end
//             with its time (for logs, pipes and tests);
//   quiet     otherwise.
// The timing summary (`convert: done in 12.31 s: sampling the surface 0.52 s, ...`) is printed always.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "runtime/core/progress.h"

namespace sffd::cli {

class ProgressPrinter {
public:
    enum class Mode { quiet, terminal, lines };
    // lines when `forced` (--progress), terminal when stderr is a terminal, else quiet.
    static Mode mode_for(bool forced);

    ProgressPrinter(std::string command, Mode mode);
    ProgressPrinter(const ProgressPrinter&) = delete;
    ProgressPrinter& operator=(const ProgressPrinter&) = delete;

    // A reporter for library code (thread-safe; it refers to this printer, which must outlive it).
    ProgressFn fn();
    void report(std::string_view step, double fraction);
    // Closes the open step and prints the total time and each step's time.
    void summary();

private:
    using Clock = std::chrono::steady_clock;
    void close_step(Clock::time_point now, bool finished);

    std::mutex m_mutex;
    std::string m_command;
    Mode m_mode;
    Clock::time_point m_start;
    std::string m_step;  // the open step ("" when none)
    Clock::time_point m_step_start, m_last_draw;
    int m_last_decile = -1;
    bool m_line_open = false;  // terminal: a line without its newline is on screen
    std::vector<std::pair<std::string, double>> m_times;
};

}  // namespace sffd::cli
