// ProfileOverlay: registry resource with live profiling data for the editor's overlay (frame-time graph,
// per-system bars). Written by the profiler at the end of every frame (systems/profiling/profiler.h);
// the editor only reads it. Plain data, header only: the editor needs no link dependency to draw it.
//
//   if (const auto* o = registry.try_resource<profiling::ProfileOverlay>()) {
//       ImGui::PlotLines("frame ms", o->frame_ms.data(), int(o->count), int(o->oldest()), nullptr,
//                        0.0f, o->max_ms, ImVec2(0, 60));
//       for (const auto& s : o->systems) ImGui::ProgressBar(s.avg_ms / o->frame_avg_ms, {}, s.name.c_str());
//   }
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace sffd::profiling {

struct ProfileOverlay {
    static constexpr std::size_t history = 240;  // frames kept in the graph (4 s at 60 Hz)

    // Ring buffer of whole-frame wall times in ms: the newest is at (head + history - 1) % history;
    // `count` grows to `history`. oldest() is the values_offset for ImGui::PlotLines.
    std::array<float, history> frame_ms{};
    std::size_t head = 0;  // next slot to write
    std::size_t count = 0;
    float max_ms = 0.0f;        // largest value in the ring (graph scale)
    float frame_avg_ms = 0.0f;  // mean over the ring
    float frame_last_ms = 0.0f;

    std::size_t oldest() const { return count < history ? 0 : head; }

    // One row per system and per named GPU pass. avg is an exponential moving average (alpha 0.05,
    // about the last 20 frames). gpu_* are -1 when the pass has no GPU time (yet: queries arrive a few
    // frames late, or no GL context).
    struct Entry {
        std::string name;   // system name, or pass name ("hq.visibility")
        std::string phase;  // phase of the system (or of the system that issued the pass)
        float last_ms = 0.0f;
        float avg_ms = 0.0f;
        float gpu_last_ms = -1.0f;
        float gpu_avg_ms = -1.0f;
    };
    std::vector<Entry> systems;
    std::vector<Entry> passes;
    std::string gpu_method;  // "queries", "sync" or "none": how gpu_* were measured
};

}  // namespace sffd::profiling
