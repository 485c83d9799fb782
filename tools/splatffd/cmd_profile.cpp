// splatffd profile: frame-time profiling of the engine's schedule, parameter sweeps, regression checks
// against a baseline, and the seed paper's timing table. The measuring machinery is systems/profiling;
// this file sets up runs (scene, context, schedule, what changes every frame) and prints results.
//
// Parts of the engine land at different times (scene loading, the FFD system, the renderer); the
// __has_include guards let this command build and profile whatever exists.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <unordered_map>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/app/clock.h"
#include "runtime/core/atomic_file.h"
#include "runtime/gfx/context.h"
#include "systems/profiling/paper_ffd.h"
#include "systems/profiling/profiler.h"
#include "systems/profiling/report.h"
#include "systems/profiling/svg_plot.h"
#include "systems/profiling/synthetic.h"
#include "tools/splatffd/command.h"

#include <nlohmann/json.hpp>

#if __has_include("tools/splatffd/engine.h")
#include "tools/splatffd/engine.h"
#define SFFD_PROFILE_HAS_ENGINE 1
#endif
#if __has_include("runtime/assets/scene.h")
#include "runtime/assets/scene.h"
#define SFFD_PROFILE_HAS_SCENES 1
#endif
#if __has_include("systems/ffd/deform.h")
#include "systems/ffd/deform.h"
#define SFFD_PROFILE_HAS_FFD 1
#endif
#if __has_include("systems/ffd/ffd_system.h")
#include "systems/ffd/ffd_system.h"
#define SFFD_PROFILE_HAS_FFD_SYSTEM 1
#endif
#if __has_include("systems/ffd/ffd_gpu.h") && __has_include("systems/splat_render/splat_pack.h")
#include "runtime/core/log.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/profiling/pass_timer.h"
#include "systems/splat_render/splat_pack.h"
#define SFFD_PROFILE_HAS_FFD_GPU 1
#endif
#if SFFD_PROFILE_HAS_FFD_GPU && __has_include("systems/ffd/paper_mode.h")
#include <glm/gtc/matrix_transform.hpp>

#include "runtime/gfx/render_target.h"
#include "systems/ffd/paper_mode.h"
#define SFFD_PROFILE_HAS_PAPER_MODE 1
#endif
#if __has_include("systems/splat_render/splat_render.h")
#include "systems/splat_render/splat_render.h"
#define SFFD_PROFILE_HAS_RENDER 1
#endif

