// `splatffd profile --suite quick|full`: every performance claim of the project measured side by side, one
// row per claim (its target, the value measured here, met or missed, the anchor where one runs here), the
// machine, a table on stdout and JSON (--json). The claims are listed once, in the top README's
// "Performance" section and in make_rows() below. Nothing here times code itself: frame and deformation rows
// are profiled runs (run_profile, the engine's own schedule and the profiler's scopes), editor rows are
// `splatffd view --replay --json` child processes, read rows time load_scene three times per file, and the
// anchor is Blender's lattice modifier timing itself. Speed is reported, never asserted: the suite's test
// checks the JSON's shape and that every row has a value or a reason.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/scene.h"
#include "runtime/core/json_text.h"
#include "runtime/core/paths.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/limits.h"
#include "systems/gaussian/from_splats.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/profiling/synthetic.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/profile_run.h"
#include "tools/splatffd/video.h"
#include "systems/engine/engine_frame.h"

extern char** environ;

namespace sffd::profile_cmd {

namespace {

namespace fs = std::filesystem;
using profiling::ProfileReport;

struct Row {
    std::string id, claim, source;
    std::string unit = "ms";
    bool higher_is_better = false;  // MB/s rows
    std::optional<double> target;
    bool gpu_only = false;
    std::optional<double> value;
    std::string status;  // met, missed, info (no target at this size), not measured
    std::string how;     // what ran
    std::string note;    // why not measured; what the value covers
    std::string anchor;  // Blender's time for the same work, or why it did not run
    double load = -1.0;  // 1-minute load average when measured
};

double load_average() {
    double l = -1.0;
    if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
        if (std::fscanf(f, "%lf", &l) != 1) l = -1.0;
        std::fclose(f);
    }
    return l;
}

// Runs argv with stdout and stderr into `log`; returns the exit status (-1: could not run or killed).
int spawn(std::vector<std::string> argv, const fs::path& log) {
    std::vector<char*> args;
    for (std::string& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int err = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (err != 0) return -1;
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string last_line(const fs::path& log) {
    std::ifstream f(log);
    std::string line, last;
    while (std::getline(f, line))
        if (!line.empty()) last = line;
    return last;
}

const profiling::TimingRow* find_row(const std::vector<profiling::TimingRow>& rows, const std::string& name) {
    for (const auto& r : rows)
        if (r.name == name) return &r;
    return nullptr;
}

class Suite {
public:
    // dry: wants() says no to every row, so make_rows() only lists the ids (nothing is measured or written).
    Suite(bool full, fs::path tmp, std::vector<std::string> only, bool dry = false)
        : m_full(full),
          m_dry(dry),
          m_tmp(std::move(tmp)),
          m_only(std::move(only)),
          m_only_matched(m_only.size(), 0) {}

    bool full() const { return m_full; }
    bool hardware_gpu() const { return m_hardware_gpu; }
    const profiling::MachineInfo& machine() const { return m_machine; }
    std::vector<Row>& rows() { return m_rows; }
    const fs::path& tmp() const { return m_tmp; }

    // Which GL implementation is present decides whether the GPU rows run (on llvmpipe they would measure
    // the CPU again, slower).
    void probe_machine() {
        auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 64, .debug = false});
        m_machine = profiling::machine_info(bool(ctx));
        m_hardware_gpu = ctx && !gfx::software_renderer_name(ctx->renderer());
    }

    // Whether row `id` runs (--only: its id starts with one of the given beginnings). Asked once per row,
    // before anything is measured for it; remembers every id for the message when a beginning matched none.
    bool wants(const std::string& id) {
        m_ids.push_back(id);
        bool wanted = m_only.empty();
        for (std::size_t i = 0; i < m_only.size(); ++i)
            if (id.rfind(m_only[i], 0) == 0) wanted = true, ++m_only_matched[i];
        return wanted && !m_dry;
    }
    // The --only beginnings no row id starts with (a typo would otherwise measure nothing, silently).
    std::vector<std::string> unmatched() const {
        std::vector<std::string> out;
        for (std::size_t i = 0; i < m_only.size(); ++i)
            if (m_only_matched[i] == 0) out.push_back(m_only[i]);
        return out;
    }
    const std::vector<std::string>& ids() const { return m_ids; }
    const std::vector<std::string>& only() const { return m_only; }

    Row& add(Row row) {
        m_rows.push_back(std::move(row));
        return m_rows.back();
    }

    // One profiled run, cached by its settings (several rows read the same run).
    const ProfileReport* profile(const RunSetup& s, std::string* error) {
        const std::string key = s.scene + "|" + std::to_string(s.frames) + "|" + s.quality + "|" + s.backend +
                                "|" + s.drive + "|" + (s.sync ? "sync" : "queries") + "|" + s.basis + "|" +
                                (s.deformation_only ? "deform" : "engine");
        for (const auto& [k, r] : m_runs)
            if (k == key) return &r;
        auto r = run_profile(s);
        if (!r) {
            *error = r.message();
            return nullptr;
        }
        m_runs.emplace_back(key, std::move(r->report));
        return &m_runs.back().second;
    }

private:
    bool m_full, m_dry;
    fs::path m_tmp;
    std::vector<std::string> m_only;
    std::vector<int> m_only_matched;
    std::vector<std::string> m_ids;
    bool m_hardware_gpu = false;
    profiling::MachineInfo m_machine;
    std::vector<Row> m_rows;
    std::vector<std::pair<std::string, ProfileReport>> m_runs;
};

void finish(Row& r, std::optional<double> value) {
    r.load = load_average();
    r.value = value;
    if (!value) r.status = "not measured";
    else if (!r.target) r.status = "info";
    else r.status = (r.higher_is_better ? *value >= *r.target : *value <= *r.target) ? "met" : "missed";
    // A full suite runs for many minutes: each row says how it ended as soon as it is known.
    std::fprintf(
        stderr, "profile --suite: %s: %s\n", r.id.c_str(),
        value ? (std::to_string(*value) + " " + r.unit + " (" + r.status + ")").c_str() : r.note.c_str());
}

void not_measured(Row& r, std::string why) {
    r.note = std::move(why);
    finish(r, std::nullopt);
}

RunSetup setup(std::string scene, int frames, std::string quality, std::string drive) {
    RunSetup s;
    s.scene = std::move(scene);
    s.frames = frames;
    s.warmup = 2;
    s.quality = std::move(quality);
    s.drive = std::move(drive);
    s.sync = true;  // on llvmpipe timer queries under-report; on a GPU glFinish makes frame rows conservative
    return s;
}

// A frame row: the median (or p95) frame time of a profiled engine run. A GPU row's frame is what a
// window would sustain: the larger of the CPU's frame time and the GPU's (the sum of the passes' timer
// queries, trustworthy on hardware), with no glFinish between passes. Synchronised, each of a frame's
// dozen passes waits a driver round trip: on an NVIDIA H200 that made the 59,650-splat sphere 1.9 ms.
void frame_row(Suite& suite, Row r, RunSetup s, bool p95 = false) {
    if (!suite.wants(r.id)) return;
    if (r.gpu_only) s.sync = false;
    r.how = "profile " + s.scene + " --quality " + s.quality + " --backend " + s.backend + " --drive '" +
            s.drive + "'" + (s.sync ? " --sync" : "") + " --frames " + std::to_string(s.frames) +
            (p95 ? " (p95)" : " (p50)");
    Row& row = suite.add(std::move(r));
    if (row.gpu_only && !suite.hardware_gpu()) return not_measured(row, "not measured (no GPU)");
    std::string error;
    const ProfileReport* rep = suite.profile(s, &error);
    if (!rep) return not_measured(row, error);
    const double cpu = p95 ? rep->frame_ms.p95 : rep->frame_ms.p50;
    if (!row.gpu_only) return finish(row, cpu);
    double gpu = 0.0;
    for (const profiling::TimingRow& pass : rep->passes)
        if (pass.gpu_ms) gpu += p95 ? pass.gpu_ms->p95 : pass.gpu_ms->p50;
    char note[160];
    std::snprintf(note, sizeof note, "CPU %.3g ms, GPU %.3g ms (sum of the passes' timer queries)", cpu, gpu);
    row.note = note;
    finish(row, std::max(cpu, gpu));
}

// A deformation row: the median time of one system in a deformation-only run (residency + deformers).
// gpu: the system's GPU time (timer queries); cpu_time: its CPU time with the GPU path (submission cost).
enum class Measure { cpu, gpu, cpu_time };
void measure_deformation(Suite& suite, Row& row, const RunSetup& s, const std::string& system, Measure m) {
    if (m != Measure::cpu && !suite.hardware_gpu()) return not_measured(row, "not measured (no GPU)");
    std::string error;
    const ProfileReport* rep = suite.profile(s, &error);
    if (!rep) return not_measured(row, error);
    const profiling::TimingRow* t = find_row(rep->systems, system);
    if (!t) return not_measured(row, "the run has no system '" + system + "'");
    if (m == Measure::gpu && !t->gpu_ms) return not_measured(row, "no GPU time was measured");
    // The spread beside the median: one run of the CPU-time row once read 3x its other runs.
    const profiling::Stats& st = m == Measure::gpu ? *t->gpu_ms : t->cpu_ms;
    char note[128];
    std::snprintf(note, sizeof note, "%zu frames: min %.3g, p95 %.3g, max %.3g ms", st.n, st.min, st.p95,
                  st.max);
    row.note = note;
    finish(row, st.p50);
}

// Returns the row, or nullptr when --only left it out.
Row* deform_row(Suite& suite, Row r, RunSetup s, const std::string& system, Measure m) {
    if (!suite.wants(r.id)) return nullptr;
    s.deformation_only = true;
    s.sync = false;  // CPU rows have no GL context; GPU rows read timer queries (trustworthy on hardware)
    r.how = "profile --sweep points=" + s.scene.substr(s.scene.find(':') + 1) +
            " basis=" + (s.basis.empty() ? std::string("bernstein") : s.basis) + " backend=" + s.backend +
            " (" + system + " " + (m == Measure::gpu ? "GPU" : "CPU") + " p50)";
    Row& row = suite.add(std::move(r));
    measure_deformation(suite, row, s, system, m);
    return &row;
}

// A read row: a file written once, then opened through load_scene as every command opens it, three times;
// the median counts. One open alone varied 2-3x between runs of the suite on the 2-core machine (the
// same binary, surface PLY 84 vs 215 ms), more than any change it was meant to show.
void read_row(Suite& suite, Row r, const fs::path& file, const std::function<Status()>& write, bool ms) {
    if (!suite.wants(r.id)) return;
    r.how = "load_scene(" + file.filename().string() + "), median of 3";
    Row& row = suite.add(std::move(r));
    std::error_code ec;
    if (!fs::exists(file, ec)) {
        if (Status st = write(); !st) return not_measured(row, st.message());
    }
    const double mb = double(fs::file_size(file, ec)) / 1e6;
    std::array<double, 3> times{};
    for (double& read_ms : times) {
        ecs::Registry registry;
        sffd::use_engine_scene_hooks(registry);
        const auto t0 = std::chrono::steady_clock::now();
        const Status st = load_scene(registry, file.string());
        read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!st) return not_measured(row, st.message());
    }
    char note[128];
    std::snprintf(note, sizeof note, "%.1f MB in %.0f, %.0f, %.0f ms", mb, times[0], times[1], times[2]);
    row.note = note;
    std::sort(times.begin(), times.end());
    finish(row, ms ? times[1] : mb / (times[1] * 1e-3));
}

