// splatffd profile: frame-time profiling of the engine's schedule, parameter sweeps, regression checks
// against a baseline, and the seed paper's timing table. The measuring machinery is systems/profiling;
// one run is profile_run.cpp, --sweep profile_sweep.cpp, --paper profile_paper.cpp; this file parses the
// options, prints and writes the report and compares it with a baseline.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>

#include "systems/profiling/report.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/profile_run.h"

namespace sffd::profile_cmd {

namespace {

using namespace profiling;

constexpr const char* usage_text =
    "usage: splatffd profile [SCENE] [--frames N] [--warmup W] [--quality hq|preview] [--raster "
    "auto|raster|compute]\n"
    "                        [--backend auto|cpu|gpu] [--sync] [--drive CASE|none] [--json F] [--csv F] "
    "[--svg "
    "F]\n"
    "                        [--trace F] [--compare BASE.json] [--sweep K=V,..] [--plot-sweep F.json] "
    "[--paper]\n"
    "                        [--preview-budget N] [--sprite-raster auto|raster|cpu] [--naive-frames N]\n"
    "                        [--suite quick|full [--only ID,..]]\n"
    "                        [--splat-budget N] [--memory-budget MB] [--lod-error PX] [--full-detail]\n"
    "  SCENE                 built-in name (sphere, face), a scene/point-cloud file, or synthetic:N\n"
    "                        (a sphere of N splats with an 11^3 lattice), synthetic-gaussians:N (that\n"
    "                        sphere as N 3D Gaussians; Gaussian files work as SCENE too). Default: sphere\n"
    "  --frames N|0:B        measured frames, after the warm-up (default 120)\n"
    "  --warmup W            frames run before measuring (default 10)\n"
    "  --quality hq|preview  render quality (default hq); preview frames are the editor's frames while\n"
    "                        moving: a cloud over the preview budget is deformed and drawn as a spread\n"
    "                        subset of that many points, enlarged (systems/ffd README, Preview budget)\n"
    "  --preview-budget N    points per cloud in preview frames (default 100000; 0: every point)\n"
    "  --raster auto|raster|compute  HQ splat rasteriser: the fixed-function one, the compute one\n"
    "                        (hybrid: sprites > 8 px stay on the rasteriser), or by splat size (default)\n"
    "  --sprite-raster auto|raster|cpu  who draws the splats' sprites (preview frames, the HQ\n"
    "                        visibility pass): GL point sprites, the CPU's ray casts (uploaded), or cpu on\n"
    "                        a software rasterizer (default)\n"
    "  --backend auto|cpu|gpu  deformation backend (default auto: the engine's own choice, the CPU on a\n"
    "                        software rasterizer; the one used is printed; cpu runs without a GL context\n"
    "                        when the renderer is not wanted)\n"
    "  --sync                time GPU passes with glFinish + CPU clock instead of timer queries\n"
    "                        (timer queries are not trustworthy on llvmpipe; default: timer queries)\n"
    "  --drive CASE|none     deform every lattice each frame with a paper case, animated over time:\n"
    "                        'global twist' (default), 'global stretch', 'local twist', 'local stretch';\n"
    "                        or orbit: the camera circles the scene's centre once every 10 s, in to\n"
    "                        40% of its distance and out twice a turn; the lattices stay (a\n"
    "                        hierarchy's memory while its cut follows the camera)\n"
    "                        A hierarchy (lod-meta.json, a Potree 2 metadata.json) streams, and one\n"
    "                        without a lattice gets an 11^3 lattice around its box\n"
    "  --json F --csv F --svg F --trace F   write the report / per-frame CSV / frame-time chart /\n"
    "                        Chrome trace-event JSON (open in ui.perfetto.dev)\n"
    "  --compare BASE.json   exit 3 when a system or pass is slower than in BASE by more than the\n"
    "                        measured spread (see systems/profiling/README.md); a BASE of another scene,\n"
    "                        quality, backend, drive, rasteriser, budget or GPU timing is refused (exit 1),\n"
    "                        naming what differs\n"
    "  --sweep K=V,.. ..     sweep points=60k,250k,1m lattice=4,11,21 backend=cpu,gpu\n"
    "                        basis=bernstein,bspline (any subset); prints a table; --svg PREFIX writes\n"
    "                        PREFIX_points.svg and PREFIX_lattice.svg; --json F writes all rows\n"
    "  --plot-sweep F.json   re-draw the plots of a sweep saved with --json (with --svg PREFIX)\n"
    "  --paper               the seed paper's table: sphere and face, 11^3 control points, four cases;\n"
    "                        naive paper CPU algorithm vs ffd_system's CPU and GPU paths, paper mode\n"
    "                        (minutes: progress is shown on a terminal)\n"
    "  --naive-frames N      frames of the naive paper algorithm per case (default 1; about a minute\n"
    "                        each; 0 skips it)\n"
    "  --suite quick|full    every performance claim of the project side by side: target, value measured\n"
    "                        here, met/missed, Blender's lattice modifier as anchor when installed, the\n"
    "                        machine; --json F writes it. quick: small sizes (CI, under 2 minutes); full:\n"
    "                        1M-16M splats, 1M/4M Gaussians, editor replays (needs a display: xvfb-run -a);\n"
    "                        GPU rows are measured on a hardware GPU only\n"
    "  --only ID,..          with --suite: only the rows whose ids start with one of these (e.g.\n"
    "                        gpu.deform.cpu_time, read.): measure one claim again without the rest\n";

}  // namespace

int usage_error(const std::string& message) { return cli::usage_error("profile", message, usage_text); }

namespace {

// A setting of a report as text ("" when the report has none).
std::string setting(const ProfileReport& r, const std::string& key) {
    for (const auto& [k, v] : r.config) {
        if (k != key) continue;
        if (const auto* t = std::get_if<std::string>(&v)) return *t;
        if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
        char n[32];
        std::snprintf(n, sizeof n, "%.17g", std::get<double>(v));
        return n;
    }
    return "";
}

// The settings that decide what a frame does: a baseline that differs in one measured something else, so
// its times say nothing about a regression. "" when they agree, else what differs, named.
std::string different_settings(const ProfileReport& base, const ProfileReport& current) {
    static const char* const keys[] = {
        "scene",   "points",        "gaussians",      "quality",
        "raster",  "sprite_raster", "preview_budget", "gaussian_preview_budget",
        "backend", "drive",         "schedule"};
    std::string out;
    const auto add = [&](const std::string& key, const std::string& b, const std::string& c) {
        out += (out.empty() ? "" : ", ") + key + " '" + b + "' (this run '" + c + "')";
    };
    for (const char* key : keys)
        if (const std::string b = setting(base, key), c = setting(current, key); b != c) add(key, b, c);
    if (base.gpu_timing != current.gpu_timing) add("gpu_timing", base.gpu_timing, current.gpu_timing);
    return out;
}

// The same check before measuring, for the settings the options already decide.
std::string different_options(const ProfileReport& base, const Options& o) {
    std::string out;
    const std::pair<const char*, std::string> given[] = {
        {"scene", o.scene}, {"quality", o.quality}, {"backend", o.backend}, {"drive", o.drive}};
    for (const auto& [key, value] : given)
        if (const std::string b = setting(base, key); !b.empty() && b != value)
            out += (out.empty() ? "" : ", ") + std::string(key) + " '" + b + "' (this run '" + value + "')";
    return out;
}

int refuse_baseline(const std::string& base_path, const std::string& differs) {
    return cli::command_error("profile", base_path + ": a baseline of another run: " + differs +
                                             "; measure the baseline with the same scene and options");
}

int compare_with(const ProfileReport& current, const std::string& base_path) {
    const auto text = read_text(base_path);
    if (!text) {
        cli::command_error("profile", base_path + ": cannot read the baseline report");
        return 1;
    }
    auto base = report_from_json(*text, base_path);
    if (!base) {
        cli::command_error("profile", base.message());
        return 1;
    }
    if (const std::string differs = different_settings(*base, current); !differs.empty())
        return refuse_baseline(base_path, differs);
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
            cli::command_error("profile", st.message());
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

// Every input and output path checked before measuring (`--compare nosuch.json` used to fail only after
// the whole run): the baseline must read and parse as a report, each output's folder must exist.
int check_paths_before_work(const Options& o) {
    if (!o.compare.empty()) {
        const auto text = read_text(o.compare);
        if (!text) {
            cli::command_error("profile", o.compare + ": cannot read the baseline report");
            return 1;
        }
        auto base = report_from_json(*text, o.compare);
        if (!base) {
            cli::command_error("profile", base.message());
            return 1;
        }
        if (const std::string differs = different_options(*base, o); !differs.empty())
            return refuse_baseline(o.compare, differs);
    }
    for (const std::string* out : {&o.json, &o.csv, &o.trace}) {
        if (out->empty()) continue;
        const std::filesystem::path folder = std::filesystem::path(*out).parent_path();
        if (!folder.empty() && !std::filesystem::is_directory(folder)) {
            cli::command_error("profile", *out + ": folder " + folder.string() + " does not exist");
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
        if (cli::is_help(a)) {
            return cli::help(std::string(usage_text) + cli::kStreamUsage);
        } else if (const int taken = cli::parse_stream_option("profile", args, i, o.stream); taken != 0) {
            if (taken < 0) return 2;
        } else if (a == "--frames") {
            // One meaning of --frames in every command (N, or 0:B); measuring starts at frame 0.
            std::string v;
            auto range = value(v) ? cli::parse_frames(v, 9'999'999)
                                  : Result<cli::FrameRange>(make_error("--frames needs a value"));
            if (!range) return usage_error(range.message());
            if (range->first != 0)
                return usage_error("--frames " + v + ": measuring starts at frame 0; use N or 0:B");
            o.frames = static_cast<int>(range->count());
        } else if (a == "--warmup") {
            if (!int_value(o.warmup)) return usage_error("--warmup takes a non-negative integer");
        } else if (a == "--naive-frames") {
            if (!int_value(o.naive_frames)) return usage_error("--naive-frames takes a non-negative integer");
        } else if (a == "--quality") {
            if (!value(o.quality) || (o.quality != "hq" && o.quality != "preview"))
                return usage_error("--quality hq|preview");
        } else if (a == "--preview-budget") {
            if (!int_value(o.preview_budget))
                return usage_error("--preview-budget takes a non-negative integer");
        } else if (a == "--raster") {
            if (!value(o.raster) || (o.raster != "auto" && o.raster != "raster" && o.raster != "compute"))
                return usage_error("--raster auto|raster|compute");
        } else if (a == "--sprite-raster") {
            if (!value(o.sprite_raster) ||
                (o.sprite_raster != "auto" && o.sprite_raster != "raster" && o.sprite_raster != "cpu"))
                return usage_error("--sprite-raster auto|raster|cpu");
        } else if (a == "--backend") {
            if (!value(o.backend) || (o.backend != "auto" && o.backend != "cpu" && o.backend != "gpu"))
                return usage_error("--backend auto|cpu|gpu");
        } else if (a == "--drive") {
            if (!value(o.drive) || (o.drive != "none" && o.drive != "orbit" && !find_case(o.drive)))
                return usage_error(
                    "--drive takes 'local stretch', 'local twist', 'global stretch', 'global twist', orbit "
                    "or "
                    "none");
        } else if (a == "--sync") {
            o.sync = true;
        } else if (a == "--paper") {
            o.paper = true;
        } else if (a == "--suite") {
            if (!value(o.suite) || (o.suite != "quick" && o.suite != "full"))
                return usage_error("--suite quick|full");
        } else if (a == "--only") {
            std::string list;
            if (!value(list))
                return usage_error("--only takes row ids (or their beginnings), comma-separated");
            for (std::size_t at = 0; at <= list.size();) {
                const std::size_t comma = std::min(list.find(',', at), list.size());
                if (comma > at) o.only.push_back(list.substr(at, comma - at));
                at = comma + 1;
            }
            if (o.only.empty())
                return usage_error("--only takes row ids (or their beginnings), comma-separated");
        } else if (a == "--json" || a == "--csv" || a == "--svg" || a == "--trace" || a == "--compare") {
            std::string& target = a == "--json"    ? o.json
                                  : a == "--csv"   ? o.csv
                                  : a == "--svg"   ? o.svg
                                  : a == "--trace" ? o.trace
                                                   : o.compare;
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
    if (!o.only.empty() && o.suite.empty()) return usage_error("--only selects rows of --suite quick|full");
    if (int rc = check_paths_before_work(o); rc != 0) return rc;
    if (!o.plot_sweep.empty()) {
        if (o.svg.empty()) return usage_error("--plot-sweep needs --svg PREFIX");
        return plot_sweep(o.plot_sweep, o.svg);
    }
    if (o.paper) return run_paper(o);
    if (!o.suite.empty()) return run_suite(o);
    if (!o.sweep.empty()) return run_sweep(o);

    RunSetup s;
    s.scene = o.scene;
    s.frames = o.frames;
    s.warmup = o.warmup;
    s.quality = o.quality;
    s.backend = o.backend;
    s.raster = o.raster;
    s.sprite_raster = o.sprite_raster;
    s.preview_budget = o.preview_budget;
    s.sync = o.sync;
    s.drive = o.drive;
    s.stream = o.stream;
    auto r = run_profile(s);
    if (!r) {
        cli::command_error("profile", r.message());
        return 1;
    }
    std::printf("%s", to_text(r->report).c_str());
    std::printf("deformation backend: %s (--backend %s)\n", r->backend_used.c_str(), o.backend.c_str());
    if (int rc = write_outputs(o, *r); rc != 0) return rc;
    if (!o.compare.empty()) return compare_with(r->report, o.compare);
    return 0;
}

}  // namespace
}  // namespace sffd::profile_cmd

SFFD_COMMAND(profile, "measure frame time per system and pass; sweeps, --compare, --paper",
             sffd::profile_cmd::run_profile_command);
