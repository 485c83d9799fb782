// The deformation backend choice and the lazily created GPU deformer that ffd_system and systems/gaussian's
// gaussian_deform_system share (one rule for both kinds of cloud, written once).
#pragma once

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>

#include "runtime/core/log.h"
#include "runtime/ecs/registry.h"

namespace sffd {
struct FfdSettings;
}

namespace sffd::ffd {

// This frame's backend: GPU when a GL context is current on this thread, except on a software rasterizer
// (llvmpipe runs the "GPU" on the same CPU cores, slower than the TBB path) unless FfdSettings::force_gpu;
// never with FfdSettings::force_cpu. `settings` may be null (defaults).
struct DeformBackend {
    bool have_gl = false;    // a GL context (EGL or GLFW) is current on this thread
    bool force_cpu = false;  // deform on the CPU even though GL is there
    bool gpu() const { return have_gl && !force_cpu; }
};
DeformBackend choose_deform_backend(const FfdSettings* settings);

// A system's GPU deformer, created on first use (a registry resource, so its GL objects live as long as
// the registry's), and the statistics read-backs in flight (queue_stats tag -> the output they were
// counted for). `Deformer` is ffd::GpuDeformer or gaussian::GpuGaussianDeformer.
template <class Deformer>
struct GpuDeformerState {
    std::optional<Deformer> deformer;
    bool unavailable = false;  // compile failed once: stay on the CPU path
    struct Pending {
        ecs::Entity cloud;
        std::uint64_t version = 0;
    };
    std::unordered_map<std::uint64_t, Pending> pending;
    std::uint64_t next_tag = 1;

    // Queues the statistics of the output `version` of `cloud` (collected a few frames later by
    // collect(); nothing waits for them): `where` names them as the deformer's queue_stats() takes it (the
    // cloud's per-page counters).
    template <class... Where>
    void queue_stats(Deformer& gpu, ecs::Entity cloud, std::uint64_t version, Where&&... where) {
        const std::uint64_t tag = next_tag++;
        if (gpu.queue_stats(tag, std::forward<Where>(where)...)) pending[tag] = {cloud, version};
    }
    // Hands each read-back that has arrived (never waits) to apply(const Pending&, const Stats&).
    template <class Apply>
    void collect(Apply&& apply) {
        if (!deformer || pending.empty()) return;
        for (const auto& t : deformer->poll_stats()) {
            auto it = pending.find(t.tag);
            if (it == pending.end()) continue;
            const Pending p = it->second;
            pending.erase(it);
            apply(p, t.stats);
        }
    }
};

// The registry's deformer of this kind, created on first use; null (and a warning naming `system`, once)
// when it cannot be created: the caller stays on the CPU path.
template <class Deformer>
Deformer* gpu_deformer(ecs::Registry& reg, const char* system) {
    auto* st = reg.try_resource<GpuDeformerState<Deformer>>();
    if (!st) st = &reg.set_resource<GpuDeformerState<Deformer>>();
    if (st->unavailable) return nullptr;
    if (!st->deformer) {
        auto d = Deformer::create();
        if (!d) {
            log::warn(system, ": GPU path unavailable, deforming on the CPU (", d.message(), ")");
            st->unavailable = true;
            return nullptr;
        }
        st->deformer.emplace(std::move(*d));
    }
    return &*st->deformer;
}

}  // namespace sffd::ffd
