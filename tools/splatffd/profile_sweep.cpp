// `splatffd profile --sweep`: the deformation phase (ffd_system alone, CPU or GPU path) over point counts,
// lattice sizes and bases; a table, plots (time vs points, time vs lattice size) and JSON rows.
#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "systems/profiling/svg_plot.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/profile_run.h"

namespace sffd::profile_cmd {

using namespace profiling;

namespace {

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
            if (by_points)
                std::snprintf(key, sizeof key, "%s %s, %d^3", r.backend.c_str(), r.basis.c_str(), r.lattice);
            else
                std::snprintf(key, sizeof key, "%s %s, %s pts", r.backend.c_str(), r.basis.c_str(),
                              tick_label(r.points).c_str());
            if (!series.count(key))
                order.push_back(key), series[key].name = key, series[key].dashed = r.backend == "gpu";
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
            cli::command_error("profile", st.message());
            return 1;
        }
        std::printf("wrote %s\n", path.c_str());
    }
    return 0;
}

}  // namespace

// --plot-sweep F.json: re-draws the plots of a sweep written with --json (no measuring).
int plot_sweep(const std::string& path, const std::string& prefix) {
    const auto text = read_text(path);
    if (!text) {
        cli::command_error("profile", path + ": cannot read the sweep file");
        return 1;
    }
    const auto j = nlohmann::json::parse(*text, nullptr, false);
    if (j.is_discarded() || j.value("format", "") != "splatffd-sweep" || !j.contains("rows") ||
        !j["rows"].is_array()) {
        std::fprintf(stderr,
                     "splatffd profile: %s: not a sweep written by 'splatffd profile --sweep ... --json'\n",
                     path.c_str());
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
        std::fprintf(stderr, "splatffd profile: %s: malformed sweep row: %s\n", path.c_str(), e.what());
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
        if (!axes.count(key))
            return usage_error("--sweep: unknown key '" + key + "' (points, lattice, backend, basis)");
        std::vector<std::string> values;
        std::stringstream ss(kv.substr(eq + 1));
        for (std::string v; std::getline(ss, v, ',');)
            if (!v.empty()) values.push_back(v);
        if (values.empty()) return usage_error("--sweep: no values for '" + key + "'");
        for (const auto& v : values) {
            double d = 0;
            int n = 0;
            if (key == "points" && !parse_count(v, d))
                return usage_error("--sweep: bad point count '" + v + "'");
            if (key == "lattice" && (!parse_int(v, n) || n < 2 || n > 65))
                return usage_error("--sweep: lattice takes control points per axis, 2..65, got '" + v + "'");
            if (key == "backend" && v != "cpu" && v != "gpu") return usage_error("--sweep: backend cpu|gpu");
            if (key == "basis" && v != "bernstein" && v != "bspline")
                return usage_error("--sweep: basis bernstein|bspline");
        }
        axes[key] = values;
    }
    std::vector<SweepRow> rows;
    std::printf(
        "sweep: %d measured frames + %d warm-up per configuration, deformation phase only, drive '%s'\n",
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
                            if (ph.name == "deformation")
                                row.deform_p50 = ph.cpu_ms.p50, row.deform_p95 = ph.cpu_ms.p95;
                        row.frame_p50 = r->report.frame_ms.p50;
                        // The row must measure the path it names: ffd_system falls back to the CPU when the
                        // GPU path is unavailable.
                        for (const auto& [key, value] : r->report.config)
                            if (key == (backend == "gpu" ? "ffd_cpu_runs" : "ffd_gpu_runs") &&
                                std::get<double>(value) > 0)
                                row.note = "ffd_system also ran its " +
                                           std::string(backend == "gpu" ? "CPU" : "GPU") + " path (" +
                                           std::to_string(static_cast<long long>(std::get<double>(value))) +
                                           " runs)";
                        machine_line =
                            r->report.machine.cpu + ", " + std::to_string(r->report.machine.cores) +
                            " cores" +
                            (r->report.machine.gl_renderer.empty() ? ""
                                                                   : ", GL " + r->report.machine.gl_renderer);
                        timing_line = r->report.gpu_timing;
                    }
                    std::printf("%9.0f %7d %7s %9s %12.3f %12.3f %12.3f  %s\n", row.points, row.lattice,
                                row.backend.c_str(), row.basis.c_str(), row.deform_p50, row.deform_p95,
                                row.frame_p50, row.note.c_str());
                    std::fflush(stdout);
                    rows.push_back(row);
                }
    std::printf("machine: %s\n", machine_line.c_str());

    if (!o.svg.empty())
        if (int rc = write_sweep_plots(rows, o.svg); rc != 0) return rc;
    if (!o.json.empty()) {
        std::string j =
            "{\n  \"format\": \"splatffd-sweep\",\n  \"machine\": \"" + machine_line + "\",\n  \"rows\": [\n";
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
            cli::command_error("profile", st.message());
            return 1;
        }
        std::printf("wrote %s\n", o.json.c_str());
    }
    const bool any_failed = std::any_of(
        rows.begin(), rows.end(), [](const SweepRow& r) { return r.deform_p50 < 0 || !r.note.empty(); });
    return any_failed ? 1 : 0;
}

}  // namespace sffd::profile_cmd