// An editor row: `splatffd view SCENE --replay FILE` in a window (a display is needed: xvfb-run -a), the
// frames in which a stretch or twist drag was live.
void editor_rows(Suite& suite, const std::string& scene, const std::string& replay_name, Row p50, Row p95) {
    const bool want_p50 = suite.wants(p50.id), want_p95 = suite.wants(p95.id);
    if (!want_p50 && !want_p95) return;  // one replay measures both
    const fs::path replay = paths::data_root() / "tests" / "data" / "editor" / replay_name;
    const fs::path json = suite.tmp() / ("view_" + scene + ".json");
    const fs::path log = suite.tmp() / ("view_" + scene + ".log");
    p50.how = p95.how =
        "view " + scene + " --replay tests/data/editor/" + replay_name + " --frames 66 --json F (1280x720)";
    suite.add(std::move(p50));
    suite.add(std::move(p95));
    auto skip = [&](const std::string& why) {
        not_measured(suite.rows()[suite.rows().size() - 2], why);
        not_measured(suite.rows().back(), why);
    };
    if (!gfx::display_available()) return skip("not measured (no display: run under xvfb-run -a)");
    if (!fs::exists(replay)) return skip("not measured (" + replay.string() + " is not installed)");
    std::fprintf(stderr, "profile --suite: view %s --replay %s\n", scene.c_str(), replay_name.c_str());
    // --save: the replay ends with ctrl+s; the scene goes to the suite's temporary folder.
    const int rc = spawn(
        {paths::executable_path().string(), "view", scene, "--replay", replay.string(), "--frames", "66",
         "--save", (suite.tmp() / ("edited_" + scene + ".glb")).string(), "--json", json.string()},
        log);
    if (rc != 0) return skip("view exited " + std::to_string(rc) + ": " + last_line(log));
    std::ifstream f(json);
    const auto j = nlohmann::json::parse(f, nullptr, false);
    if (j.is_discarded() || !j.contains("drag_frame_ms_p50") || j.value("drag_frames", 0) == 0)
        return skip("view wrote no drag frames: " + json.string());
    Row& r50 = suite.rows()[suite.rows().size() - 2];
    Row& r95 = suite.rows().back();
    finish(r50, j["drag_frame_ms_p50"].get<double>());
    finish(r95, j["drag_frame_ms_p95"].get<double>());
    r50.note = r95.note = std::to_string(j.value("drag_frames", 0)) + " drag frames";
}