namespace sffd {
namespace {

using namespace profiling;

constexpr const char* usage_text =
    "usage: splatffd profile [SCENE] [options]\n"
    "  SCENE                 built-in name (sphere, face), a scene/point-cloud file, or synthetic:N\n"
    "                        (a sphere of N splats with an 11^3 lattice). Default: sphere\n"
    "  --frames N            measured frames (default 120)\n"
    "  --warmup W            frames run before measuring (default 10)\n"
    "  --quality hq|preview  render quality (default hq)\n"
    "  --backend cpu|gpu     deformation backend (default gpu; cpu runs without a GL context when the\n"
    "                        renderer is not wanted)\n"
    "  --sync                time GPU passes with glFinish + CPU clock instead of timer queries\n"
    "                        (timer queries are not trustworthy on llvmpipe)\n"
    "  --drive CASE|none     deform every lattice each frame with a paper case, animated over time:\n"
    "                        'global twist' (default), 'global stretch', 'local twist', 'local stretch'\n"
    "  --json F --csv F --svg F --trace F   write the report / per-frame CSV / frame-time chart /\n"
    "                        Chrome trace-event JSON (open in ui.perfetto.dev)\n"
    "  --compare BASE.json   exit 3 when a system or pass is slower than in BASE by more than the\n"
    "                        measured spread (see systems/profiling/README.md)\n"
    "  --sweep K=V,.. ..     sweep points=60k,250k,1m lattice=4,11,21 backend=cpu,gpu\n"
    "                        basis=bernstein,bspline (any subset); prints a table; --svg PREFIX writes\n"
    "                        PREFIX_points.svg and PREFIX_lattice.svg; --json F writes all rows\n"
    "  --plot-sweep F.json   re-draw the plots of a sweep saved with --json (with --svg PREFIX)\n"
    "  --paper               the seed paper's table: sphere and face, 11^3 control points, four cases;\n"
    "                        naive paper CPU algorithm vs our fast CPU path (and GPU paths when built)\n"
    "  --naive-frames N      frames of the naive paper algorithm per case (default 1; about a minute\n"
    "                        each; 0 skips it)\n";

int usage_error(const std::string& message) {
    std::fprintf(stderr, "splatffd profile: %s\n%s", message.c_str(), usage_text);
    return 2;
}

struct Options {
    std::string scene = "sphere";
    int frames = 120;
    int warmup = 10;
    std::string quality = "hq";
    std::string backend = "gpu";
    bool sync = false;
    std::string drive = "global twist";
    std::string json, csv, svg, trace, compare;
    std::vector<std::string> sweep;
    std::string plot_sweep;
    bool paper = false;
    int naive_frames = 1;
};

bool parse_int(const std::string& s, int& out) {
    auto v = cli::parse_integer("", s, 0, 10'000'000);  // the shared number parser (the caller names the option)
    if (!v) return false;
    out = static_cast<int>(*v);
    return true;
}

// 60k -> 60000, 1m -> 1000000.
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
    std::ifstream f(path, std::ios::binary);
    if (!f) return std::nullopt;
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

double median(std::vector<double> v) { return compute_stats(std::move(v)).p50; }

// CPU time of the calling thread in ms: on a loaded machine (other jobs competing for the cores) the
// wall time of a single-threaded loop overstates its cost; its thread CPU time does not.
double thread_cpu_ms() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// ---------------------------------------------------------------------------------------------- scenes

// Creates the scene's entities. synthetic:N (and the built-ins when scene loading has not landed) make a
// Fibonacci sphere with an 11^3 Bernstein lattice around it.
Status load(ecs::Registry& registry, const std::string& scene, bool* synthetic) {
    *synthetic = false;
    double count = 0.0;
    std::string synthetic_count;
    if (scene.rfind("synthetic:", 0) == 0) synthetic_count = scene.substr(10);
#if !SFFD_PROFILE_HAS_SCENES
    else if (scene == "sphere") synthetic_count = "59650";
    else if (scene == "face") synthetic_count = "40880";
#endif
    if (!synthetic_count.empty()) {
        if (!parse_count(synthetic_count, count)) return make_error(scene + ": bad synthetic point count");
        *synthetic = true;
        const ecs::Entity cloud = registry.create();
        registry.emplace<Name>(cloud, Name{"synthetic sphere"});
        const SplatCloud& c = registry.emplace<SplatCloud>(cloud, synthetic_sphere(static_cast<std::size_t>(count)));
        const ecs::Entity lattice = registry.create();
        registry.emplace<Lattice>(lattice, paper_lattice(c, 10));
        registry.emplace<Deformers>(cloud, Deformers{{lattice}});
        return {};
    }
#if SFFD_PROFILE_HAS_SCENES
    return load_scene(registry, scene);
#else
    return make_error(scene + ": scene loading is not built yet (use sphere, face or synthetic:N)");
#endif
}

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

#if SFFD_PROFILE_HAS_FFD
// CPU deformation through the FFD engineer's fast path, for schedules without the FFD system (and for
// the sweep's cpu backend). Writes DeformedSplats like the FFD system's CPU path, so the renderer draws
// the deformed cloud (it uploads cpu_valid output when version moves).
void harness_cpu_deform(ecs::Registry& registry, const FrameContext&) {
    std::vector<ecs::Entity> clouds;
    for (auto [e, cloud, deformers] : registry.view<const SplatCloud, const Deformers>()) {
        (void)cloud, (void)deformers;
        clouds.push_back(e);
    }
    for (ecs::Entity e : clouds) {
        if (!registry.has<DeformedSplats>(e)) registry.emplace<DeformedSplats>(e);
        const SplatCloud& cloud = registry.get<SplatCloud>(e);
        const Deformers& deformers = registry.get<Deformers>(e);
        DeformedSplats& out = registry.patch<DeformedSplats>(e);
        const std::size_t n = cloud.size();
        out.origin = cloud.origin;
        out.positions.resize(n), out.normals.resize(n), out.axis_u.resize(n), out.axis_v.resize(n);
        ffd::PointsIn in{cloud.positions.data(), cloud.normals.size() == n ? cloud.normals.data() : nullptr,
                         cloud.axis_u.size() == n ? cloud.axis_u.data() : nullptr,
                         cloud.axis_v.size() == n ? cloud.axis_v.data() : nullptr, n, cloud.origin};
        ffd::PointsOut o{out.positions.data(), out.normals.data(), out.axis_u.data(), out.axis_v.data()};
        bool first = true;
        for (ecs::Entity le : deformers.lattices) {
            const Lattice* l = registry.try_get<Lattice>(le);
            if (!l) continue;
            (void)ffd::deform(*l, in, o, ffd::Backend::fast);
            in = ffd::PointsIn{o.positions, o.normals, o.axis_u, o.axis_v, n, cloud.origin};  // chain in place
            first = false;
        }
        if (first) {  // no lattice: the rest cloud
            out.positions = cloud.positions, out.normals = cloud.normals;
            out.axis_u = cloud.axis_u, out.axis_v = cloud.axis_v;
        }
        glm::dvec3 lo(1e300), hi(-1e300);
        for (const auto& p : out.positions) {
            lo = glm::min(lo, glm::dvec3(p));
            hi = glm::max(hi, glm::dvec3(p));
        }
        out.bounds_min = cloud.origin + lo;
        out.bounds_max = cloud.origin + hi;
        out.cpu_valid = true;
        out.gpu_valid = false;
        ++out.version;
    }
}
#endif

#if SFFD_PROFILE_HAS_FFD_GPU
// GPU compute deformation through the FFD engineer's GpuDeformer (shaders/ffd/deform.comp), for
// schedules without the FFD system (sweeps, the paper table): rest splats packed once into a buffer,
// every lattice dispatched in order into `deformed`, the whole thing named as the pass "ffd.compute".
struct HarnessGpuDeform {
    std::optional<ffd::GpuDeformer> deformer;
    struct Cloud {
        gfx::Buffer rest, deformed;
        std::uint32_t count = 0;
    };
    std::unordered_map<ecs::Entity, Cloud> clouds;
    bool failed = false;
};

Status gpu_deform_all(ecs::Registry& registry) {
    auto* st = registry.try_resource<HarnessGpuDeform>();
    if (!st) st = &registry.set_resource<HarnessGpuDeform>();
    if (st->failed) return make_error("profile: GPU deformer unavailable");
    if (!st->deformer) {
        auto d = ffd::GpuDeformer::create();
        if (!d) {
            st->failed = true;
            return d.error();
        }
        st->deformer.emplace(std::move(d.value()));
    }
    auto scope = profiling::gpu_scope(registry, "ffd.compute");
    for (auto [e, cloud, deformers] : registry.view<const SplatCloud, const Deformers>()) {
        auto& c = st->clouds[e];
        if (!c.rest) {
            const auto packed = render::pack_splats(cloud);
            c.count = static_cast<std::uint32_t>(packed.size());
            const auto bytes = static_cast<GLsizeiptr>(std::max<std::size_t>(packed.size(), 1) * sizeof(packed[0]));
            c.rest = gfx::Buffer::create("profile.rest");
            c.deformed = gfx::Buffer::create("profile.deformed");
            glNamedBufferData(c.rest.id(), bytes, packed.empty() ? nullptr : packed.data(), GL_STATIC_DRAW);
            glNamedBufferData(c.deformed.id(), bytes, nullptr, GL_DYNAMIC_DRAW);
        }
        bool first = true;
        for (ecs::Entity le : deformers.lattices) {
            const Lattice* l = registry.try_get<Lattice>(le);
            if (!l) continue;
            if (Status s = st->deformer->dispatch(*l, registry.version<Lattice>(le), cloud.origin,
                                                  first ? c.rest.id() : c.deformed.id(), c.deformed.id(), c.count);
                !s)
                return s;
            first = false;
        }
    }
    return {};
}

void harness_gpu_deform(ecs::Registry& registry, const FrameContext&) {
    if (Status s = gpu_deform_all(registry); !s) log::error(s.message());
}
#endif

// ---------------------------------------------------------------------------------------------- one run

struct RunSetup {
    std::string scene;
    int frames = 120, warmup = 10;
    std::string quality = "hq", backend = "gpu", drive = "global twist";
    bool sync = false;
    int lattice_points = 0;           // > 0: replace every lattice's divisions (control points per axis)
    std::string basis;                // "": keep
    bool deformation_only = false;    // sweeps: no renderer
};

// Member order matters: the profiler's GL queries must be deleted before the context.
struct RunOutput {
    gfx::GlContext context;
    std::unique_ptr<Profiler> profiler;
    ProfileReport report;
    std::size_t points = 0;
};

Result<RunOutput> run_profile(const RunSetup& s) {
    RunOutput out;
    const bool want_render = !s.deformation_only;
#if SFFD_PROFILE_HAS_RENDER
    const bool need_gl = s.backend == "gpu" || want_render;
#else
    const bool need_gl = s.backend == "gpu";
#endif
    bool have_gl = false;
    if (need_gl) {
        auto ctx = gfx::create_context({.headless = true, .width = 1280, .height = 720, .debug = false});
        if (!ctx) {
            if (s.backend == "gpu") return make_error("profile: --backend gpu needs a GL context: " + ctx.message());
        } else {
            out.context = std::move(ctx.value());
            have_gl = true;
        }
    }
    // Declared after `out`, so it dies first: GL objects in its resources need the context.
    auto registry_owner = std::make_unique<ecs::Registry>();
    ecs::Registry& registry = *registry_owner;
    bool synthetic = false;
    if (Status st = load(registry, s.scene, &synthetic); !st) return st.error();
    for (auto [e, c] : registry.view<const SplatCloud>()) {
        (void)e;
        out.points += c.size();
    }
    if (s.lattice_points > 0 || !s.basis.empty()) {
        std::vector<ecs::Entity> ls;
        for (auto [e, l] : registry.view<const Lattice>()) {
            (void)l;
            ls.push_back(e);
        }
        for (ecs::Entity e : ls) {
            Lattice& l = registry.patch<Lattice>(e);
            if (s.lattice_points > 0) {
                Lattice fresh = l;
                fresh.divisions = glm::ivec3(s.lattice_points - 1);
                fresh.rest.resize(fresh.size());
                const glm::ivec3 d = fresh.divisions;
                for (int i = 0; i <= d.x; ++i)
                    for (int j = 0; j <= d.y; ++j)
                        for (int k = 0; k <= d.z; ++k)
                            fresh.rest[fresh.index(i, j, k)] = fresh.origin + (double(i) / d.x) * fresh.axes[0] +
                                                               (double(j) / d.y) * fresh.axes[1] +
                                                               (double(k) / d.z) * fresh.axes[2];
                fresh.current = fresh.rest;
                l = std::move(fresh);
            }
            if (s.basis == "bspline") l.basis = LatticeBasis::bspline;
            if (s.basis == "bernstein") l.basis = LatticeBasis::bernstein;
        }
    }

    Schedule schedule;
    std::string schedule_kind = "harness";
#if SFFD_PROFILE_HAS_ENGINE
    if (!s.deformation_only) {
        schedule = make_engine_schedule({.present = false});
        schedule_kind = "engine";
    }
#endif
    if (s.drive != "none") {
        const PaperCase* c = find_case(s.drive);
        if (!c) return make_error("profile: unknown --drive case '" + s.drive + "'");
        schedule.add(Phase::animation, "profile.drive", drive_system(*c));
    }
    bool has_deformer = !schedule.systems(Phase::deformation).empty();
#if SFFD_PROFILE_HAS_FFD
    if (!has_deformer && (s.backend == "cpu" || !have_gl)) {
        schedule.add(Phase::deformation, "ffd.cpu_fast", harness_cpu_deform);
        has_deformer = true;
    }
#endif
#if SFFD_PROFILE_HAS_FFD_GPU
    if (!has_deformer && s.backend == "gpu" && have_gl) {
        schedule.add(Phase::deformation, "ffd.gpu_compute", harness_gpu_deform);
        has_deformer = true;
    }
#endif
    if (!has_deformer && s.backend == "gpu" && s.deformation_only)
        return make_error("profile: the GPU deformation path is not built yet");
#if SFFD_PROFILE_HAS_RENDER
    if (have_gl) {
        auto& rs = registry.set_resource<render::RenderSettings>();
        rs.quality = s.quality == "preview" ? render::Quality::preview : render::Quality::hq;
    }
#endif

#if SFFD_PROFILE_HAS_FFD_SYSTEM
    // The engine's FFD system picks its CPU path on a software rasterizer; --backend forces either path.
    registry.set_resource<FfdSettings>(FfdSettings{.force_cpu = s.backend == "cpu", .force_gpu = s.backend == "gpu"});
#endif
    GpuTiming timing = GpuTiming::none;
    if (have_gl) timing = s.sync ? GpuTiming::sync : GpuTiming::queries;
    out.profiler = std::make_unique<Profiler>(ProfilerSettings{.gpu = timing});
    out.profiler->attach(schedule, registry);
    Clock clock({.fixed_dt = 1.0 / 60.0});
    for (int i = 0; i < s.warmup; ++i) schedule.run_frame(registry, clock.tick());
    out.profiler->clear();
    for (int i = 0; i < s.frames; ++i) schedule.run_frame(registry, clock.tick());
    out.profiler->resolve_all();
    out.profiler->detach(schedule, registry);

    Config config{{"scene", s.scene},
                  {"synthetic_scene", synthetic},
                  {"points", static_cast<double>(out.points)},
                  {"frames", static_cast<double>(s.frames)},
                  {"warmup", static_cast<double>(s.warmup)},
                  {"quality", s.quality},
                  {"backend", s.backend},
                  {"drive", s.drive},
                  {"schedule", schedule_kind},
                  {"clock", std::string("fixed 1/60 s")}};
#if SFFD_PROFILE_HAS_FFD_SYSTEM
    // Which path the FFD system really took (it falls back to the CPU e.g. before the render upload).
    if (const auto* fs = registry.try_resource<FfdSettings>()) {
        config.emplace_back("ffd_cpu_runs", static_cast<double>(fs->cpu_runs));
        config.emplace_back("ffd_gpu_runs", static_cast<double>(fs->gpu_runs));
    }
#endif
    if (s.lattice_points > 0) config.emplace_back("lattice", static_cast<double>(s.lattice_points));
    if (!s.basis.empty()) config.emplace_back("basis", s.basis);
    out.report = build_report(*out.profiler, std::move(config), machine_info(have_gl));
#if SFFD_PROFILE_HAS_RENDER
    if (have_gl) render::release_render_state(registry);
#endif
#if SFFD_PROFILE_HAS_FFD_SYSTEM
    if (have_gl) ffd_release_gpu(registry);
#endif
    registry_owner.reset();
    return out;
}

// ---------------------------------------------------------------------------------------------- compare

int compare_with(const ProfileReport& current, const std::string& base_path) {
    const auto text = read_text(base_path);
    if (!text) {
        std::fprintf(stderr, "%s: cannot read the baseline report\n", base_path.c_str());
        return 1;
    }
    auto base = report_from_json(*text, base_path);
    if (!base) {
        std::fprintf(stderr, "%s\n", base.message().c_str());
        return 1;
    }
    const auto rows = compare_reports(*base, current);
    std::printf("\ncompare with %s:\n%s", base_path.c_str(), to_text(rows).c_str());
    const auto slower = std::count_if(rows.begin(), rows.end(), [](const Regression& r) { return r.slower; });
    if (slower > 0) {
        std::printf("%lld regression(s): slower than the baseline by more than the measured spread\n",
                    static_cast<long long>(slower));
        return 3;
    }
    std::printf("no regression\n");
    return 0;
}

int write_outputs(const Options& o, const RunOutput& r) {
    auto save = [](const std::string& path, const std::string& text) {
        if (path.empty()) return true;
        if (Status st = write_text(path, text); !st) {
            std::fprintf(stderr, "%s\n", st.message().c_str());
            return false;
        }
        std::printf("wrote %s\n", path.c_str());
        return true;
    };
    bool ok = save(o.json, to_json(r.report));
    ok &= save(o.csv, to_csv(*r.profiler));
    ok &= save(o.trace, to_chrome_trace(*r.profiler, "splatffd profile " + o.scene));
    ok &= save(o.svg, frame_svg(*r.profiler, "splatffd profile " + o.scene + ": time per frame"));
    return ok ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------- sweep

struct SweepRow {
    double points = 0;
    int lattice = 0;
    std::string backend, basis;
    double deform_p50 = -1, deform_p95 = -1, frame_p50 = -1;
    std::string note;
};

// Time vs points: one series per (backend, basis, lattice). Time vs lattice: per (backend, basis, points).
int write_sweep_plots(const std::vector<SweepRow>& rows, const std::string& prefix) {
    auto chart = [&](bool by_points) {
        LineChart c;
        c.title = by_points ? "FFD deformation time vs point count" : "FFD deformation time vs lattice size";
        c.x_label = by_points ? "splats" : "control points per axis (lattice n x n x n)";
        c.y_label = "deformation time per frame, median (ms)";
        c.title += " (solid: CPU, dashed: GPU)";
        c.log_x = by_points;
        c.log_y = true;
        c.x_ticks_at_data = true;
        std::map<std::string, Series> series;
        std::vector<std::string> order;
        for (const auto& r : rows) {
            if (r.deform_p50 <= 0) continue;
            char key[128];
            if (by_points) std::snprintf(key, sizeof key, "%s %s, %d^3", r.backend.c_str(), r.basis.c_str(), r.lattice);
            else std::snprintf(key, sizeof key, "%s %s, %s pts", r.backend.c_str(), r.basis.c_str(), tick_label(r.points).c_str());
            if (!series.count(key)) order.push_back(key), series[key].name = key, series[key].dashed = r.backend == "gpu";
            series[key].points.emplace_back(by_points ? r.points : double(r.lattice), r.deform_p50);
        }
        for (const auto& k : order) {
            auto& pts = series[k].points;
            std::sort(pts.begin(), pts.end());
            c.series.push_back(series[k]);
        }
        return render_svg(c);
    };
    for (bool by_points : {true, false}) {
        const std::string path = prefix + (by_points ? "_points.svg" : "_lattice.svg");
        if (Status st = write_text(path, chart(by_points)); !st) {
            std::fprintf(stderr, "%s\n", st.message().c_str());
            return 1;
        }
        std::printf("wrote %s\n", path.c_str());
    }
    return 0;
}

// --plot-sweep F.json: re-draws the plots of a sweep written with --json (no measuring).
int plot_sweep(const std::string& path, const std::string& prefix) {
    const auto text = read_text(path);
    if (!text) {
        std::fprintf(stderr, "%s: cannot read the sweep file\n", path.c_str());
        return 1;
    }
    const auto j = nlohmann::json::parse(*text, nullptr, false);
    if (j.is_discarded() || j.value("format", "") != "splatffd-sweep" || !j.contains("rows") || !j["rows"].is_array()) {
        std::fprintf(stderr, "%s: not a sweep written by 'splatffd profile --sweep ... --json'\n", path.c_str());
        return 1;
    }
    std::vector<SweepRow> rows;
    try {
        for (const auto& r : j["rows"]) {
            SweepRow row;
            row.points = r.at("points").get<double>();
            row.lattice = r.at("lattice").get<int>();
            row.backend = r.at("backend").get<std::string>();
            row.basis = r.at("basis").get<std::string>();
            row.deform_p50 = r.at("deform_p50_ms").get<double>();
            row.deform_p95 = r.at("deform_p95_ms").get<double>();
            row.frame_p50 = r.at("frame_p50_ms").get<double>();
            rows.push_back(row);
        }
    } catch (const nlohmann::json::exception& e) {
        std::fprintf(stderr, "%s: malformed sweep row: %s\n", path.c_str(), e.what());
        return 1;
    }
    return write_sweep_plots(rows, prefix);
}

int run_sweep(const Options& o) {
    std::map<std::string, std::vector<std::string>> axes{
        {"points", {"60k"}}, {"lattice", {"11"}}, {"backend", {"cpu"}}, {"basis", {"bernstein"}}};
    for (const auto& kv : o.sweep) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos) return usage_error("--sweep: expected KEY=V1,V2,... got '" + kv + "'");
        const std::string key = kv.substr(0, eq);
        if (!axes.count(key)) return usage_error("--sweep: unknown key '" + key + "' (points, lattice, backend, basis)");
        std::vector<std::string> values;
        std::stringstream ss(kv.substr(eq + 1));
        for (std::string v; std::getline(ss, v, ',');)
            if (!v.empty()) values.push_back(v);
        if (values.empty()) return usage_error("--sweep: no values for '" + key + "'");
        for (const auto& v : values) {
            double d = 0;
            int n = 0;
            if (key == "points" && !parse_count(v, d)) return usage_error("--sweep: bad point count '" + v + "'");
            if (key == "lattice" && (!parse_int(v, n) || n < 2 || n > 65))
                return usage_error("--sweep: lattice takes control points per axis, 2..65, got '" + v + "'");
            if (key == "backend" && v != "cpu" && v != "gpu") return usage_error("--sweep: backend cpu|gpu");
            if (key == "basis" && v != "bernstein" && v != "bspline") return usage_error("--sweep: basis bernstein|bspline");
        }
        axes[key] = values;
    }
    std::vector<SweepRow> rows;
    std::printf("sweep: %d measured frames + %d warm-up per configuration, deformation phase only, drive '%s'\n",
                o.frames, o.warmup, o.drive.c_str());
    std::printf("%9s %7s %7s %9s %12s %12s %12s  %s\n", "points", "lattice", "backend", "basis", "deform p50",
                "deform p95", "frame p50", "note");
    std::string machine_line, timing_line;
    for (const auto& backend : axes["backend"])
        for (const auto& basis : axes["basis"])
            for (const auto& lat : axes["lattice"])
                for (const auto& pts : axes["points"]) {
                    SweepRow row;
                    parse_count(pts, row.points);
                    parse_int(lat, row.lattice);
                    row.backend = backend;
                    row.basis = basis;
                    RunSetup s;
                    s.scene = "synthetic:" + std::to_string(static_cast<long long>(row.points));
                    s.frames = o.frames;
                    s.warmup = o.warmup;
                    s.backend = backend;
                    s.sync = true;  // one number per pass that includes the GPU work
                    s.drive = o.drive;
                    s.lattice_points = row.lattice;
                    s.basis = basis;
                    s.deformation_only = true;
                    auto r = run_profile(s);
                    if (!r) {
                        row.note = r.message();
                    } else {
                        for (const auto& ph : r->report.phases)
                            if (ph.name == "deformation") row.deform_p50 = ph.cpu_ms.p50, row.deform_p95 = ph.cpu_ms.p95;
                        row.frame_p50 = r->report.frame_ms.p50;
                        machine_line = r->report.machine.cpu + ", " + std::to_string(r->report.machine.cores) + " cores" +
                                       (r->report.machine.gl_renderer.empty() ? "" : ", GL " + r->report.machine.gl_renderer);
                        timing_line = r->report.gpu_timing;
                    }
                    std::printf("%9.0f %7d %7s %9s %12.3f %12.3f %12.3f  %s\n", row.points, row.lattice,
                                row.backend.c_str(), row.basis.c_str(), row.deform_p50, row.deform_p95, row.frame_p50,
                                row.note.c_str());
                    std::fflush(stdout);
                    rows.push_back(row);
                }
    std::printf("machine: %s\n", machine_line.c_str());

