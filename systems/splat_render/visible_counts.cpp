// Splat render system: the visible counts' read-back ring (never waits on the GPU).
#include "systems/splat_render/splat_render_detail.h"

namespace sffd::render::detail {

namespace {

// The ring that brings the compute cull's visible counts back without waiting: each frame copies the draw
// commands of its compute-culled clouds into one slot of a persistently mapped buffer and fences it; a later
// frame reads the slot once glClientWaitSync(fence, 0 timeout) says the copies landed.
void ensure_counts_ring(SplatRenderState& s, std::size_t clouds) {
    if (s.counts_ring && s.counts_ring_clouds >= clouds) return;
    for (CountsSlot& slot : s.counts_slots) slot = CountsSlot{};  // in flight into the old ring: dropped
    s.counts_ring_clouds = std::max<std::size_t>(clouds, 4);
    const auto bytes = GLsizeiptr(SplatRenderState::counts_slot_count * s.counts_ring_clouds *
                                  counts_entry_words * sizeof(std::uint32_t));
    const GLbitfield map = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    s.counts_ring = gfx::Buffer::create("render.visible_counts");
    glNamedBufferStorage(s.counts_ring.id(), bytes, nullptr, map | GL_CLIENT_STORAGE_BIT);
    s.counts_mapped =
        static_cast<const std::uint32_t*>(glMapNamedBufferRange(s.counts_ring.id(), 0, bytes, map));
}

}  // namespace

// Frees every slot whose fence has signalled (a zero-timeout poll) and keeps the newest one's counts.
void collect_counts(SplatRenderState& s) {
    for (std::size_t i = 0; i < s.counts_slots.size(); ++i) {
        CountsSlot& slot = s.counts_slots[i];
        if (!slot.fence) continue;
        const GLenum state = glClientWaitSync(slot.fence.get(), 0, 0);
        if (state != GL_ALREADY_SIGNALED && state != GL_CONDITION_SATISFIED) continue;
        slot.fence.reset();
        if (slot.serial <= s.counts_serial || !s.counts_mapped) continue;
        std::uint32_t points = slot.cpu_points, quads = slot.cpu_quads, big = 0;
        const std::uint32_t* p = s.counts_mapped + i * s.counts_ring_clouds * counts_entry_words;
        for (std::uint32_t c = 0; c < slot.gpu_clouds; ++c) {
            const std::uint32_t* commands = p + c * counts_entry_words;
            if (slot.parts[c] & counts_cull) {
                points += commands[0] + commands[8];  // sprites + flat-coloured sprites
                quads += commands[5];
            }
            if (slot.parts[c] & counts_big)
                big += commands[draw_command_words] + commands[draw_command_words + 5];
        }
        s.counts_serial = slot.serial, s.counts_frame = slot.frame;
        s.counts_points = points, s.counts_quads = quads, s.counts_raster_sprites = big;
    }
}

// Copies this frame's GPU-side draw commands into a free slot of the ring and fences it. With every slot
// still in flight this frame's counts are not taken (never waited for). Dropping the oldest slot instead
// starved the ring: a headless loop with no swap to hold it back ran more than four frames ahead of an
// NVIDIA H200, so each slot was overwritten before its fence signalled and no counts ever came back.
void issue_counts(SplatRenderState& s, const std::vector<CountsSource>& computed, std::uint32_t cpu_points,
                  std::uint32_t cpu_quads, std::uint64_t frame) {
    ensure_counts_ring(s, computed.size());
    const auto free_slot = std::find_if(s.counts_slots.begin(), s.counts_slots.end(),
                                        [](const CountsSlot& slot) { return !slot.fence; });
    if (free_slot == s.counts_slots.end()) return;
    const auto at = std::size_t(free_slot - s.counts_slots.begin());
    CountsSlot& slot = *free_slot;
    slot.parts.assign(computed.size(), 0);
    // The copies read counters that shader atomics wrote (cull.comp, compute_visibility.comp).
    if (!computed.empty()) gfx::memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT, "render.counts");
    for (std::size_t c = 0; c < computed.size(); ++c) {
        const GLintptr entry =
            GLintptr((at * s.counts_ring_clouds + c) * counts_entry_words * sizeof(std::uint32_t));
        if (computed[c].parts & counts_cull)
            glCopyNamedBufferSubData(computed[c].gpu->commands.id(), s.counts_ring.id(), 0, entry,
                                     draw_command_words * sizeof(std::uint32_t));
        if (computed[c].parts & counts_big)
            glCopyNamedBufferSubData(computed[c].gpu->raster.commands.id(), s.counts_ring.id(), 0,
                                     entry + GLintptr(draw_command_words * sizeof(std::uint32_t)),
                                     10 * sizeof(std::uint32_t));
        slot.parts[c] = computed[c].parts;
    }
    slot.fence = Fence(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
    glFlush();  // a fence signals only once submitted; polls never flush (a headless run has no swap)
    slot.serial = ++s.counts_issued, slot.frame = frame;
    slot.cpu_points = cpu_points, slot.cpu_quads = cpu_quads;
    slot.gpu_clouds = std::uint32_t(computed.size());
}

}  // namespace sffd::render::detail
