// Profiler: times every phase, system and named GPU pass of a Schedule from the outside.
//
//   profiling::Profiler profiler({.gpu = profiling::GpuTiming::queries});
//   profiler.attach(schedule, registry);   // FrameObserver + PassTimer + ProfileOverlay resources
//   for (...) schedule.run_frame(registry, clock.tick());
//   profiler.resolve_all();                // wait for the last GPU query results
//   auto report = profiling::build_report(profiler, config);
//
// CPU side: a steady_clock reading at each begin/end hook (two clock reads and one vector push per
// scope: cheap enough to leave on in the editor). GPU side, per pass (runtime/app/pass_timer.h):
//   - queries: a pair of GL_TIMESTAMP queries (glQueryCounter) per pass from a recycled pool, read back
//     >= `query_latency` frames later only once GL_QUERY_RESULT_AVAILABLE says so: never stalls.
//     Timestamps rather than GL_TIME_ELAPSED because passes nest ("hq" around "hq.visibility") and only
//     one TIME_ELAPSED query may be active at a time.
//   - sync: glFinish before and after each pass and each system, CPU clock in between. Stalls the
//     pipeline, so CPU times of surrounding code shift, but it is the only trustworthy method on Mesa
//     llvmpipe, whose timer queries report 0-1.6 ms for passes that take 67-95 ms.
//   - none: no GL calls at all (no context, or CPU-only runs).
// Frames in flight (queries mode, `max_frames_in_flight` > 0): a headless run has no swap chain, so nothing
// stops the CPU from queueing frames faster than the GPU runs them, and the driver then blocks in whichever
// GL call finds its queue full, charging the GPU's time to that system's CPU time (the deformation-only
// run's ffd system measured ~its GPU time as CPU time, growing with the cloud). The profiler paces such
// runs as a swap chain would: a fence at each frame's end, and each frame begins (before its clock starts)
// once no more than max - 1 earlier frames are unfinished.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"

// GLsync's pointee, as the GL headers declare it (this header includes none).
struct __GLsync;

namespace sffd::profiling {

enum class GpuTiming : std::uint8_t { none, queries, sync };
const char* gpu_timing_name(GpuTiming timing);

enum class ScopeKind : std::uint8_t { phase, system, pass };

inline constexpr std::uint32_t no_name = 0xffffffffu;

struct ScopeSample {
    std::uint32_t name = no_name;    // Profiler::name(id)
    std::uint32_t system = no_name;  // passes: the system that issued it (no_name outside systems)
    ScopeKind kind = ScopeKind::system;
    Phase phase = Phase::input;
    std::uint16_t depth = 0;  // passes: nesting level (0 = outermost)
    double begin_ms = 0.0;    // CPU clock, ms since the profiler was created
    double cpu_ms = 0.0;      // CPU wall time between begin and end hooks
    double gpu_ms = -1.0;     // passes: GPU time; -1 when unknown (method none, or not read yet)
};

struct FrameRecord {
    std::uint64_t frame = 0;
    double begin_ms = 0.0;
    double total_ms = 0.0;  // frame_begin to frame_end hooks
    std::vector<ScopeSample> scopes;
};

struct ProfilerSettings {
    GpuTiming gpu = GpuTiming::none;
    int query_latency = 3;         // frames before a query result is polled (never waited for)
    bool keep_frames = true;       // false: only the live overlay is updated (editor), no history kept
    int max_frames_in_flight = 0;  // queries mode: pace headless runs to this many frames (0: no pacing)
};

class Profiler {
public:
    explicit Profiler(ProfilerSettings settings = {});
    ~Profiler();  // queries mode: deletes its GL queries, so the context must still be current
    Profiler(const Profiler&) = delete;
    Profiler& operator=(const Profiler&) = delete;

    // Installs the Schedule's FrameObserver and the PassTimer and ProfileOverlay resources. The
    // profiler must outlive every run_frame() of the schedule while attached.
    void attach(Schedule& schedule, ecs::Registry& registry);
    void detach(Schedule& schedule, ecs::Registry& registry);

    // Blocks until every outstanding query has its result (end of a run, or before clear()).
    void resolve_all();
    // Drops recorded frames (after warm-up). Resolves outstanding queries first.
    void clear();

    // Pass hooks (what the PassTimer resource calls); usable directly for harness-level scopes.
    void pass_begin(const char* name);
    void pass_end(const char* name);

    const std::vector<FrameRecord>& frames() const { return m_frames; }
    const std::string& name(std::uint32_t id) const { return m_names[id]; }
    std::size_t name_count() const { return m_names.size(); }
    GpuTiming gpu_timing() const { return m_settings.gpu; }
    std::size_t pending_queries() const { return m_pending.size(); }
    // Earlier frames whose GL work may be unfinished (their fences not yet waited for); always 0 unpaced.
    std::size_t frames_in_flight() const { return m_frame_fences.size(); }

private:
    struct OpenPass {
        std::size_t sample = 0;
        std::uint32_t q_begin = 0, q_end = 0;  // pool indices (queries mode)
    };
    struct Pending {
        std::uint64_t frame = 0;
        std::size_t record = 0;  // index in m_frames (SIZE_MAX when frames are not kept)
        std::size_t sample = 0;
        std::uint32_t name = 0;
        std::uint32_t q_begin = 0, q_end = 0;
    };

    double now_ms() const;
    std::uint32_t intern(std::string_view name);
    std::uint32_t intern_pass(const char* name);
    FrameRecord& current();
    void on_frame_begin(const FrameContext& ctx);
    void on_frame_end(const FrameContext& ctx);
    void on_phase_begin(Phase phase);
    void on_phase_end(Phase phase);
    void on_system_begin(Phase phase, std::string_view system);
    void on_system_end(Phase phase, std::string_view system);
    std::uint32_t acquire_query();
    void poll_queries(bool wait);
    void pace_frames();
    void deliver_gpu(const Pending& p, double gpu_ms);
    void update_overlay(const FrameRecord& record);

    ProfilerSettings m_settings;
    std::chrono::steady_clock::time_point m_t0;
    ecs::Registry* m_registry = nullptr;

    std::vector<std::string> m_names;
    std::unordered_map<std::string, std::uint32_t> m_name_ids;
    std::unordered_map<const char*, std::uint32_t> m_pass_ids;  // pointer cache (content-checked)

    std::vector<FrameRecord> m_frames;
    FrameRecord m_scratch;  // the open frame when frames are not kept
    bool m_in_frame = false;
    std::uint64_t m_frame_no = 0;
    Phase m_phase = Phase::input;
    std::size_t m_phase_sample = 0;
    std::size_t m_system_sample = 0;
    std::uint32_t m_system = no_name;
    std::vector<OpenPass> m_open;

    // GL timestamp query pool (queries mode). Free list of indices; names created on demand.
    std::vector<std::uint32_t> m_query_names;
    std::vector<std::uint32_t> m_free_queries;
    std::vector<Pending> m_pending;
    std::vector<::__GLsync*> m_frame_fences;  // GLsync, oldest first (max_frames_in_flight)

    // Overlay bookkeeping: name id -> row in ProfileOverlay::systems / passes.
    std::unordered_map<std::uint32_t, std::size_t> m_overlay_system_rows, m_overlay_pass_rows;
};

}  // namespace sffd::profiling
