// `splatffd profile`: one profiled run (scene, context, schedule, what changes every frame), and the helpers
// the sweep and paper files share.
#include "tools/splatffd/profile_run.h"

#include <time.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "runtime/app/clock.h"
#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/preview_budget.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/lod/streaming.h"
#include "systems/profiling/synthetic.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_render.h"
#include "tools/splatffd/command.h"
#include "systems/engine/engine.h"
#include "tools/splatffd/progress.h"
#include "systems/engine/engine_frame.h"

namespace sffd::profile_cmd {

using namespace profiling;

bool parse_int(const std::string& s, int& out) {
    auto v =
        cli::parse_integer("", s, 0, 10'000'000);  // the shared number parser (the caller names the option)
    if (!v) return false;
    out = static_cast<int>(*v);
    return true;
}

bool parse_count(std::string s, double& out) {
    double mult = 1.0;
    if (!s.empty() && (s.back() == 'k' || s.back() == 'K')) mult = 1e3, s.pop_back();
    else if (!s.empty() && (s.back() == 'm' || s.back() == 'M')) mult = 1e6, s.pop_back();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !(v > 0)) return false;
    out = v * mult;
    return true;
}

const PaperCase* find_case(const std::string& name) {
    for (const auto& c : paper_cases)
        if (name == c.name) return &c;
    return nullptr;
}

Status write_text(const std::string& path, const std::string& text) { return write_file_atomic(path, text); }

std::optional<std::string> read_text(const std::string& path) {
    auto text = read_file(path, kMaxJsonFileBytes);  // runtime/core/file_io.h
    if (!text) return std::nullopt;
    return std::move(*text);
}

double median(std::vector<double> v) { return compute_stats(std::move(v)).p50; }

// On a loaded machine (other jobs competing for the cores) the wall time of a single-threaded loop
// overstates its cost; its thread CPU time does not.
double thread_cpu_ms() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

Status load(ecs::Registry& registry, const std::string& scene, bool* synthetic) {
    *synthetic = false;
    if (scene.rfind("synthetic-gaussians:", 0) == 0) {
        // The synthetic sphere as 3D Gaussians (gaussians_from_splats: flat Gaussians, SH degree 0) in the
        // same 11^3 lattice: gaussian_deform_system deforms it, render_system's Gaussian pass draws it.
        // synthetic-gaussians:N:sh3 adds SH degree 3 (the size of trained 3DGS files, whose SH rotation is
        // most of a CPU deformation's cost), with fixed small higher-order coefficients.
        std::string spec = scene.substr(20);
        int degree = 0;
        if (const auto colon = spec.find(':'); colon != std::string::npos) {
            const std::string sh = spec.substr(colon + 1);
            if (sh.size() != 3 || sh.rfind("sh", 0) != 0 || sh[2] < '0' || sh[2] > '3')
                return make_error(scene + ": the SH suffix is :sh0 .. :sh3");
            degree = sh[2] - '0';
            spec.resize(colon);
        }
        double count = 0.0;
        if (!parse_count(spec, count)) return make_error(scene + ": bad synthetic Gaussian count");
        *synthetic = true;
        const SplatCloud sphere = synthetic_sphere(static_cast<std::size_t>(count));
        const ecs::Entity cloud = registry.create();
        registry.emplace<Name>(cloud, Name{"synthetic Gaussian sphere"});
        GaussianCloud& g = registry.emplace<GaussianCloud>(cloud, gaussian::gaussians_from_splats(sphere));
        if (degree > 0) {
            const std::size_t k = std::size_t(sh_coeffs(degree));
            std::vector<float> sh(g.size() * k * 3);
            for (std::size_t i = 0; i < g.size(); ++i)
                for (std::size_t j = 0; j < k * 3; ++j)
                    sh[i * k * 3 + j] = j < 3 ? g.sh[i * 3 + j] : 0.05f * float((i + j) % 7) - 0.15f;
            g.sh = std::move(sh);
            g.sh_degree = degree;
        }
        const ecs::Entity lattice = registry.create();
        registry.emplace<Lattice>(lattice, paper_lattice(sphere, 10));
        registry.emplace<Deformers>(cloud, Deformers{{lattice}});
        return {};
    }
    // run_profile gives the registry its hooks first (with the streaming loader); a caller without them
    // gets the engine's.
    if (!SceneHooks::of(registry)) sffd::use_engine_scene_hooks(registry);
    if (scene.rfind("synthetic:", 0) != 0) return load_scene(registry, scene);
    double count = 0.0;
    if (!parse_count(scene.substr(10), count)) return make_error(scene + ": bad synthetic point count");
    *synthetic = true;
    const ecs::Entity cloud = registry.create();
    registry.emplace<Name>(cloud, Name{"synthetic sphere"});
    const SplatCloud& c =
        registry.emplace<SplatCloud>(cloud, synthetic_sphere(static_cast<std::size_t>(count)));
    const ecs::Entity lattice = registry.create();
    registry.emplace<Lattice>(lattice, paper_lattice(c, 10));
    registry.emplace<Deformers>(cloud, Deformers{{lattice}});
    return {};
}

