// The one way the engine issues glMemoryBarrier: gfx::memory_barrier(bits, why).
//
// GL 4.5 §7.12.2 leaves shader-storage writes (SSBOs, atomics, images) unordered against every later use
// until a barrier names how that later use reads or writes the memory. llvmpipe finishes each command
// before the next, so a missing bit never shows here; on a hardware GPU it draws stale data. Routing every
// barrier through one function lets tests record the bits each pass issues and assert the ones the spec
// requires (tests/runtime/barrier_test.cpp, tests/systems/splat_render/barrier_pass_test.cpp):
//
//   gfx::BarrierLog log;                      // records on this thread while alive
//   ... run a pass ...
//   EXPECT_TRUE(log.issued("render.cull", GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT));
//
// Which bit for which later use (the subsequent access, not the shader write, picks the bit):
//   vertex attributes fetched from the buffer      VERTEX_ATTRIB_ARRAY
//   index buffer of indexed draws                  ELEMENT_ARRAY
//   indirect draw or dispatch commands             COMMAND
//   copies, clears, sub-data reads and writes      BUFFER_UPDATE
//   SSBO reads, and any later write (SSBO, atomic) that must wait for earlier reads (write-after-read
//   across frames: the next frame's overwrite of a buffer this frame's draws read)   SHADER_STORAGE
//
// `site` names the pass ("render.cull", "ffd.dispatch"...); tests look barriers up by it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace sffd::gfx {

// Issues glMemoryBarrier(bits) and records it in this thread's BarrierLog, when one is alive.
void memory_barrier(std::uint32_t bits, const char* site);

struct BarrierRecord {
    std::uint32_t bits = 0;
    std::string site;
};

// Records every memory_barrier() on the constructing thread while it lives (tests). Nesting is not
// supported: one log per thread at a time.
class BarrierLog {
public:
    BarrierLog();
    ~BarrierLog();
    BarrierLog(const BarrierLog&) = delete;
    BarrierLog& operator=(const BarrierLog&) = delete;

    const std::vector<BarrierRecord>& records() const { return m_records; }
    // The OR of the bits of every barrier recorded at `site`.
    std::uint32_t bits_at(std::string_view site) const;
    // Whether a barrier at `site` included every bit of `bits`.
    bool issued(std::string_view site, std::uint32_t bits) const;
    std::size_t count(std::string_view site) const;
    void clear() { m_records.clear(); }

private:
    friend void memory_barrier(std::uint32_t, const char*);
    std::vector<BarrierRecord> m_records;
};

// "SHADER_STORAGE|COMMAND" for messages and test failures.
std::string barrier_bit_names(std::uint32_t bits);

}  // namespace sffd::gfx
