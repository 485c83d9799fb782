#include "systems/profiling/report.h"

#include <sys/utsname.h>

#include <algorithm>
#include <limits>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include <nlohmann/json.hpp>

#include "runtime/gfx/gl.h"
#include "systems/profiling/svg_plot.h"

namespace sffd::profiling {

using nlohmann::json;

Stats compute_stats(std::vector<double> v) {
    Stats s;
    s.n = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    auto q = [&](double p) {
        const double pos = p * static_cast<double>(v.size() - 1);
        const auto i = static_cast<std::size_t>(std::floor(pos));
        const double f = pos - static_cast<double>(i);
        return i + 1 < v.size() ? v[i] + f * (v[i + 1] - v[i]) : v[i];
    };
    s.min = v.front();
    s.max = v.back();
    double sum = 0.0;
    for (double x : v) sum += x;
    s.mean = sum / static_cast<double>(v.size());
    s.p50 = q(0.50);
    s.p95 = q(0.95);
    s.p99 = q(0.99);
    return s;
}

MachineInfo machine_info(bool with_gl) {
    MachineInfo m;
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);)
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) m.cpu = line.substr(colon + 2);
            break;
        }
    m.cores = std::thread::hardware_concurrency();
    utsname u{};
    if (uname(&u) == 0) m.os = std::string(u.sysname) + " " + u.release;
    if (with_gl) {
        if (const auto* r = glGetString(GL_RENDERER)) m.gl_renderer = reinterpret_cast<const char*>(r);
        if (const auto* v = glGetString(GL_VERSION)) m.gl_version = reinterpret_cast<const char*>(v);
    }
    return m;
}

ProfileReport build_report(const Profiler& profiler, Config config, MachineInfo machine) {
    ProfileReport r;
    r.config = std::move(config);
    r.machine = std::move(machine);
    r.gpu_timing = gpu_timing_name(profiler.gpu_timing());

    const auto& frames = profiler.frames();
    std::vector<double> frame_ms;
    double total = 0.0;
    for (const auto& f : frames) {
        frame_ms.push_back(f.total_ms);
        total += f.total_ms;
    }
    r.frame_ms = compute_stats(frame_ms);
    r.fps_mean = total > 0.0 ? 1000.0 * static_cast<double>(frames.size()) / total : 0.0;
    r.fps_p50 = r.frame_ms.p50 > 0.0 ? 1000.0 / r.frame_ms.p50 : 0.0;

    // Per (kind, name): per-frame sums. Rows keep first-seen order (= schedule order).
    struct Acc {
        ScopeKind kind;
        std::uint32_t name;
        Phase phase;
        std::uint32_t system;
        std::vector<double> cpu, gpu;
        std::size_t calls = 0;
        bool any_gpu = false;
    };
    std::vector<Acc> accs;
    std::map<std::pair<int, std::uint32_t>, std::size_t> index;
    for (std::size_t fi = 0; fi < frames.size(); ++fi) {
        for (const ScopeSample& s : frames[fi].scopes) {
            const auto key = std::make_pair(static_cast<int>(s.kind), s.name);
            auto it = index.find(key);
            if (it == index.end()) {
                it = index.emplace(key, accs.size()).first;
                accs.push_back({s.kind, s.name, s.phase, s.system, {}, {}, 0, false});
            }
            Acc& a = accs[it->second];
            a.cpu.resize(frames.size(), 0.0);
            a.gpu.resize(frames.size(), 0.0);
            a.cpu[fi] += s.cpu_ms;
            if (s.gpu_ms >= 0.0) a.gpu[fi] += s.gpu_ms, a.any_gpu = true;
            ++a.calls;
        }
    }
    // A system's GPU time: its outermost passes (nested passes are already inside their parent).
    std::map<std::uint32_t, std::vector<double>> system_gpu;
    for (std::size_t fi = 0; fi < frames.size(); ++fi)
        for (const ScopeSample& s : frames[fi].scopes)
            if (s.kind == ScopeKind::pass && s.depth == 0 && s.system != no_name && s.gpu_ms >= 0.0) {
                auto& v = system_gpu[s.system];
                v.resize(frames.size(), 0.0);
                v[fi] += s.gpu_ms;
            }

    for (Acc& a : accs) {
        TimingRow row;
        row.name = profiler.name(a.name);
        row.phase = phase_name(a.phase);
        if (a.system != no_name) row.system = profiler.name(a.system);
        row.calls_per_frame =
            frames.empty() ? 0.0 : static_cast<double>(a.calls) / static_cast<double>(frames.size());
        a.cpu.resize(frames.size(), 0.0);
        row.cpu_ms = compute_stats(a.cpu);
        if (a.kind == ScopeKind::pass && a.any_gpu) {
            a.gpu.resize(frames.size(), 0.0);
            row.gpu_ms = compute_stats(a.gpu);
        }
        if (a.kind == ScopeKind::system) {
            if (auto it = system_gpu.find(a.name); it != system_gpu.end()) {
                it->second.resize(frames.size(), 0.0);
                row.gpu_ms = compute_stats(it->second);
            }
            r.systems.push_back(std::move(row));
        } else if (a.kind == ScopeKind::phase) {
            r.phases.push_back(std::move(row));
        } else {
            r.passes.push_back(std::move(row));
        }
    }
    return r;
}

