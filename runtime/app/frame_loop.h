// The frame. Phases run in this order, every frame, and this enum is the only place the order is
// written (flecs-style named phases; EnTT testbed's application::draw()):
//
//   input       window events, replayed input files, editor tools -> edit commands on lattices
//   animation   clips evaluate at the frame time and write lattice control points from the rest lattice
//   residency   authored clouds whose change stamp moved are uploaded to the GPU stores, once, by one
//               function per kind (the stores and their per-cloud state have this one owner)
//   deformation point clouds whose rest data or lattices changed are re-deformed (GPU compute or CPU,
//               whose output is uploaded); writes the deformed buffers and their state
//   picking     only when a pick was requested: refresh the ray-casting scene, cast, store the hit
//   rendering   culling, splat passes, shading, overlays, UI, frame capture
//   present     sRGB display pass into the window (after every overlay), window UI, swap; or read back
//               and write files when headless
//
// Systems are free functions `void system(ecs::Registry&, const FrameContext&)`; a Schedule holds them
// per phase in registration order, each with the components and resources it declares it reads and
// writes (ecs::reads<...>().writes<...>(), runtime/ecs/access.h). While a system runs its declaration is
// the registry's active access, which builds with SFFD_CHECK_ACCESS enforce. Deferred structural
// changes are flushed after every phase.
// A FrameObserver sees every system and phase start and end (the profiling harness times from outside).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/ecs/registry.h"

namespace sffd {

enum class Phase : std::uint8_t { input, animation, residency, deformation, picking, rendering, present };
inline constexpr std::size_t phase_count = 7;
const char* phase_name(Phase phase);

// Per-frame timing handed to every system.
struct FrameContext {
    std::uint64_t frame = 0;  // index of this frame, 0-based
    double time = 0.0;        // seconds of clock time at this frame (paused time does not advance)
    double dt = 0.0;          // seconds since the previous frame (0 when paused)
};

using SystemFn = std::function<void(ecs::Registry&, const FrameContext&)>;

// Observer for instrumentation; all callbacks optional.
struct FrameObserver {
    std::function<void(const FrameContext&)> frame_begin;
    std::function<void(const FrameContext&)> frame_end;
    std::function<void(Phase)> phase_begin;
    std::function<void(Phase)> phase_end;
    std::function<void(Phase, std::string_view system)> system_begin;
    std::function<void(Phase, std::string_view system)> system_end;
};

class Schedule {
public:
    // `access` is what the system reads and writes; a default (undeclared) Access is not checked, for
    // ad hoc schedules in tests; the engine's schedule declares every system.
    void add(Phase phase, std::string name, SystemFn fn, ecs::Access access = {});
    // Runs every phase in order; flushes the registry's deferred commands after each phase.
    void run_frame(ecs::Registry& registry, const FrameContext& frame) const;
    void set_observer(FrameObserver observer) { m_observer = std::move(observer); }

    struct Entry {
        std::string name;
        SystemFn fn;
        ecs::Access access;
    };
    const std::vector<Entry>& systems(Phase phase) const { return m_phases[static_cast<std::size_t>(phase)]; }

private:
    std::array<std::vector<Entry>, phase_count> m_phases;
    FrameObserver m_observer;
};

}  // namespace sffd
