// Profile reports: statistics over recorded frames, and the files the `splatffd profile` command writes.
//
// The JSON layout is documented by systems/profiling/profile.schema.json (JSON Schema draft 2020-12
// subset; the tests validate every report against it). Times are milliseconds throughout.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "runtime/core/result.h"
#include "systems/profiling/profiler.h"

namespace sffd::profiling {

// Order statistics of one series (linear interpolation between closest ranks).
struct Stats {
    std::size_t n = 0;
    double min = 0.0, mean = 0.0, p50 = 0.0, p95 = 0.0, p99 = 0.0, max = 0.0;
};
Stats compute_stats(std::vector<double> values);

struct MachineInfo {
    std::string cpu;          // /proc/cpuinfo "model name"
    unsigned cores = 0;       // std::thread::hardware_concurrency()
    std::string os;           // uname sysname + release
    std::string gl_renderer;  // empty without a GL context
    std::string gl_version;
};
// Reads the CPU model and core count; GL strings only when `with_gl` (a context must be current).
MachineInfo machine_info(bool with_gl);

using ConfigValue = std::variant<std::string, double, bool>;
using Config = std::vector<std::pair<std::string, ConfigValue>>;

// One row per system, phase or pass name. Times are summed per frame (a pass issued once per cloud
// counts once per frame with the total), then summarised over frames.
struct TimingRow {
    std::string name;
    std::string phase;
    std::string system;  // passes: the issuing system ("" outside systems)
    double calls_per_frame = 0.0;
    Stats cpu_ms;
    std::optional<Stats> gpu_ms;  // passes (and systems with passes) when GPU times were measured
};

struct ProfileReport {
    Config config;
    MachineInfo machine;
    std::string gpu_timing;  // "queries", "sync" or "none"
    Stats frame_ms;
    double fps_mean = 0.0;  // frames / summed frame time
    double fps_p50 = 0.0;   // 1000 / median frame time
    std::vector<TimingRow> phases;
    std::vector<TimingRow> systems;
    std::vector<TimingRow> passes;
};

ProfileReport build_report(const Profiler& profiler, Config config, MachineInfo machine);

std::string to_json(const ProfileReport& report);
// Parses a report written by to_json (for --compare). `path` only names the source in errors.
Result<ProfileReport> report_from_json(const std::string& text, const std::string& path);

// Human-readable summary table.
std::string to_text(const ProfileReport& report);
// One row per frame: frame, frame_ms, then one column per phase, system and pass (cpu, gpu).
std::string to_csv(const Profiler& profiler);
// Chrome trace-event JSON (chrome://tracing, ui.perfetto.dev): complete ("X") events, CPU scopes on
// thread 1, GPU pass times on thread 2, one after another in submission order: each starts at its pass's
// CPU start or where the one before ended (the GPU clock is not aligned; args.issued_ms keeps the CPU
// start), so no two slices of a track overlap.
std::string to_chrome_trace(const Profiler& profiler, const std::string& process_name);
// Frame-time chart: total per frame and each phase, in ms.
std::string frame_svg(const Profiler& profiler, const std::string& title);

// --compare: a row regressed when its median grew by more than the measured spread:
//   cur.p50 - base.p50 > max(base.p95 - base.p50, cur.p95 - cur.p50, floor_ms, floor_rel * base.p50).
// The floors keep constant-time rows (spread 0) from flagging scheduler jitter.
struct Regression {
    std::string kind;  // "frame", "system", "pass"
    std::string name;
    std::string metric;  // "cpu_ms" or "gpu_ms"
    double base_p50 = 0.0, current_p50 = 0.0, threshold = 0.0;
    bool slower = false;
};
struct CompareOptions {
    double floor_ms = 0.05;
    double floor_rel = 0.05;
};
std::vector<Regression> compare_reports(const ProfileReport& base, const ProfileReport& current,
                                        CompareOptions options = {});
std::string to_text(const std::vector<Regression>& rows);

}  // namespace sffd::profiling