    if (!o.svg.empty())
        if (int rc = write_sweep_plots(rows, o.svg); rc != 0) return rc;
    if (!o.json.empty()) {
        std::string j = "{\n  \"format\": \"splatffd-sweep\",\n  \"machine\": \"" + machine_line + "\",\n  \"rows\": [\n";
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const auto& r = rows[i];
            char buf[512];
            std::snprintf(buf, sizeof buf,
                          "    {\"points\": %.0f, \"lattice\": %d, \"backend\": \"%s\", \"basis\": \"%s\", "
                          "\"deform_p50_ms\": %.6f, \"deform_p95_ms\": %.6f, \"frame_p50_ms\": %.6f}%s\n",
                          r.points, r.lattice, r.backend.c_str(), r.basis.c_str(), r.deform_p50, r.deform_p95,
                          r.frame_p50, i + 1 < rows.size() ? "," : "");
            j += buf;
        }
        j += "  ]\n}\n";
        if (Status st = write_text(o.json, j); !st) {
            std::fprintf(stderr, "%s\n", st.message().c_str());
            return 1;
        }
        std::printf("wrote %s\n", o.json.c_str());
    }
    // Configurations whose path is not built yet are skipped, not failed.
    const bool any_failed = std::any_of(rows.begin(), rows.end(), [](const SweepRow& r) {
        return r.deform_p50 < 0 && r.note.find("not built yet") == std::string::npos;
    });
    return any_failed ? 1 : 0;
}

