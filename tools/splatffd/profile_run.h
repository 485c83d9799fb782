// Shared by the `splatffd profile` files: one profiled run of the engine's schedule (profile_run.cpp),
// parameter sweeps (profile_sweep.cpp), the seed paper's table (profile_paper.cpp); the command itself
// (options, report output, --compare) is cmd_profile.cpp. Every run deforms through ffd_system, the
// engine's one deformation step; FfdSettings::force_cpu / force_gpu choose its path.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "systems/profiling/paper_ffd.h"
#include "systems/profiling/profiler.h"
#include "systems/profiling/report.h"
#include "tools/splatffd/stream_options.h"

namespace sffd::profile_cmd {

struct Options {
    std::string scene = "sphere";
    int frames = 120;
    int warmup = 10;
    std::string quality = "hq";
    std::string backend = "auto";        // auto: the engine's own choice (ffd/deform_backend.h), cpu, gpu
    std::string raster = "auto";         // HQ rasteriser: auto, raster, compute (render::RasterPath)
    std::string sprite_raster = "auto";  // preview rasteriser: auto, raster, cpu (render::SpritePath)
    int preview_budget = -1;  // points per cloud in preview frames (PreviewBudget); -1: the default
    bool sync = false;
    std::string drive = "global twist";
    std::string json, csv, svg, trace, compare;
    std::vector<std::string> sweep;
    std::string plot_sweep;
    bool paper = false;
    int naive_frames = 1;
    std::string suite;              // "quick" or "full": the performance suite (profile_suite.cpp)
    std::vector<std::string> only;  // --only: the suite rows whose ids start with one of these
    cli::StreamCli stream = cli::interactive_stream_defaults();
};

struct RunSetup {
    std::string scene;
    int frames = 120, warmup = 10;
    std::string quality = "hq", backend = "auto", drive = "global twist", raster = "auto";
    std::string sprite_raster = "auto";
    bool sync = false;
    int preview_budget = -1;        // as Options::preview_budget
    int lattice_points = 0;         // > 0: replace every lattice's divisions (control points per axis)
    std::string basis;              // "": keep
    bool deformation_only = false;  // sweeps: no renderer
    cli::StreamCli stream = cli::interactive_stream_defaults();
};

// Member order matters: the profiler's GL queries must be deleted before the context.
struct RunOutput {
    gfx::GlContext context;
    std::unique_ptr<profiling::Profiler> profiler;
    profiling::ProfileReport report;
    std::size_t points = 0;    // surface splats (the report's "gaussians" counts the Gaussians)
    std::string backend_used;  // deformation path of the measured frames: cpu, gpu, mixed or none
};

Result<RunOutput> run_profile(const RunSetup& s);
// "cpu", "gpu", "mixed" (both ran) or "none" from the clouds deformed on each path.
std::string deformation_backend_name(std::uint64_t cpu_runs, std::uint64_t gpu_runs);

// Creates the scene's entities; synthetic:N makes a Fibonacci sphere of N splats in an 11^3 lattice.
Status load(ecs::Registry& registry, const std::string& scene, bool* synthetic);

int run_sweep(const Options& o);
int plot_sweep(const std::string& path, const std::string& prefix);
int run_paper(const Options& o);
int run_suite(const Options& o);

// Helpers.
int usage_error(const std::string& message);  // cmd_profile.cpp: message + usage, exit code 2
bool parse_int(const std::string& s, int& out);
bool parse_count(std::string s, double& out);  // 60k -> 60000, 1m -> 1000000
const profiling::PaperCase* find_case(const std::string& name);
Status write_text(const std::string& path, const std::string& text);
std::optional<std::string> read_text(const std::string& path);
double median(std::vector<double> v);
double thread_cpu_ms();  // CPU time of the calling thread

}  // namespace sffd::profile_cmd