// ---------------------------------------------------------------------------------------------- JSON

namespace {

json stats_json(const Stats& s) {
    return json{{"n", s.n},     {"min", s.min}, {"mean", s.mean}, {"p50", s.p50},
                {"p95", s.p95}, {"p99", s.p99}, {"max", s.max}};
}

Stats stats_from(const json& j) {
    Stats s;
    s.n = j.at("n").get<std::size_t>();
    s.min = j.at("min").get<double>();
    s.mean = j.at("mean").get<double>();
    s.p50 = j.at("p50").get<double>();
    s.p95 = j.at("p95").get<double>();
    s.p99 = j.at("p99").get<double>();
    s.max = j.at("max").get<double>();
    return s;
}

json rows_json(const std::vector<TimingRow>& rows, bool with_system) {
    json a = json::array();
    for (const auto& r : rows) {
        json o{{"name", r.name},
               {"phase", r.phase},
               {"calls_per_frame", r.calls_per_frame},
               {"cpu_ms", stats_json(r.cpu_ms)},
               {"gpu_ms", r.gpu_ms ? stats_json(*r.gpu_ms) : json(nullptr)}};
        if (with_system) o["system"] = r.system;
        a.push_back(std::move(o));
    }
    return a;
}

std::vector<TimingRow> rows_from(const json& a) {
    std::vector<TimingRow> rows;
    for (const auto& o : a) {
        TimingRow r;
        r.name = o.at("name").get<std::string>();
        r.phase = o.at("phase").get<std::string>();
        if (o.contains("system")) r.system = o.at("system").get<std::string>();
        r.calls_per_frame = o.at("calls_per_frame").get<double>();
        r.cpu_ms = stats_from(o.at("cpu_ms"));
        if (!o.at("gpu_ms").is_null()) r.gpu_ms = stats_from(o.at("gpu_ms"));
        rows.push_back(std::move(r));
    }
    return rows;
}

}  // namespace

std::string to_json(const ProfileReport& r) {
    json config = json::object();
    for (const auto& [k, v] : r.config) std::visit([&, key = k](const auto& x) { config[key] = x; }, v);
    json j{
        {"format", "splatffd-profile"},
        {"version", 1},
        {"config", config},
        {"machine",
         {{"cpu", r.machine.cpu},
          {"cores", r.machine.cores},
          {"os", r.machine.os},
          {"gl_renderer", r.machine.gl_renderer},
          {"gl_version", r.machine.gl_version}}},
        {"gpu_timing", r.gpu_timing},
        {"frame", {{"cpu_ms", stats_json(r.frame_ms)}, {"fps_mean", r.fps_mean}, {"fps_p50", r.fps_p50}}},
        {"phases", rows_json(r.phases, false)},
        {"systems", rows_json(r.systems, false)},
        {"passes", rows_json(r.passes, true)},
    };
    return j.dump(2) + "\n";
}