// The anchor: Blender's lattice modifier on the same number of points, 11^3 B-spline (its default
// interpolation), timing its own depsgraph update (../shared/peers/blender_lattice.py).
void blender_anchor(Row& row, std::size_t points, const fs::path& tmp) {
    const std::string blender = cli::find_on_path("blender");
    const fs::path script = paths::data_root() / ".." / "shared" / "peers" / "blender_lattice.py";
    if (blender.empty()) {
        row.anchor = "Blender: not installed (skipped)";
        return;
    }
    if (!fs::exists(script)) {
        row.anchor = "Blender: " + script.string() + " not found (skipped)";
        return;
    }
    const fs::path log = tmp / "blender.log";
    const int rc = spawn({blender, "-b", "--factory-startup", "--python", script.string(), "--",
                          std::to_string(points), "11", "KEY_BSPLINE"},
                         log);
    std::ifstream f(log);
    std::string line;
    while (std::getline(f, line)) {
        const auto at = line.find("median_ms=");
        if (line.rfind("BLENDER_LATTICE", 0) == 0 && at != std::string::npos) {
            row.anchor =
                "Blender lattice modifier: " + line.substr(at + 10, line.find(' ', at) - at - 10) + " ms";
            return;
        }
    }
    row.anchor = "Blender: exit " + std::to_string(rc) + ", no timing line (" + log.string() + ")";
}

