#include "runtime/core/log.h"

#include <atomic>
#include <cstdio>

namespace sffd::log {
namespace {

std::mutex g_mutex;
Sink g_sink;
std::atomic<Level> g_min_level{Level::info};

void default_sink(Level level, std::string_view message) {
    std::fprintf(stderr, "[%s] %.*s\n", level_name(level), static_cast<int>(message.size()), message.data());
}

}  // namespace

const char* level_name(Level level) {
    switch (level) {
        case Level::debug: return "debug";
        case Level::info: return "info";
        case Level::warn: return "warn";
        case Level::error: return "error";
    }
    return "?";
}

Sink set_sink(Sink sink) {
    std::lock_guard lock(g_mutex);
    Sink previous = std::move(g_sink);
    g_sink = std::move(sink);
    return previous;
}

void set_min_level(Level level) { g_min_level = level; }
Level min_level() { return g_min_level; }

void write(Level level, std::string_view message) {
    if (level < g_min_level) return;
    std::lock_guard lock(g_mutex);
    if (g_sink) g_sink(level, message);
    else default_sink(level, message);
}

ScopedLogCapture::ScopedLogCapture() : m_previous_level(min_level()) {
    set_min_level(Level::debug);
    m_previous = set_sink([this](Level level, std::string_view message) {
        std::lock_guard lock(m_mutex);
        m_entries.push_back({level, std::string(message)});
    });
}

ScopedLogCapture::~ScopedLogCapture() {
    set_sink(std::move(m_previous));
    set_min_level(m_previous_level);
}

std::vector<ScopedLogCapture::Entry> ScopedLogCapture::entries() const {
    std::lock_guard lock(m_mutex);
    return m_entries;
}

bool ScopedLogCapture::contains(std::string_view needle) const {
    std::lock_guard lock(m_mutex);
    for (const Entry& e : m_entries)
        if (e.message.find(needle) != std::string::npos) return true;
    return false;
}

}  // namespace sffd::log