namespace {

// Harness system (animation phase): every lattice follows a paper case whose strength oscillates with
// the frame time, so every frame is a fresh deformation (the FFD system skips unchanged lattices).
SystemFn drive_system(PaperCase c) {
    return [c](ecs::Registry& registry, const FrameContext& frame) {
        const double amount = 0.5 + 0.5 * std::sin(2.0 * M_PI * frame.time / 2.0 + 0.3);
        std::vector<ecs::Entity> lattices;
        for (auto [e, l] : registry.view<const Lattice>()) {
            (void)l;
            lattices.push_back(e);
        }
        for (ecs::Entity e : lattices) apply_paper_case(registry.patch<Lattice>(e), c, amount);
    };
}

// Harness system (animation phase): the camera circles its target once every 10 s of frame time, at its
// height, coming in to 40% of its distance and back out twice a turn (the lattices stay): what a viewer
// orbiting the model asks of the streaming.
SystemFn orbit_system() {
    return [start = std::optional<Camera>()](ecs::Registry& registry, const FrameContext& frame) mutable {
        for (auto [e, c] : registry.view<Camera>()) {
            (void)e;
            if (!start) start = c;
            const glm::dvec3 d = start->eye - start->target;
            const double a = 2.0 * M_PI * frame.time / 10.0;
            const glm::dvec3 up = glm::normalize(start->up);
            const glm::dvec3 along = glm::dot(d, up) * up;
            const glm::dvec3 flat = d - along;
            const glm::dvec3 side = glm::cross(up, flat);
            // In to 40% of the distance and back out twice a turn: the cut refines and coarsens.
            const double reach = 0.7 + 0.3 * std::cos(2.0 * a);
            c.eye = start->target + reach * (along + std::cos(a) * flat + std::sin(a) * side);
            break;
        }
    };
}

// A streamed hierarchy without a lattice gets the paper's 11^3 lattice around its box, in its frame, so
// the drive deforms it as it deforms the synthetic sphere.
void add_hierarchy_lattices(ecs::Registry& registry) {
    std::vector<ecs::Entity> bare;
    for (auto [e, sc] : registry.view<const lod::StreamedCloud>()) {
        (void)sc;
        if (!registry.has<Deformers>(e)) bare.push_back(e);
    }
    for (const ecs::Entity e : bare) {
        const ffd::Box b = registry.get<lod::StreamedCloud>(e).stream->bounds();
        SplatCloud corners;
        for (int i = 0; i < 8; ++i)
            corners.positions.emplace_back((i & 4) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y,
                                           (i & 1) ? b.hi.z : b.lo.z);
        const ecs::Entity lattice = registry.create();
        registry.emplace<Lattice>(lattice, paper_lattice(corners, 10));
        if (const Transform* t = registry.try_get<Transform>(e)) registry.emplace<Transform>(lattice, *t);
        registry.emplace<Deformers>(e, Deformers{{lattice}});
    }
}

}  // namespace

std::string deformation_backend_name(std::uint64_t cpu_runs, std::uint64_t gpu_runs) {
    if (cpu_runs > 0 && gpu_runs > 0) return "mixed";
    return gpu_runs > 0 ? "gpu" : cpu_runs > 0 ? "cpu" : "none";
}