// A claim: lower is better, in ms, unless made with mb_per_s(); no target = information at this size.
Row claim(std::string id, std::string text, std::string source, std::optional<double> target = std::nullopt,
          bool gpu_only = false) {
    Row r;
    r.id = std::move(id);
    r.claim = std::move(text);
    r.source = std::move(source);
    r.target = target;
    r.gpu_only = gpu_only;
    return r;
}

Row mb_per_s(std::string id, std::string text, std::string source, double target) {
    Row r = claim(std::move(id), std::move(text), std::move(source), target);
    r.unit = "MB/s";
    r.higher_is_better = true;
    return r;
}

void make_rows(Suite& suite) {
    const bool full = suite.full();
    const std::string readme = "README: Performance";
    const std::string results = "systems/splat_render/RESULTS.md";
    const int f = full ? 30 : 8;  // measured frames per frame row
    const std::string n = full ? "1m" : "100k";
    const std::optional<double> none;

    // Frame times of the built-in sphere (render only: the lattice still), the renderer's own claims.
    frame_row(suite, claim("sphere.preview", "sphere 59,650 splats, preview frame", results, 30.0),
              setup("sphere", f, "preview", "none"));
    frame_row(suite, claim("sphere.hq", "sphere 59,650 splats, HQ frame", results, 65.0),
              setup("sphere", f, "hq", "none"));
    // Editing: deformation + HQ every frame.
    frame_row(suite, claim("sphere.edit_hq", "sphere, deformed every frame + HQ", readme),
              setup("sphere", f, "hq", "global twist"));
    {
        RunSetup s = setup("sphere", f, "hq", "global twist");
        s.backend = "gpu";
        frame_row(suite, claim("gpu.sphere.frame", "sphere, GPU deformation + HQ frame", readme, 1.0, true),
                  s);
    }

    // The editor at 1280x720 with its panels, while dragging (a window: xvfb-run -a); full only.
    if (full) {
        editor_rows(suite, "sphere", "session.txt",
                    claim("editor.sphere.drag_p50", "editor, sphere, dragging p50", readme, 30.0),
                    claim("editor.sphere.drag_p95", "editor, sphere, dragging p95", readme, 45.0));
        editor_rows(suite, "face", "face_session.txt",
                    claim("editor.face.drag_p50", "editor, face, dragging p50", readme, 30.0),
                    claim("editor.face.drag_p95", "editor, face, dragging p95", readme, 45.0));
    }

    // CPU deformation of surface splats (positions + normals), with Blender's modifier as the anchor.
    {
        RunSetup s = setup("synthetic:" + n, full ? 10 : 8, "hq", "global twist");
        s.backend = "cpu";
        s.basis = "bspline";
        if (Row* r = deform_row(
                suite, claim("deform.cpu." + n, n + " splats, CPU deformation 11^3 B-spline", readme), s,
                "ffd", Measure::cpu))
            blender_anchor(*r, full ? 1'000'000 : 100'000, suite.tmp());
    }

    // Gaussians: deformation (J S J^T and SH degree 3 on the CPU) and the frame while moving (preview).
    {
        RunSetup s = setup("synthetic-gaussians:" + n + ":sh3", full ? 5 : 6, "hq", "global twist");
        s.backend = "cpu";
        deform_row(suite,
                   claim("gaussians.deform_cpu." + n, n + " Gaussians SH 3, CPU deformation", readme,
                         full ? std::optional<double>(150.0) : none),
                   s, "gaussian", Measure::cpu);
    }
    frame_row(suite,
              claim("gaussians.moving." + n, n + " Gaussians, frame while moving (preview)", readme,
                    full ? std::optional<double>(250.0) : none),
              setup("synthetic-gaussians:" + n, full ? 6 : 3, "preview", "global twist"));

    // Reading files: generated once into the suite's temporary folder, opened as every command opens them.
    {
        const std::size_t count = full ? 1'000'000 : 100'000;
        const fs::path g = suite.tmp() / ("gaussians_" + n + ".ply");
        const fs::path p = suite.tmp() / ("splats_" + n + ".ply");
        const fs::path b = suite.tmp() / ("splats_" + n + ".glb");
        const fs::path gg = suite.tmp() / ("gaussians_" + n + ".glb");
        auto gaussians = [&] {
            GaussianCloud c = gaussian::gaussians_from_splats(profiling::synthetic_sphere(count));
            const std::size_t k = 16;
            std::vector<float> sh(c.size() * k * 3, 0.01f);
            for (std::size_t i = 0; i < c.size(); ++i)
                for (std::size_t ch = 0; ch < 3; ++ch) sh[i * k * 3 + ch] = c.sh[i * 3 + ch];
            c.sh = std::move(sh);
            c.sh_degree = 3;
            return c;
        };
        auto write_g = [&] { return gaussian::write_ply(g, gaussians()); };
        auto write_gg = [&] { return gaussian::write_glb(gg, gaussians()); };
        auto write_p = [&] { return assets::save_splat_ply(profiling::synthetic_sphere(count), p); };
        auto write_b = [&] { return assets::save_splat_glb(profiling::synthetic_sphere(count), b); };
        read_row(suite, mb_per_s("read.3dgs_ply", n + " Gaussians SH 3, 3DGS PLY read", readme, 400.0), g,
                 write_g, false);
        if (full)
            read_row(suite,
                     claim("read.3dgs_ply.1m_ms", "1M Gaussians SH 3 (248 MB), 3DGS PLY read", readme, 600.0),
                     g, write_g, true);
        read_row(suite, mb_per_s("read.surface_ply", n + " splats, surface PLY read", readme, 400.0), p,
                 write_p, false);
        read_row(suite, mb_per_s("read.glb", n + " splats, GLB read", readme, 400.0), b, write_b, false);
        read_row(suite,
                 mb_per_s("read.gaussian_glb", n + " Gaussians SH 3, KHR_gaussian_splatting GLB read", readme,
                          400.0),
                 gg, write_gg, false);
    }
    if (!full) return;

    // Large surface clouds on the CPU path (llvmpipe) and on a GPU.
    frame_row(suite, claim("splats.600k.preview", "600k splats, preview frame", results, 130.0),
              setup("synthetic:600k", 10, "preview", "none"));
    frame_row(suite, claim("splats.600k.hq", "600k splats, HQ frame", results, 250.0),
              setup("synthetic:600k", 10, "hq", "none"));
    frame_row(suite, claim("splats.1m.preview_moving", "1M splats, deformed + preview frame", readme, 100.0),
              setup("synthetic:1m", 10, "preview", "global twist"));
    frame_row(suite, claim("splats.4m.preview_moving", "4M splats, deformed + preview frame", readme),
              setup("synthetic:4m", 4, "preview", "global twist"));
    frame_row(suite, claim("gaussians.moving.4m", "4M Gaussians, frame while moving (preview)", readme),
              setup("synthetic-gaussians:4m", 3, "preview", "global twist"));
    for (const std::string size : {"1m", "4m", "16m"}) {
        RunSetup s = setup("synthetic:" + size, 30, "hq", "global twist");
        s.backend = "gpu";
        frame_row(suite,
                  claim("gpu.splats." + size + ".deform_hq", size + " splats, GPU deformation + HQ", readme,
                        size == "16m" ? std::optional<double>(16.7) : none, true),
                  s);
    }
    for (const std::string basis : {"bernstein", "bspline"}) {
        RunSetup s = setup("synthetic:1m", 30, "hq", "global twist");
        s.backend = "gpu";
        s.basis = basis;
        deform_row(suite,
                   claim("gpu.deform." + basis + ".1m", "1M splats, GPU deformation 11^3 " + basis, readme,
                         basis == "bernstein" ? 0.6 : 0.15, true),
                   s, "ffd", Measure::gpu);
    }
    for (const std::string size : {"1m", "16m"}) {
        RunSetup s = setup("synthetic:" + size, 30, "hq", "global twist");
        s.backend = "gpu";
        deform_row(suite,
                   claim("gpu.deform.cpu_time." + size, size + " splats, CPU time of the GPU deformation",
                         readme, 0.1, true),
                   s, "ffd", Measure::cpu_time);
    }
    // Gaussians deformed on the GPU (information, no target): SH degree 0, which writes neither frames nor
    // coefficients, and degree 3 with frames (the engine's default mode), each its own program.
    for (const std::string sh : {"", ":sh3"}) {
        RunSetup s = setup("synthetic-gaussians:1m" + sh, 30, "hq", "global twist");
        s.backend = "gpu";
        deform_row(suite,
                   claim("gpu.gaussians.deform.1m" + std::string(sh.empty() ? "" : ".sh3"),
                         "1M Gaussians" + std::string(sh.empty() ? "" : " SH 3") +
                             ", GPU deformation 11^3 Bernstein",
                         readme, none, true),
                   s, "gaussian", Measure::gpu);
    }
}

std::string fmt(std::optional<double> v) {
    if (!v) return "-";
    char b[32];
    std::snprintf(b, sizeof b, *v < 10 ? "%.3g" : "%.1f", *v);
    return b;
}

std::string to_table(Suite& suite, const std::string& kind) {
    const auto& m = suite.machine();
    std::string only;
    for (const std::string& o : suite.only()) only += (only.empty() ? "" : ",") + o;
    std::string out = "performance suite (" + kind + (only.empty() ? "" : ", --only " + only) +
                      ")\nmachine: " + m.cpu + ", " + std::to_string(m.cores) +
                      " cores; GL: " + (m.gl_renderer.empty() ? "none" : m.gl_renderer) + " (" +
                      (suite.hardware_gpu() ? "GPU" : "software: GPU rows not measured") + ")\n";
    char line[512];
    std::snprintf(line, sizeof line, "%-28s %-46s %9s %9s %-6s %-12s %5s  %s\n", "id", "claim", "target",
                  "value", "unit", "status", "load", "notes");
    out += line;
    for (const Row& r : suite.rows()) {
        const std::string target =
            r.target ? std::string(r.higher_is_better ? ">= " : "<= ") + fmt(r.target) : "-";
        std::string notes = r.note;
        if (!r.anchor.empty()) notes += (notes.empty() ? "" : "; ") + r.anchor;
        char load[16];
        std::snprintf(load, sizeof load, "%.1f", r.load);
        std::snprintf(line, sizeof line, "%-28s %-46s %9s %9s %-6s %-12s %5s  %s\n", r.id.c_str(),
                      r.claim.c_str(), target.c_str(), fmt(r.value).c_str(), r.unit.c_str(), r.status.c_str(),
                      load, notes.c_str());
        out += line;
    }
    return out;
}

std::string to_json(Suite& suite, const std::string& kind) {
    const auto& m = suite.machine();
    auto num = [](std::optional<double> v) {
        if (!v) return std::string("null");
        char b[32];
        std::snprintf(b, sizeof b, "%.6g", *v);
        return std::string(b);
    };
    std::string only;  // a partial suite says which rows it ran, so it is not read as the whole suite
    for (const std::string& o : suite.only()) only += (only.empty() ? "" : ", ") + json_quote(o);
    std::string out =
        "{\n  \"format\": \"splatffd-suite\",\n  \"version\": 1,\n  \"suite\": " + json_quote(kind) +
        (suite.only().empty() ? std::string() : ",\n  \"only\": [" + only + "]") +
        ",\n  \"machine\": {\"cpu\": " + json_quote(m.cpu) + ", \"cores\": " + std::to_string(m.cores) +
        ", \"os\": " + json_quote(m.os) + ", \"gl_renderer\": " + json_quote(m.gl_renderer) +
        ", \"gl_version\": " + json_quote(m.gl_version) +
        ", \"gpu\": " + (suite.hardware_gpu() ? "true" : "false") + "},\n  \"rows\": [";
    bool first = true;
    for (const Row& r : suite.rows()) {
        out += first ? "\n" : ",\n";
        first = false;
        out += "    {\"id\": " + json_quote(r.id) + ", \"claim\": " + json_quote(r.claim) +
               ", \"source\": " + json_quote(r.source) + ", \"unit\": " + json_quote(r.unit) +
               ", \"better\": " + (r.higher_is_better ? "\"higher\"" : "\"lower\"") +
               ", \"target\": " + num(r.target) + ", \"gpu_only\": " + (r.gpu_only ? "true" : "false") +
               ", \"value\": " + num(r.value) + ", \"status\": " + json_quote(r.status) +
               ", \"how\": " + json_quote(r.how) + ", \"note\": " + json_quote(r.note) +
               ", \"anchor\": " + json_quote(r.anchor) + ", \"load_average\": " + num(r.load) + "}";
    }
    return out + "\n  ]\n}\n";
}

}  // namespace