Result<ProfileReport> report_from_json(const std::string& text, const std::string& path) {
    json j = json::parse(text, nullptr, false);
    if (j.is_discarded()) return make_error(path + ": not valid JSON");
    try {
        if (j.value("format", "") != "splatffd-profile")
            return make_error(path +
                              ": not a splatffd profile report (\"format\" is not \"splatffd-profile\")");
        ProfileReport r;
        for (const auto& [k, v] : j.at("config").items()) {
            if (v.is_string()) r.config.emplace_back(k, v.get<std::string>());
            else if (v.is_boolean()) r.config.emplace_back(k, v.get<bool>());
            else if (v.is_number()) r.config.emplace_back(k, v.get<double>());
        }
        const auto& m = j.at("machine");
        r.machine.cpu = m.at("cpu").get<std::string>();
        r.machine.cores = m.at("cores").get<unsigned>();
        r.machine.os = m.at("os").get<std::string>();
        r.machine.gl_renderer = m.at("gl_renderer").get<std::string>();
        r.machine.gl_version = m.at("gl_version").get<std::string>();
        r.gpu_timing = j.at("gpu_timing").get<std::string>();
        r.frame_ms = stats_from(j.at("frame").at("cpu_ms"));
        r.fps_mean = j.at("frame").at("fps_mean").get<double>();
        r.fps_p50 = j.at("frame").at("fps_p50").get<double>();
        r.phases = rows_from(j.at("phases"));
        r.systems = rows_from(j.at("systems"));
        r.passes = rows_from(j.at("passes"));
        return r;
    } catch (const json::exception& e) {
        return make_error(path + ": malformed profile report: " + e.what());
    }
}

// ---------------------------------------------------------------------------------------------- text

namespace {
std::string fmt_row(const char* kind, const std::string& name, const Stats& s,
                    const std::optional<Stats>& g) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%-7s %-28s %9.3f %9.3f %9.3f %9.3f", kind, name.c_str(), s.p50, s.p95,
                  s.p99, s.max);
    std::string out = buf;
    if (g) {
        std::snprintf(buf, sizeof buf, "   %9.3f %9.3f %9.3f %9.3f", g->p50, g->p95, g->p99, g->max);
        out += buf;
    }
    return out + "\n";
}
}  // namespace

std::string to_text(const ProfileReport& r) {
    std::string o;
    char buf[512];
    o += "config:";
    for (const auto& [k, v] : r.config) {
        o += " " + k + "=";
        std::visit(
            [&](const auto& x) {
                using T = std::decay_t<decltype(x)>;
                if constexpr (std::is_same_v<T, std::string>) o += x;
                else if constexpr (std::is_same_v<T, bool>) o += x ? "true" : "false";
                else {
                    std::snprintf(buf, sizeof buf, "%g", x);
                    o += buf;
                }
            },
            v);
    }
    o += "\n";
    std::snprintf(buf, sizeof buf, "machine: %s, %u cores, %s; GL: %s (%s)\n", r.machine.cpu.c_str(),
                  r.machine.cores, r.machine.os.c_str(),
                  r.machine.gl_renderer.empty() ? "none" : r.machine.gl_renderer.c_str(),
                  r.machine.gl_version.c_str());
    o += buf;
    std::snprintf(buf, sizeof buf, "GPU timing: %s%s\n", r.gpu_timing.c_str(),
                  r.gpu_timing == "sync" ? " (glFinish around every pass and system + CPU clock)"
                  : r.gpu_timing == "queries"
                      ? " (GL timestamp queries; not trustworthy on llvmpipe: use --sync)"
                      : " (no GPU timing)");
    o += buf;
    std::snprintf(buf, sizeof buf,
                  "frames: %zu  frame ms p50 %.3f p95 %.3f p99 %.3f max %.3f  FPS mean %.2f p50 %.2f\n\n",
                  r.frame_ms.n, r.frame_ms.p50, r.frame_ms.p95, r.frame_ms.p99, r.frame_ms.max, r.fps_mean,
                  r.fps_p50);
    o += buf;
    std::snprintf(buf, sizeof buf, "%-7s %-28s %9s %9s %9s %9s   %9s %9s %9s %9s\n", "kind", "name",
                  "cpu p50", "p95", "p99", "max", "gpu p50", "p95", "p99", "max");
    o += buf;
    for (const auto& row : r.phases) o += fmt_row("phase", row.name, row.cpu_ms, row.gpu_ms);
    for (const auto& row : r.systems)
        o += fmt_row("system", row.phase + "/" + row.name, row.cpu_ms, row.gpu_ms);
    for (const auto& row : r.passes) o += fmt_row("pass", row.name, row.cpu_ms, row.gpu_ms);
    return o;
}

// ---------------------------------------------------------------------------------------------- CSV

