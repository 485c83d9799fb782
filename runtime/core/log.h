// One logger with a pluggable sink. The default sink prints to stderr; tests install a capturing sink
// (ScopedLogCapture) and assert on the messages.
#pragma once

#include <functional>
#include <mutex>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace sffd::log {

enum class Level { debug, info, warn, error };

using Sink = std::function<void(Level, std::string_view)>;

// Replaces the sink; returns the previous one. An empty sink restores the default (stderr).
Sink set_sink(Sink sink);
void set_min_level(Level level);
Level min_level();
void write(Level level, std::string_view message);
const char* level_name(Level level);

// Concatenate anything streamable: log::info("loaded ", n, " points from ", path).
template <class... Args>
std::string str(const Args&... args) {
    std::ostringstream s;
    (s << ... << args);
    return s.str();
}

template <class... Args>
void debug(const Args&... a) {
    if (min_level() <= Level::debug) write(Level::debug, str(a...));
}
template <class... Args>
void info(const Args&... a) {
    if (min_level() <= Level::info) write(Level::info, str(a...));
}
template <class... Args>
void warn(const Args&... a) {
    write(Level::warn, str(a...));
}
template <class... Args>
void error(const Args&... a) {
    write(Level::error, str(a...));
}

// Captures every message while alive (thread-safe), then restores the previous sink.
class ScopedLogCapture {
public:
    struct Entry {
        Level level;
        std::string message;
    };
    ScopedLogCapture();
    ~ScopedLogCapture();
    ScopedLogCapture(const ScopedLogCapture&) = delete;
    ScopedLogCapture& operator=(const ScopedLogCapture&) = delete;

    std::vector<Entry> entries() const;
    bool contains(std::string_view needle) const;  // any message containing `needle`

private:
    mutable std::mutex m_mutex;
    std::vector<Entry> m_entries;
    Sink m_previous;
    Level m_previous_level;
};

}  // namespace sffd::log