// ---------------------------------------------------------------------------------------------- paper

struct PaperRow {
    std::string object, method;
    std::size_t points = 0;
    std::vector<double> case_ms;  // per case: median ms per frame (-1: not available)
    std::string note;
};

int run_paper(const Options& o) {
    std::printf("The seed paper's experiment (section IV): 11x11x11 = 1331 control points, Bernstein basis,\n"
                "positions + normals deformed every frame; time per frame = deformation only.\n"
                "Paper (Pentium Dual-Core 2.7 GHz, GeForce 9500 GT): CPU %.2f FPS (~%.0f s/frame), "
                "GPU vertex shader up to %.0f FPS (~%.0f ms), x%.0f.\n\n",
                paper_cpu_fps, 1.0 / paper_cpu_fps, paper_gpu_fps, 1000.0 / paper_gpu_fps, paper_speedup);
    std::vector<PaperRow> rows;
    for (const char* object : {"sphere", "face"}) {
        ecs::Registry registry;
        bool synthetic = false;
        if (Status st = load(registry, object, &synthetic); !st) {
            std::fprintf(stderr, "%s\n", st.message().c_str());
            return 1;
        }
        // The largest cloud of the scene is the paper's object.
        const SplatCloud* cloud = nullptr;
        for (auto [e, c] : registry.view<const SplatCloud>()) {
            (void)e;
            if (!cloud || c.size() > cloud->size()) cloud = &c;
        }
        if (!cloud) {
            std::fprintf(stderr, "%s: no point cloud in the scene\n", object);
            return 1;
        }
        const std::string label = std::string(object) + (synthetic ? " (synthetic stand-in)" : "");
        Lattice lattice = paper_lattice(*cloud, 10);
        std::vector<glm::vec3> pos, nrm;

        PaperRow naive{label, "paper CPU naive, wall (1 thread)", cloud->size(), {}, ""};
        PaperRow naive_cpu{label, "paper CPU naive, thread CPU time", cloud->size(), {}, ""};
        for (const auto& pc : paper_cases) {
            std::vector<double> ms, cpu;
            for (int f = 0; f < o.naive_frames; ++f) {
                apply_paper_case(lattice, pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                const auto t0 = std::chrono::steady_clock::now();
                const double c0 = thread_cpu_ms();
                paper_ffd_naive(lattice, *cloud, pos, nrm);
                cpu.push_back(thread_cpu_ms() - c0);
                ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            }
            naive.case_ms.push_back(ms.empty() ? -1.0 : median(ms));
            naive_cpu.case_ms.push_back(cpu.empty() ? -1.0 : median(cpu));
            if (ms.empty()) {
                naive.note = naive_cpu.note = "skipped (--naive-frames 0)";
                continue;
            }
            std::printf("  %-8s %-15s naive  wall %10.1f ms  thread CPU %10.1f ms\n", object, pc.name,
                        naive.case_ms.back(), naive_cpu.case_ms.back());
            std::fflush(stdout);
        }
        rows.push_back(naive);
        rows.push_back(naive_cpu);

#if SFFD_PROFILE_HAS_FFD
        PaperRow fast{label, "ours CPU fast (factorised, AVX-512, TBB)", cloud->size(), {}, ""};
        pos.assign(cloud->size(), {});
        nrm.assign(cloud->size(), {});
        for (const auto& pc : paper_cases) {
            std::vector<double> ms;
            ffd::PointsIn in{cloud->positions.data(), cloud->normals.data(), nullptr, nullptr, cloud->size(), cloud->origin};
            ffd::PointsOut out{pos.data(), nrm.data(), nullptr, nullptr};
            for (int f = 0; f < std::max(3, o.frames / 4) + 2; ++f) {
                apply_paper_case(lattice, pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                const auto t0 = std::chrono::steady_clock::now();
                auto r = ffd::deform(lattice, in, out, ffd::Backend::fast);
                const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
                if (!r) {
                    std::fprintf(stderr, "%s\n", r.message().c_str());
                    return 1;
                }
                if (f >= 2) ms.push_back(t);  // two warm-up frames
            }
            fast.case_ms.push_back(median(ms));
        }
        rows.push_back(fast);
#else
        rows.push_back({label, "ours CPU fast", cloud->size(), {-1, -1, -1, -1}, "not built yet"});
#endif
#if SFFD_PROFILE_HAS_FFD_GPU
        {
            // GPU rows, timed with glFinish + CPU clock (llvmpipe's timer queries are not trustworthy):
            //   compute          the skinning-style compute pass alone (deform once per change);
            //   compute + draw   that pass then the same point sprites drawn from the deformed buffer;
            //   paper mode       the paper's design: deformation in the vertex shader of the point draw.
            // Draws go to an offscreen 1024x768 target, camera framing the cloud; 2-pixel point sprites.
            PaperRow gpu{label, "ours GPU compute (deform only)", cloud->size(), {}, ""};
            PaperRow gpu_draw{label, "ours GPU compute + point draw", cloud->size(), {}, ""};
            PaperRow paper_mode{label, "paper mode: vertex-shader deform + draw", cloud->size(), {}, ""};
            auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 64, .debug = false});
            if (!ctx) {
                gpu.case_ms = gpu_draw.case_ms = paper_mode.case_ms = {-1, -1, -1, -1};
                gpu.note = gpu_draw.note = paper_mode.note = ctx.message();
            } else {
                auto greg = std::make_unique<ecs::Registry>();  // dies before the context
                const ecs::Entity ce = greg->create();
                greg->emplace<SplatCloud>(ce, *cloud);
                const ecs::Entity le = greg->create();
                greg->emplace<Lattice>(le, lattice);
                greg->emplace<Deformers>(ce, Deformers{{le}});
                const int frames = std::max(3, o.frames / 8) + 2;
                auto time_frames = [&](const PaperCase& pc, auto&& body) -> Result<double> {
                    std::vector<double> ms;
                    for (int f = 0; f < frames; ++f) {
                        apply_paper_case(greg->patch<Lattice>(le), pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                        glFinish();
                        const auto t0 = std::chrono::steady_clock::now();
                        if (Status st = body(); !st) return st.error();
                        glFinish();
                        const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
                        if (f >= 2) ms.push_back(t);  // two warm-up frames
                    }
                    return median(ms);
                };
                for (const auto& pc : paper_cases) {
                    auto t = time_frames(pc, [&] { return gpu_deform_all(*greg); });
                    if (!t) {
                        std::fprintf(stderr, "%s\n", t.message().c_str());
                        return 1;
                    }
                    gpu.case_ms.push_back(*t);
                }
#if SFFD_PROFILE_HAS_PAPER_MODE
                auto target = gfx::RenderTarget::create(
                    {.label = "profile.paper", .width = 1024, .height = 768, .color = {{"color", gfx::ColorFormat::rgba8}}});
                auto paper = ffd::PaperModeRenderer::create();
                if (!target || !paper) {
                    std::fprintf(stderr, "%s\n", (!target ? target.message() : paper.message()).c_str());
                    return 1;
                }
                glm::dvec3 lo = lattice.origin, hi = lattice.origin + lattice.axes[0] + lattice.axes[1] + lattice.axes[2];
                const glm::dvec3 centre = 0.5 * (lo + hi) - cloud->origin;
                const float radius = static_cast<float>(0.5 * glm::length(hi - lo));
                const glm::mat4 view_proj =
                    glm::perspective(glm::radians(45.0f), 1024.0f / 768.0f, 0.01f * radius, 10.0f * radius) *
                    glm::lookAt(glm::vec3(centre) + glm::vec3(0, 0, 2.8f * radius), glm::vec3(centre), glm::vec3(0, 1, 0));
                const float black[4] = {0, 0, 0, 0};
                auto& st = greg->resource<HarnessGpuDeform>();
                const auto& buffers = st.clouds.at(ce);
                for (const auto& pc : paper_cases) {
                    auto t = time_frames(pc, [&]() -> Status {
                        if (Status s1 = gpu_deform_all(*greg); !s1) return s1;
                        target->bind();
                        target->clear_color("color", black);
                        target->clear_depth();
                        paper->draw_deformed(buffers.deformed.id(), buffers.count, view_proj, 2.0f);
                        return {};
                    });
                    if (!t) {
                        std::fprintf(stderr, "%s\n", t.message().c_str());
                        return 1;
                    }
                    gpu_draw.case_ms.push_back(*t);
                    auto tp = time_frames(pc, [&]() -> Status {
                        target->bind();
                        target->clear_color("color", black);
                        target->clear_depth();
                        return paper->draw(greg->get<Lattice>(le), greg->version<Lattice>(le), cloud->origin,
                                           buffers.rest.id(), buffers.count, view_proj, 2.0f);
                    });
                    if (!tp) {
                        std::fprintf(stderr, "%s\n", tp.message().c_str());
                        return 1;
                    }
                    paper_mode.case_ms.push_back(*tp);
                }
                paper = make_error("done");  // GL objects go while the context is current
                target = make_error("done");
#else
                gpu_draw.case_ms = paper_mode.case_ms = {-1, -1, -1, -1};
                gpu_draw.note = paper_mode.note = "not built yet";
#endif
                greg.reset();
            }
            rows.push_back(gpu);
            rows.push_back(gpu_draw);
            rows.push_back(paper_mode);
        }
#else
        rows.push_back({label, "ours GPU compute", cloud->size(), {-1, -1, -1, -1}, "not built yet"});
        rows.push_back({label, "paper mode (vertex shader)", cloud->size(), {-1, -1, -1, -1}, "not built yet"});
#endif
    }

    const MachineInfo m = machine_info(false);
    std::printf("\nmachine: %s, %u cores, %s\n", m.cpu.c_str(), m.cores, m.os.c_str());
    std::printf("%-30s %-42s", "object (splats)", "method");
    for (const auto& pc : paper_cases) std::printf(" %15s", pc.name);
    std::printf(" %10s %9s\n", "FPS", "speed-up");
    for (const auto& r : rows) {
        const std::string obj = r.object + " (" + std::to_string(r.points) + ")";
        std::printf("%-30s %-42s", obj.c_str(), r.method.c_str());
        double sum = 0;
        int n = 0;
        for (double ms : r.case_ms) {
            if (ms < 0) std::printf(" %15s", "-");
            else std::printf(" %12.2f ms", ms), sum += ms, ++n;
        }
        // Speed-up against the naive algorithm's thread CPU time (what its wall time is on an idle core), on
        // the mean over the four cases; the other rows are wall times, so under load the ratio is conservative.
        double naive_mean = 0;
        for (const auto& q : rows)
            if (q.object == r.object && q.method.rfind("paper CPU naive, thread CPU", 0) == 0) {
                for (double ms : q.case_ms) naive_mean += ms < 0 ? -1e300 : ms / 4.0;
            }
        if (n > 0) {
            const double mean = sum / n;
            const double ratio = naive_mean / mean;
            if (naive_mean > 0) std::printf(ratio < 10 ? " %10.2f %8.2fx" : " %10.2f %8.0fx", 1000.0 / mean, ratio);
            else std::printf(" %10.2f %9s", 1000.0 / mean, "-");
        } else {
            std::printf(" %10s %9s  %s", "-", "-", r.note.c_str());
        }
        std::printf("\n");
    }
    std::printf("%-30s %-42s %63s %10.2f %8s\n", "paper (59,650 / 40,880)", "paper CPU", "", paper_cpu_fps, "1x");
    std::printf("%-30s %-42s %63s %10.2f %8.0fx\n", "paper (59,650 / 40,880)", "paper GPU (vertex shader)", "",
                paper_gpu_fps, paper_speedup);
    return 0;
}

// ---------------------------------------------------------------------------------------------- main

// Every input and output path checked before measuring (`--compare nosuch.json` used to fail only after
// the whole run): the baseline must read and parse as a report, each output's folder must exist.
int check_paths_before_work(const Options& o) {
    if (!o.compare.empty()) {
        const auto text = read_text(o.compare);
        if (!text) {
            std::fprintf(stderr, "%s: cannot read the baseline report\n", o.compare.c_str());
            return 1;
        }
        if (auto base = report_from_json(*text, o.compare); !base) {
            std::fprintf(stderr, "%s\n", base.message().c_str());
            return 1;
        }
    }
    for (const std::string* out : {&o.json, &o.csv, &o.trace}) {
        if (out->empty()) continue;
        const std::filesystem::path folder = std::filesystem::path(*out).parent_path();
        if (!folder.empty() && !std::filesystem::is_directory(folder)) {
            std::fprintf(stderr, "%s: folder %s does not exist\n", out->c_str(), folder.string().c_str());
            return 1;
        }
    }
    return 0;
}

int run_profile_command(cli::Args args) {
    Options o;
    bool scene_given = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&](std::string& out) {
            if (i + 1 >= args.size()) return false;
            out = args[++i];
            return true;
        };
        auto int_value = [&](int& out) {
            std::string v;
            return value(v) && parse_int(v, out);
        };
        if (a == "--help" || a == "-h") {
            std::printf("%s", usage_text);
            return 0;
        } else if (a == "--frames") {
            if (!int_value(o.frames) || o.frames < 1) return usage_error("--frames takes a positive integer");
        } else if (a == "--warmup") {
            if (!int_value(o.warmup)) return usage_error("--warmup takes a non-negative integer");
        } else if (a == "--naive-frames") {
            if (!int_value(o.naive_frames)) return usage_error("--naive-frames takes a non-negative integer");
        } else if (a == "--quality") {
            if (!value(o.quality) || (o.quality != "hq" && o.quality != "preview")) return usage_error("--quality hq|preview");
        } else if (a == "--backend") {
            if (!value(o.backend) || (o.backend != "cpu" && o.backend != "gpu")) return usage_error("--backend cpu|gpu");
        } else if (a == "--drive") {
            if (!value(o.drive) || (o.drive != "none" && !find_case(o.drive)))
                return usage_error("--drive takes 'local stretch', 'local twist', 'global stretch', 'global twist' or none");
        } else if (a == "--sync") {
            o.sync = true;
        } else if (a == "--paper") {
            o.paper = true;
        } else if (a == "--json" || a == "--csv" || a == "--svg" || a == "--trace" || a == "--compare") {
            std::string& target = a == "--json" ? o.json : a == "--csv" ? o.csv : a == "--svg" ? o.svg
                                : a == "--trace" ? o.trace : o.compare;
            if (!value(target)) return usage_error(a + " takes a file name");
        } else if (a == "--plot-sweep") {
            if (!value(o.plot_sweep)) return usage_error("--plot-sweep takes a sweep JSON file");
        } else if (a == "--sweep") {
            while (i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0) o.sweep.push_back(args[++i]);
            if (o.sweep.empty()) return usage_error("--sweep takes KEY=V1,V2 arguments");
        } else if (!a.empty() && a[0] == '-') {
            return usage_error("unknown option '" + a + "'");
        } else if (!scene_given) {
            o.scene = a;
            scene_given = true;
        } else {
            return usage_error("more than one scene given ('" + o.scene + "', '" + a + "')");
        }
    }
    if (int rc = check_paths_before_work(o); rc != 0) return rc;
    if (!o.plot_sweep.empty()) {
        if (o.svg.empty()) return usage_error("--plot-sweep needs --svg PREFIX");
        return plot_sweep(o.plot_sweep, o.svg);
    }
    if (o.paper) return run_paper(o);
    if (!o.sweep.empty()) return run_sweep(o);

    RunSetup s;
    s.scene = o.scene;
    s.frames = o.frames;
    s.warmup = o.warmup;
    s.quality = o.quality;
    s.backend = o.backend;
    s.sync = o.sync;
    s.drive = o.drive;
    auto r = run_profile(s);
    if (!r) {
        std::fprintf(stderr, "%s\n", r.message().c_str());
        return 1;
    }
    std::printf("%s", to_text(r->report).c_str());
    if (int rc = write_outputs(o, *r); rc != 0) return rc;
    if (!o.compare.empty()) return compare_with(r->report, o.compare);
    return 0;
}

}  // namespace
}  // namespace sffd

SFFD_COMMAND(profile, "measure frame time per system and pass; sweeps, --compare, --paper", sffd::run_profile_command);