int run_suite(const Options& o) {
    const bool full = o.suite == "full";
    std::error_code ec;
    const fs::path tmp = fs::temp_directory_path(ec) / ("splatffd_suite_" + std::to_string(::getpid()));
    fs::create_directories(tmp, ec);
    if (ec) {
        std::fprintf(stderr, "splatffd profile: --suite: cannot make the temporary folder %s: %s\n",
                     tmp.c_str(), ec.message().c_str());
        return 1;
    }
    // --only is checked against the rows' ids before anything runs: a beginning that matches no row is a
    // typo (or a row of the other suite), and the message lists the ids.
    if (!o.only.empty()) {
        Suite list(full, tmp, o.only, true);
        make_rows(list);
        if (const std::vector<std::string> none = list.unmatched(); !none.empty()) {
            fs::remove_all(tmp, ec);
            std::string ids;
            for (const std::string& id : list.ids()) ids += "\n  " + id;
            std::fprintf(
                stderr,
                "splatffd profile: --suite %s: --only %s: no row id starts with it; the rows are:%s\n",
                o.suite.c_str(), none.front().c_str(), ids.c_str());
            return 2;
        }
    }
    Suite suite(full, tmp, o.only);
    suite.probe_machine();
    std::fprintf(stderr, "profile --suite %s: GL %s (%s)\n", o.suite.c_str(),
                 suite.machine().gl_renderer.empty() ? "none" : suite.machine().gl_renderer.c_str(),
                 suite.hardware_gpu() ? "GPU rows measured" : "no GPU: GPU rows not measured");
    make_rows(suite);
    fs::remove_all(tmp, ec);
    std::printf("%s", to_table(suite, o.suite).c_str());
    if (!o.json.empty()) {
        if (Status st = write_text(o.json, to_json(suite, o.suite)); !st) {
            cli::command_error("profile", st.message());
            return 1;
        }
        std::printf("wrote %s\n", o.json.c_str());
    }
    return 0;
}

}  // namespace sffd::profile_cmd
