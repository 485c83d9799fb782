// Naming GPU passes for the profiler, without depending on it. Lives beside FrameObserver
// (frame_loop.h): both are hooks the runtime offers so that the profiling harness (systems/profiling)
// can time the frame from outside; systems include this header, never the profiler's.
//
// Systems that issue GL work (FFD compute, splat render passes) wrap each pass in a scope:
//
//   #include "runtime/app/pass_timer.h"
//   {
//       auto scope = profiling::gpu_scope(registry, "hq.visibility");
//       glDrawArrays(...);
//   }
//
// When no profiler is attached (no PassTimer resource) the scope is one failed resource lookup and
// nothing else. When the profiling harness runs (systems/profiling/profiler.h), it installs a PassTimer
// resource whose hooks time the pass on the CPU and on the GPU (timer queries read back a few frames
// later, or glFinish + CPU clock in --sync mode). This header is plain data + inline code: including it
// needs no link dependency on sffd_profiling and pulls in no GL header.
//
// Pass names must outlive the frame (string literals): the profiler keeps the pointer as a cache key.
// Scopes may nest ("hq" around "hq.visibility"); begin/end must pair on the same thread (the GL thread).
#pragma once

#include "runtime/ecs/registry.h"

namespace sffd::profiling {

// Registry resource installed by the profiler. Plain function pointers + an opaque owner so that
// systems see no profiler type.
struct PassTimer {
    void* owner = nullptr;
    void (*begin)(void* owner, const char* name) = nullptr;
    void (*end)(void* owner, const char* name) = nullptr;
};

class GpuScope {
public:
    GpuScope(ecs::Registry& registry, const char* name) : m_name(name) {
        if (PassTimer* t = registry.try_resource<PassTimer>(); t && t->begin) {
            m_timer = *t;
            m_timer.begin(m_timer.owner, m_name);
        }
    }
    ~GpuScope() {
        if (m_timer.end) m_timer.end(m_timer.owner, m_name);
    }
    GpuScope(const GpuScope&) = delete;
    GpuScope& operator=(const GpuScope&) = delete;

private:
    PassTimer m_timer{};
    const char* m_name;
};

// Guaranteed copy elision (C++17): `auto s = gpu_scope(reg, "ffd.compute");` constructs in place.
inline GpuScope gpu_scope(ecs::Registry& registry, const char* name) { return GpuScope(registry, name); }

}  // namespace sffd::profiling
