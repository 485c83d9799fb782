#include "runtime/gfx/barrier.h"

#include <cassert>
#include <cstdio>
#include <string_view>

#include "runtime/gfx/gl.h"

namespace sffd::gfx {

namespace {
thread_local BarrierLog* t_log = nullptr;
}

void memory_barrier(std::uint32_t bits, const char* site) {
    assert(bits != 0 && site != nullptr);
    glMemoryBarrier(GLbitfield(bits));
    if (t_log) t_log->m_records.push_back({bits, site});
}

BarrierLog::BarrierLog() {
    assert(!t_log && "one BarrierLog per thread at a time");
    t_log = this;
}

BarrierLog::~BarrierLog() { t_log = nullptr; }

std::uint32_t BarrierLog::bits_at(std::string_view site) const {
    std::uint32_t bits = 0;
    for (const BarrierRecord& r : m_records)
        if (r.site == site) bits |= r.bits;
    return bits;
}

bool BarrierLog::issued(std::string_view site, std::uint32_t bits) const {
    for (const BarrierRecord& r : m_records)
        if (r.site == site && (r.bits & bits) == bits) return true;
    return false;
}

std::size_t BarrierLog::count(std::string_view site) const {
    std::size_t n = 0;
    for (const BarrierRecord& r : m_records) n += r.site == site ? 1 : 0;
    return n;
}

std::string barrier_bit_names(std::uint32_t bits) {
    static constexpr struct {
        std::uint32_t bit;
        const char* name;
    } names[] = {
        {GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT, "VERTEX_ATTRIB_ARRAY"},
        {GL_ELEMENT_ARRAY_BARRIER_BIT, "ELEMENT_ARRAY"},
        {GL_UNIFORM_BARRIER_BIT, "UNIFORM"},
        {GL_TEXTURE_FETCH_BARRIER_BIT, "TEXTURE_FETCH"},
        {GL_SHADER_IMAGE_ACCESS_BARRIER_BIT, "SHADER_IMAGE_ACCESS"},
        {GL_COMMAND_BARRIER_BIT, "COMMAND"},
        {GL_PIXEL_BUFFER_BARRIER_BIT, "PIXEL_BUFFER"},
        {GL_TEXTURE_UPDATE_BARRIER_BIT, "TEXTURE_UPDATE"},
        {GL_BUFFER_UPDATE_BARRIER_BIT, "BUFFER_UPDATE"},
        {GL_FRAMEBUFFER_BARRIER_BIT, "FRAMEBUFFER"},
        {GL_TRANSFORM_FEEDBACK_BARRIER_BIT, "TRANSFORM_FEEDBACK"},
        {GL_ATOMIC_COUNTER_BARRIER_BIT, "ATOMIC_COUNTER"},
        {GL_SHADER_STORAGE_BARRIER_BIT, "SHADER_STORAGE"},
        {GL_CLIENT_MAPPED_BUFFER_BARRIER_BIT, "CLIENT_MAPPED_BUFFER"},
        {GL_QUERY_BUFFER_BARRIER_BIT, "QUERY_BUFFER"},
    };
    std::string out;
    for (const auto& n : names) {
        if (!(bits & n.bit)) continue;
        if (!out.empty()) out += '|';
        out += n.name;
        bits &= ~n.bit;
    }
    if (bits) {  // bits without a name above
        char hex[16];
        std::snprintf(hex, sizeof hex, "0x%x", unsigned(bits));
        if (!out.empty()) out += '|';
        out += hex;
    }
    return out;
}

}  // namespace sffd::gfx