std::string to_csv(const Profiler& p) {
    // Columns: every (kind, name) seen, in first-seen order.
    std::vector<std::pair<ScopeKind, std::uint32_t>> cols;
    std::set<std::pair<int, std::uint32_t>> seen;
    bool any_gpu = false;
    for (const auto& f : p.frames())
        for (const auto& s : f.scopes) {
            if (seen.insert({static_cast<int>(s.kind), s.name}).second) cols.emplace_back(s.kind, s.name);
            any_gpu |= s.gpu_ms >= 0.0;
        }
    auto kind_name = [](ScopeKind k) {
        return k == ScopeKind::phase ? "phase" : k == ScopeKind::system ? "system" : "pass";
    };
    auto quote = [](const std::string& s) {
        std::string q(1, '"');
        for (char c : s) {
            if (c == '"') q.push_back('"');
            q.push_back(c);
        }
        q.push_back('"');
        return q;
    };
    std::string o = "frame,frame_ms";
    for (const auto& [k, n] : cols) {
        o += ',';
        o += quote(std::string(kind_name(k)) + ":" + p.name(n) + ":cpu_ms");
        if (k == ScopeKind::pass && any_gpu) {
            o += ',';
            o += quote("pass:" + p.name(n) + ":gpu_ms");
        }
    }
    o += "\n";
    char buf[64];
    for (const auto& f : p.frames()) {
        std::snprintf(buf, sizeof buf, "%llu,%.6f", static_cast<unsigned long long>(f.frame), f.total_ms);
        o += buf;
        for (const auto& [k, n] : cols) {
            double cpu = 0.0, gpu = 0.0;
            bool has_gpu = false;
            for (const auto& s : f.scopes)
                if (s.kind == k && s.name == n) {
                    cpu += s.cpu_ms;
                    if (s.gpu_ms >= 0.0) gpu += s.gpu_ms, has_gpu = true;
                }
            std::snprintf(buf, sizeof buf, ",%.6f", cpu);
            o += buf;
            if (k == ScopeKind::pass && any_gpu) {
                if (has_gpu) std::snprintf(buf, sizeof buf, ",%.6f", gpu);
                else std::snprintf(buf, sizeof buf, ",");
                o += buf;
            }
        }
        o += "\n";
    }
    return o;
}

// ---------------------------------------------------------------------------------------------- trace

std::string to_chrome_trace(const Profiler& p, const std::string& process_name) {
    json events = json::array();
    events.push_back(
        {{"name", "process_name"}, {"ph", "M"}, {"pid", 1}, {"tid", 1}, {"args", {{"name", process_name}}}});
    events.push_back({{"name", "thread_name"},
                      {"ph", "M"},
                      {"pid", 1},
                      {"tid", 1},
                      {"args", {{"name", "CPU (frame loop)"}}}});
    events.push_back(
        {{"name", "thread_name"},
         {"ph", "M"},
         {"pid", 1},
         {"tid", 2},
         {"args", {{"name", std::string("GPU passes (") + gpu_timing_name(p.gpu_timing()) + ")"}}}});
    auto us = [](double ms) { return ms * 1000.0; };
    // The GPU runs passes one after another in submission order, and a pass cannot start before the CPU
    // issued it: each GPU slice starts at its pass's CPU start or at the end of the slice before, whichever
    // is later, so the GPU track's slices follow one another (Perfetto needs a track's slices to nest or be
    // apart; placed at the CPU starts, long GPU passes overlapped the next ones).
    double gpu_free_ms = -std::numeric_limits<double>::infinity();
    for (const auto& f : p.frames()) {
        events.push_back({{"name", "frame " + std::to_string(f.frame)},
                          {"cat", "frame"},
                          {"ph", "X"},
                          {"pid", 1},
                          {"tid", 1},
                          {"ts", us(f.begin_ms)},
                          {"dur", us(f.total_ms)}});
        for (const auto& s : f.scopes) {
            const char* cat = s.kind == ScopeKind::phase    ? "phase"
                              : s.kind == ScopeKind::system ? "system"
                                                            : "pass";
            json args{{"phase", phase_name(s.phase)}};
            if (s.system != no_name) args["system"] = p.name(s.system);
            events.push_back({{"name", p.name(s.name)},
                              {"cat", cat},
                              {"ph", "X"},
                              {"pid", 1},
                              {"tid", 1},
                              {"ts", us(s.begin_ms)},
                              {"dur", us(s.cpu_ms)},
                              {"args", args}});
            if (s.kind == ScopeKind::pass && s.gpu_ms >= 0.0) {
                const double start_ms = std::max(s.begin_ms, gpu_free_ms);
                gpu_free_ms = start_ms + s.gpu_ms;
                json gpu_args = args;
                gpu_args["issued_ms"] = s.begin_ms;  // the CPU start, where the slice would have been
                events.push_back({{"name", p.name(s.name)},
                                  {"cat", "gpu"},
                                  {"ph", "X"},
                                  {"pid", 1},
                                  {"tid", 2},
                                  {"ts", us(start_ms)},
                                  {"dur", us(s.gpu_ms)},
                                  {"args", gpu_args}});
            }
        }
    }
    return json{{"traceEvents", events}, {"displayTimeUnit", "ms"}}.dump() + "\n";
}