Result<RunOutput> run_profile(const RunSetup& s) {
    RunOutput out;
    const bool want_render = !s.deformation_only;
    // auto needs a context only where the engine could pick its GPU path (the renderer wants one anyway).
    const bool need_gl = s.backend != "cpu" || want_render;
    bool have_gl = false;
    if (need_gl) {
        auto ctx = gfx::create_context({.headless = true, .width = 1280, .height = 720, .debug = false});
        if (!ctx) {
            if (s.backend == "gpu")
                return make_error("profile: --backend gpu needs a GL context: " + ctx.message());
        } else {
            out.context = std::move(ctx.value());
            have_gl = true;
        }
    }
    // Declared after `out`, so it dies first: GL objects in its resources need the context.
    auto registry_owner = std::make_unique<ecs::Registry>();
    ecs::Registry& registry = *registry_owner;
    bool synthetic = false;
    const auto load_start = std::chrono::steady_clock::now();
    sffd::use_engine_scene_hooks(registry);
    cli::apply_stream_options(registry, s.stream);
    if (Status st = load(registry, s.scene, &synthetic); !st) return st.error();
    add_hierarchy_lattices(registry);
    for (auto [e, c] : registry.view<const SplatCloud>()) {
        (void)e;
        out.points += c.size();
    }
    std::size_t gaussians = 0;
    for (auto [e, g] : registry.view<const GaussianCloud>()) {
        (void)e;
        gaussians += g.size();
    }
    if (s.lattice_points > 0 || !s.basis.empty()) {
        std::vector<ecs::Entity> ls;
        for (auto [e, l] : registry.view<const Lattice>()) {
            (void)l;
            ls.push_back(e);
        }
        for (ecs::Entity e : ls) {
            Lattice& l = registry.patch<Lattice>(e);
            if (s.lattice_points > 0)
                l = make_lattice(l.origin, l.axes, glm::ivec3(s.lattice_points - 1), l.basis);
            if (s.basis == "bspline") l.basis = LatticeBasis::bspline;
            if (s.basis == "bernstein") l.basis = LatticeBasis::bernstein;
        }
    }

    // The engine's frame; sweeps run its deformation phase alone (ffd_system, the same system).
    Schedule schedule;
    std::string schedule_kind = "engine";
    if (!s.deformation_only) {
        schedule = make_engine_schedule({.present = false});
    } else {
        schedule.add(Phase::residency, "residency", residency_system);  // the compute path's input
        schedule.add(Phase::deformation, "ffd", ffd_system);
        schedule.add(Phase::deformation, "gaussian", gaussian_deform_system);  // the same for Gaussian clouds
        schedule_kind = "deformation";
    }
    if (s.drive == "orbit") {
        schedule.add(Phase::animation, "profile.orbit", orbit_system());
    } else if (s.drive != "none") {
        const PaperCase* c = find_case(s.drive);
        if (!c) return make_error("profile: unknown --drive case '" + s.drive + "'");
        schedule.add(Phase::animation, "profile.drive", drive_system(*c));
    }
    if (have_gl && want_render) {
        auto& rs = registry.set_resource<render::RenderSettings>();
        rs.quality = s.quality == "preview" ? render::Quality::preview : render::Quality::hq;
        rs.raster_path = s.raster == "compute"  ? render::RasterPath::compute
                         : s.raster == "raster" ? render::RasterPath::raster
                                                : render::RasterPath::automatic;
        rs.sprite_path = s.sprite_raster == "cpu"      ? render::SpritePath::cpu
                         : s.sprite_raster == "raster" ? render::SpritePath::raster
                                                       : render::SpritePath::automatic;
    }
    // Every frame moves the lattice (the drive), so a preview frame is the editor's frame while moving: the
    // deformation and the renderer keep to the point budget (systems/ffd/preview_budget.h).
    PreviewBudget budget;
    if (s.preview_budget >= 0) budget.points = std::uint32_t(s.preview_budget);
    budget.active = want_render && s.quality == "preview";
    registry.set_resource<PreviewBudget>(budget);
    // The FFD system picks its CPU path on a software rasterizer (auto); --backend cpu|gpu forces either
    // path. The Gaussian system's counters (its default settings) say which path it took.
    registry.set_resource<FfdSettings>(
        FfdSettings{.force_cpu = s.backend == "cpu", .force_gpu = s.backend == "gpu"});
    registry.set_resource<GaussianDeformSettings>();

    GpuTiming timing = GpuTiming::none;
    if (have_gl) timing = s.sync ? GpuTiming::sync : GpuTiming::queries;
    // Headless: no present paces the frames, so the profiler does (two in flight, as a double-buffered swap
    // chain); otherwise the GPU's backlog is charged to whichever system's GL call blocks on a full queue.
    out.profiler = std::make_unique<Profiler>(ProfilerSettings{.gpu = timing, .max_frames_in_flight = 2});
    out.profiler->attach(schedule, registry);
    Clock clock({.fixed_dt = 1.0 / 60.0});
    // Says what it runs before it starts (a profile can run for minutes), and shows a percentage on a
    // terminal only (ProgressPrinter: quiet in logs and pipes).
    std::fprintf(stderr, "profile: %s: %d warm-up + %d measured frames (%d in all)\n", s.scene.c_str(),
                 s.warmup, s.frames, s.warmup + s.frames);
    cli::ProgressPrinter progress("profile", cli::ProgressPrinter::mode_for(false));
    double first_frame_ms = -1.0;  // from the start of the load to the end of the first frame
    double settle_ms = -1.0;       // a hierarchy's frame that waited for its whole cut
    for (int i = 0; i < s.warmup; ++i) {
        schedule.run_frame(registry, clock.tick());
        if (i == 0) {
            first_frame_ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start)
                    .count();
            // A hierarchy is measured as a user edits one: once its cut for the camera has arrived (one
            // frame that waits for it), then held while the drive moves the lattice.
            if (auto* st = registry.try_resource<lod::StreamSettings>();
                st && lod::stream_summary(registry).clouds) {
                const auto settle = std::chrono::steady_clock::now();
                st->wait = true;
                schedule.run_frame(registry, clock.tick());
                st->wait = false;
                settle_ms =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - settle)
                        .count();
            }
        }
        progress.report("warm-up", double(i + 1) / double(s.warmup));
    }
    out.profiler->clear();
    // Deformations per path so far: the first frames may take the CPU path before the render upload.
    auto runs = [&registry] {
        std::pair<std::uint64_t, std::uint64_t> r{0, 0};
        // A budgeted preview deforms its subset on the CPU (preview_budget.h).
        if (const auto* fs = registry.try_resource<FfdStats>())
            r.first += fs->cpu_runs + fs->preview_runs, r.second += fs->gpu_runs;
        if (const auto* gs = registry.try_resource<GaussianDeformStats>())
            r.first += gs->cpu_runs + gs->preview_runs, r.second += gs->gpu_runs;
        return r;
    };
    const auto runs_before = runs();
    for (int i = 0; i < s.frames; ++i) {
        schedule.run_frame(registry, clock.tick());
        progress.report("measuring", double(i + 1) / double(s.frames));
    }
    const auto runs_after = runs();
    out.profiler->resolve_all();
    out.profiler->detach(schedule, registry);

    Config config{{"scene", s.scene},
                  {"synthetic_scene", synthetic},
                  {"points", static_cast<double>(out.points)},
                  {"gaussians", static_cast<double>(gaussians)},
                  {"frames", static_cast<double>(s.frames)},
                  {"warmup", static_cast<double>(s.warmup)},
                  {"quality", s.quality},
                  {"raster", want_render ? s.raster : std::string("none")},
                  {"sprite_raster", want_render ? s.sprite_raster : std::string("none")},
                  {"preview_budget", budget.active ? static_cast<double>(budget.points) : 0.0},
                  {"gaussian_preview_budget", static_cast<double>(gaussian_preview_budget_for(
                                                  registry, std::numeric_limits<std::size_t>::max()))},
                  {"backend", s.backend},
                  {"drive", s.drive},
                  {"schedule", schedule_kind},
                  {"clock", std::string("fixed 1/60 s")}};
    // Which path the FFD system really took (it falls back to the CPU e.g. before the render upload).
    if (const auto* fs = registry.try_resource<FfdStats>()) {
        config.emplace_back("ffd_cpu_runs", static_cast<double>(fs->cpu_runs));
        config.emplace_back("ffd_gpu_runs", static_cast<double>(fs->gpu_runs));
        config.emplace_back("ffd_preview_runs", static_cast<double>(fs->preview_runs));
    }
    if (const auto* gs = registry.try_resource<GaussianDeformStats>()) {
        config.emplace_back("gaussian_cpu_runs", static_cast<double>(gs->cpu_runs));
        config.emplace_back("gaussian_gpu_runs", static_cast<double>(gs->gpu_runs));
        config.emplace_back("gaussian_preview_runs", static_cast<double>(gs->preview_runs));
    }
    out.backend_used = deformation_backend_name(runs_after.first - runs_before.first,
                                                runs_after.second - runs_before.second);
    config.emplace_back("backend_used", out.backend_used);
    // Which blend the Gaussian pass took in the last frame (systems/splat_render/gaussian_draw.h: quads up to
    // quad_coverage_budget() images of coverage, the tile renderer past it, where a GPU's blending units
    // would bound the quads) and the coverage it weighed, in images of the frame's size.
    if (have_gl && want_render && gaussians > 0) {
        const render::GaussianPassStats g = render::gaussian_pass_stats(registry);
        config.emplace_back("gaussian_blend", std::string(g.tile_clouds == 0   ? "quads"
                                                          : g.quad_clouds == 0 ? "tiles"
                                                                               : "mixed"));
        const auto& rs = registry.resource<render::RenderSettings>();
        const double pixels = double(rs.width) * double(rs.height);
        // Past 2^32 pixels the pass keeps only that the sum overflowed: -1.
        config.emplace_back("gaussian_covered_images",
                            g.covered_pixels == std::numeric_limits<std::uint64_t>::max()
                                ? -1.0
                                : double(g.covered_pixels) / pixels);
        config.emplace_back("gaussian_quad_budget_images", double(g.quad_budget_images));
    }
    if (first_frame_ms >= 0.0) config.emplace_back("first_frame_ms", first_frame_ms);
    if (settle_ms >= 0.0) config.emplace_back("stream_settle_frame_ms", settle_ms);
    // Streamed hierarchies (systems/lod/streaming.h): what the last measured frame drew and held.
    if (const lod::StreamSummary sum = lod::stream_summary(registry); sum.clouds > 0) {
        const lod::StreamStats& st = sum.stats;
        config.emplace_back("stream_splat_budget", double(s.stream.settings.options.splat_budget));
        config.emplace_back("stream_memory_budget_mb", double(s.stream.settings.options.memory_budget >> 20));
        config.emplace_back("stream_drawn_splats", double(st.drawn_splats));
        config.emplace_back("stream_wanted_splats", double(st.wanted_splats));
        config.emplace_back("stream_missing_pieces", double(st.missing_pieces));
        config.emplace_back("stream_resident_mb", double(st.resident_bytes) / 1048576.0);
        config.emplace_back("stream_peak_resident_mb", double(st.peak_resident_bytes) / 1048576.0);
        config.emplace_back("stream_loads", double(st.loads));
        config.emplace_back("stream_evictions", double(st.evictions));
        config.emplace_back("stream_select_ms", st.select_ms);
        config.emplace_back("stream_cut_nodes", double(st.cut_nodes));
        config.emplace_back("stream_memory_limited", bool(st.memory_limited));
    }
    if (s.lattice_points > 0) config.emplace_back("lattice", static_cast<double>(s.lattice_points));
    if (!s.basis.empty()) config.emplace_back("basis", s.basis);
    out.report = build_report(*out.profiler, std::move(config), machine_info(have_gl));
    if (have_gl) {
        render::release_render_state(registry);
        ffd_release_gpu(registry);
        registry.erase_resource<gfx::GpuSplatStore>();
    }
    registry_owner.reset();
    return out;
}

}  // namespace sffd::profile_cmd