// ---------------------------------------------------------------------------------------------- SVG

std::string frame_svg(const Profiler& p, const std::string& title) {
    LineChart c;
    c.title = title;
    c.x_label = "frame";
    c.y_label = "time per frame (ms)";
    c.markers = p.frames().size() <= 120;
    Series total{"whole frame", {}};
    std::map<std::uint32_t, std::size_t> phase_series;
    std::vector<Series> phases;
    for (const auto& f : p.frames()) {
        total.points.emplace_back(static_cast<double>(f.frame), f.total_ms);
        for (const auto& s : f.scopes) {
            if (s.kind != ScopeKind::phase) continue;
            auto it = phase_series.find(s.name);
            if (it == phase_series.end()) {
                it = phase_series.emplace(s.name, phases.size()).first;
                phases.push_back({"phase " + p.name(s.name), {}});
            }
            phases[it->second].points.emplace_back(static_cast<double>(f.frame), s.cpu_ms);
        }
    }
    c.series.push_back(std::move(total));
    // Phases that never take measurable time would only clutter the legend.
    for (auto& s : phases) {
        double mx = 0.0;
        for (auto [x, y] : s.points) mx = std::max(mx, y);
        if (mx >= 0.01) c.series.push_back(std::move(s));
    }
    return render_svg(c);
}

// ---------------------------------------------------------------------------------------------- compare

std::vector<Regression> compare_reports(const ProfileReport& base, const ProfileReport& cur,
                                        CompareOptions opt) {
    std::vector<Regression> out;
    auto check = [&](const char* kind, const std::string& name, const char* metric, const Stats& b,
                     const Stats& c) {
        Regression r;
        r.kind = kind;
        r.name = name;
        r.metric = metric;
        r.base_p50 = b.p50;
        r.current_p50 = c.p50;
        r.threshold = std::max({b.p95 - b.p50, c.p95 - c.p50, opt.floor_ms, opt.floor_rel * b.p50});
        r.slower = c.p50 - b.p50 > r.threshold;
        out.push_back(std::move(r));
    };
    check("frame", "frame", "cpu_ms", base.frame_ms, cur.frame_ms);
    auto rows = [&](const char* kind, const std::vector<TimingRow>& b, const std::vector<TimingRow>& c) {
        for (const auto& rb : b)
            for (const auto& rc : c)
                if (rb.name == rc.name) {
                    check(kind, rb.name, "cpu_ms", rb.cpu_ms, rc.cpu_ms);
                    if (rb.gpu_ms && rc.gpu_ms) check(kind, rb.name, "gpu_ms", *rb.gpu_ms, *rc.gpu_ms);
                }
    };
    rows("system", base.systems, cur.systems);
    rows("pass", base.passes, cur.passes);
    return out;
}

std::string to_text(const std::vector<Regression>& rows) {
    std::string o;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%-7s %-28s %-7s %10s %10s %10s %10s  %s\n", "kind", "name", "metric",
                  "base p50", "now p50", "diff", "threshold", "verdict");
    o += buf;
    for (const auto& r : rows) {
        std::snprintf(buf, sizeof buf, "%-7s %-28s %-7s %10.3f %10.3f %+10.3f %10.3f  %s\n", r.kind.c_str(),
                      r.name.c_str(), r.metric.c_str(), r.base_p50, r.current_p50, r.current_p50 - r.base_p50,
                      r.threshold, r.slower ? "SLOWER" : "ok");
        o += buf;
    }
    return o;
}

}  // namespace sffd::profiling
