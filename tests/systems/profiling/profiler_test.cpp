// Profiler on a synthetic schedule (CPU only): what it records, the report it builds, the files it
// writes (JSON against the schema, trace, CSV), and --compare on a planted slowdown.
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/app/clock.h"
#include "runtime/app/frame_loop.h"
#include "systems/profiling/json_schema.h"
#include "systems/profiling/overlay.h"
#include "runtime/app/pass_timer.h"
#include "systems/profiling/profiler.h"
#include "systems/profiling/report.h"

namespace sffd::profiling {
namespace {

std::string read_text(const char* path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

void sleep_ms(double ms) { std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(ms)); }

// A schedule standing in for the engine's: a cheap system, a sleeping "deformer" issuing a named pass,
// a "renderer" issuing nested passes.
Schedule make_schedule(double deform_ms) {
    Schedule s;
    s.add(Phase::animation, "animate", [](ecs::Registry&, const FrameContext&) {});
    s.add(Phase::deformation, "deform", [deform_ms](ecs::Registry& r, const FrameContext&) {
        auto scope = gpu_scope(r, "ffd.compute");
        sleep_ms(deform_ms);
    });
    s.add(Phase::rendering, "render", [](ecs::Registry& r, const FrameContext&) {
        auto outer = gpu_scope(r, "hq");
        {
            auto a = gpu_scope(r, "hq.visibility");
            sleep_ms(0.3);
        }
        {
            auto b = gpu_scope(r, "hq.attributes");
            sleep_ms(0.2);
        }
    });
    return s;
}

ProfileReport run(double deform_ms, int frames, Profiler& profiler, int warmup = 2) {
    ecs::Registry registry;
    Schedule schedule = make_schedule(deform_ms);
    profiler.attach(schedule, registry);
    Clock clock({.fixed_dt = 1.0 / 60.0});
    for (int i = 0; i < warmup; ++i) schedule.run_frame(registry, clock.tick());
    profiler.clear();
    for (int i = 0; i < frames; ++i) schedule.run_frame(registry, clock.tick());
    profiler.resolve_all();
    profiler.detach(schedule, registry);
    return build_report(profiler, {{"scene", std::string("synthetic")}, {"frames", double(frames)}},
                        machine_info(false));
}

const TimingRow* find(const std::vector<TimingRow>& rows, const std::string& name) {
    for (const auto& r : rows)
        if (r.name == name) return &r;
    return nullptr;
}

TEST(Profiler, RecordsEveryPhaseSystemAndPassPerFrame) {
    Profiler profiler;
    run(1.0, 10, profiler);
    ASSERT_EQ(profiler.frames().size(), 10u);
    for (const auto& f : profiler.frames()) {
        int phases = 0, systems = 0, passes = 0;
        for (const auto& s : f.scopes) {
            phases += s.kind == ScopeKind::phase;
            systems += s.kind == ScopeKind::system;
            passes += s.kind == ScopeKind::pass;
        }
        EXPECT_EQ(phases, int(phase_count));
        EXPECT_EQ(systems, 3);
        EXPECT_EQ(passes, 4);
    }
    // Nesting and attribution of passes.
    const auto& scopes = profiler.frames()[0].scopes;
    for (const auto& s : scopes) {
        if (s.kind != ScopeKind::pass) continue;
        const std::string name = profiler.name(s.name);
        EXPECT_EQ(s.depth, name == "hq.visibility" || name == "hq.attributes" ? 1 : 0) << name;
        EXPECT_EQ(profiler.name(s.system), name == "ffd.compute" ? "deform" : "render") << name;
        EXPECT_LT(s.gpu_ms, 0.0) << "no GPU timing was asked for";
    }
}

TEST(Profiler, SystemTimesAreNonNegativeAndFitInTheFrame) {
    Profiler profiler;
    run(2.0, 20, profiler);
    for (const auto& f : profiler.frames()) {
        double systems = 0.0, phases = 0.0;
        for (const auto& s : f.scopes) {
            EXPECT_GE(s.cpu_ms, 0.0);
            EXPECT_GE(s.begin_ms, f.begin_ms);
            EXPECT_LE(s.begin_ms + s.cpu_ms, f.begin_ms + f.total_ms + 1e-9);
            if (s.kind == ScopeKind::system) systems += s.cpu_ms;
            if (s.kind == ScopeKind::phase) phases += s.cpu_ms;
        }
        EXPECT_LE(systems, phases + 1e-9);
        EXPECT_LE(phases, f.total_ms + 1e-9);
        // The sleeping systems are really measured: at least the sleep, in the right system.
        EXPECT_GE(systems, 2.0 + 0.3 + 0.2);
    }
}

TEST(Profiler, ReportPercentilesOrderedAndSystemsMatchSleeps) {
    Profiler profiler;
    const ProfileReport r = run(3.0, 15, profiler);
    EXPECT_EQ(r.frame_ms.n, 15u);
    EXPECT_GT(r.fps_mean, 0.0);
    for (const auto* rows : {&r.phases, &r.systems, &r.passes})
        for (const auto& row : *rows) {
            EXPECT_LE(row.cpu_ms.min, row.cpu_ms.p50) << row.name;
            EXPECT_LE(row.cpu_ms.p50, row.cpu_ms.p95) << row.name;
            EXPECT_LE(row.cpu_ms.p95, row.cpu_ms.p99) << row.name;
            EXPECT_LE(row.cpu_ms.p99, row.cpu_ms.max) << row.name;
            EXPECT_LE(row.cpu_ms.p50, r.frame_ms.max) << row.name;
        }
    const TimingRow* deform = find(r.systems, "deform");
    ASSERT_NE(deform, nullptr);
    EXPECT_EQ(deform->phase, "deformation");
    EXPECT_GE(deform->cpu_ms.min, 3.0);
    const TimingRow* vis = find(r.passes, "hq.visibility");
    ASSERT_NE(vis, nullptr);
    EXPECT_EQ(vis->system, "render");
    EXPECT_DOUBLE_EQ(vis->calls_per_frame, 1.0);
    EXPECT_FALSE(vis->gpu_ms.has_value());
}

TEST(Profiler, FillsTheLiveOverlay) {
    ecs::Registry registry;
    Schedule schedule = make_schedule(0.5);
    Profiler profiler({.keep_frames = false});
    profiler.attach(schedule, registry);
    Clock clock({.fixed_dt = 1.0 / 60.0});
    for (int i = 0; i < 5; ++i) schedule.run_frame(registry, clock.tick());
    EXPECT_TRUE(profiler.frames().empty());
    const auto& o = registry.resource<ProfileOverlay>();
    EXPECT_EQ(o.count, 5u);
    EXPECT_EQ(o.head, 5u);
    EXPECT_GT(o.frame_last_ms, 0.5f);
    EXPECT_GE(o.max_ms, o.frame_avg_ms);
    ASSERT_EQ(o.systems.size(), 3u);
    EXPECT_EQ(o.systems[1].name, "deform");
    EXPECT_EQ(o.systems[1].phase, "deformation");
    EXPECT_GE(o.systems[1].last_ms, 0.5f);
    EXPECT_GE(o.systems[1].avg_ms, 0.5f);
    EXPECT_EQ(o.passes.size(), 4u);
    EXPECT_EQ(o.gpu_method, "none");
}

TEST(Profiler, PassScopeWithoutProfilerDoesNothing) {
    ecs::Registry registry;
    { auto s = gpu_scope(registry, "orphan"); }
    EXPECT_EQ(registry.try_resource<PassTimer>(), nullptr);
}

TEST(ProfileFiles, JsonValidatesAgainstSchemaAndRoundTrips) {
    Profiler profiler;
    const ProfileReport r = run(1.0, 12, profiler);
    const std::string text = to_json(r);
    const std::string schema = read_text(SFFD_PROFILE_SCHEMA);
    ASSERT_FALSE(schema.empty());
    const auto errors = validate_json(schema, text);
    EXPECT_TRUE(errors.empty()) << (errors.empty() ? "" : errors.front());

    auto back = report_from_json(text, "mem.json");
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(back->systems.size(), r.systems.size());
    EXPECT_DOUBLE_EQ(back->frame_ms.p95, r.frame_ms.p95);
    EXPECT_EQ(back->passes[0].system, r.passes[0].system);
}

TEST(ProfileFiles, SchemaRejectsBrokenReports) {
    Profiler profiler;
    auto j = nlohmann::json::parse(to_json(run(0.2, 3, profiler)));
    const std::string schema = read_text(SFFD_PROFILE_SCHEMA);
    auto errors_for = [&](nlohmann::json broken) { return validate_json(schema, broken.dump()); };
    {
        auto b = j;
        b["systems"][0]["cpu_ms"]["p50"] = -1.0;
        auto e = errors_for(b);
        ASSERT_EQ(e.size(), 1u);
        EXPECT_NE(e[0].find("/systems/0/cpu_ms/p50"), std::string::npos) << e[0];
    }
    {
        auto b = j;
        b["frame"].erase("fps_mean");
        EXPECT_EQ(errors_for(b).size(), 1u);
    }
    {
        auto b = j;
        b["gpu_timing"] = "guess";
        EXPECT_EQ(errors_for(b).size(), 1u);
    }
    {
        auto b = j;
        b["passes"][0]["phase"] = "lunch";
        EXPECT_EQ(errors_for(b).size(), 1u);
    }
    {
        auto b = j;
        b["surprise"] = 1;
        EXPECT_EQ(errors_for(b).size(), 1u);
    }
    EXPECT_FALSE(validate_json(schema, "{\"format\": ").empty());
}

TEST(ProfileFiles, ReadingABadReportNamesTheFile) {
    auto r = report_from_json("{\"format\": \"something else\"}", "base.json");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message().rfind("base.json: ", 0), 0u) << r.message();
    auto t = report_from_json("{not json", "trunc.json");
    ASSERT_FALSE(t.ok());
    EXPECT_EQ(t.message(), "trunc.json: not valid JSON");
}

TEST(ProfileFiles, ChromeTraceParsesWithCompleteEventsInsideFrames) {
    Profiler profiler;
    run(0.5, 4, profiler);
    const auto trace = nlohmann::json::parse(to_chrome_trace(profiler, "test"));
    ASSERT_TRUE(trace.contains("traceEvents"));
    int frames = 0, complete = 0;
    double frame_begin = 0, frame_end = 0;
    for (const auto& e : trace["traceEvents"]) {
        const std::string ph = e.at("ph");
        ASSERT_TRUE(ph == "X" || ph == "M") << ph;
        if (ph == "M") continue;
        ++complete;
        const double ts = e.at("ts"), dur = e.at("dur");
        EXPECT_GE(dur, 0.0);
        EXPECT_EQ(e.at("pid"), 1);
        if (e.at("cat") == "frame") {
            ++frames;
            frame_begin = ts, frame_end = ts + dur;
        } else {
            // Every scope lies inside its frame (events are emitted frame by frame).
            EXPECT_GE(ts, frame_begin - 1e-6);
            EXPECT_LE(ts + dur, frame_end + 1e-3);
        }
    }
    EXPECT_EQ(frames, 4);
    EXPECT_EQ(complete, 4 * (1 + int(phase_count) + 3 + 4));
}

TEST(ProfileFiles, CsvHasOneRowPerFrameAndAColumnPerScope) {
    Profiler profiler;
    run(0.5, 6, profiler);
    const std::string csv = to_csv(profiler);
    std::istringstream in(csv);
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header.rfind("frame,frame_ms,", 0), 0u);
    EXPECT_NE(header.find("\"system:deform:cpu_ms\""), std::string::npos);
    EXPECT_NE(header.find("\"pass:hq.visibility:cpu_ms\""), std::string::npos);
    const auto columns = std::count(header.begin(), header.end(), ',') + 1;
    EXPECT_EQ(columns, 2 + long(phase_count) + 3 + 4);
    int rows = 0;
    for (std::string line; std::getline(in, line);) {
        ++rows;
        EXPECT_EQ(std::count(line.begin(), line.end(), ',') + 1, columns);
    }
    EXPECT_EQ(rows, 6);
}

// A report whose frame, "deform" system and "ffd.compute" pass follow a given series of times. The
// comparison is a pure function of the statistics, so it is tested on known series instead of on sleeps
// measured on a machine that may be loaded (a wall-clock test breaks when the scheduler wakes late).
ProfileReport report_of(const std::vector<double>& deform_ms) {
    ProfileReport r;
    std::vector<double> frame;
    for (double d : deform_ms) frame.push_back(d + 1.0);
    r.frame_ms = compute_stats(frame);
    TimingRow system;
    system.name = "deform";
    system.phase = "deformation";
    system.cpu_ms = compute_stats(deform_ms);
    TimingRow pass = system;
    pass.name = "ffd.compute";
    pass.system = "deform";
    r.systems.push_back(system);
    r.passes.push_back(pass);
    return r;
}

// `n` samples around `ms`: a deterministic jitter of +-`spread`, with one outlier at 3x the spread.
std::vector<double> series(double ms, double spread, int n = 30) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(ms + spread * std::sin(1.7 * i));
    v.back() = ms + 3.0 * spread;
    return v;
}

TEST(Compare, FlagsAPlantedSlowdownAndPassesAnIdenticalRun) {
    const ProfileReport base = report_of(series(10.0, 0.5));
    const ProfileReport same = report_of(series(10.1, 0.6));
    const ProfileReport slow = report_of(series(30.0, 0.5));

    auto slower = [](const std::vector<Regression>& rows, const std::string& name) {
        for (const auto& r : rows)
            if (r.name == name && r.metric == "cpu_ms") return r.slower;
        ADD_FAILURE() << name << " not compared";
        return false;
    };
    const auto regress = compare_reports(base, slow);
    EXPECT_TRUE(slower(regress, "deform")) << to_text(regress);
    EXPECT_TRUE(slower(regress, "ffd.compute")) << to_text(regress);
    EXPECT_TRUE(slower(regress, "frame")) << to_text(regress);

    const auto steady = compare_reports(base, same);
    EXPECT_FALSE(slower(steady, "deform")) << to_text(steady);
    EXPECT_FALSE(slower(steady, "ffd.compute")) << to_text(steady);
    EXPECT_FALSE(slower(steady, "frame")) << to_text(steady);
    for (const auto& r : compare_reports(base, base)) EXPECT_FALSE(r.slower);
    // Faster is never a regression.
    for (const auto& r : compare_reports(slow, base)) EXPECT_FALSE(r.slower);
    // A slowdown smaller than the runs' own spread is noise, not a regression.
    const auto noisy = compare_reports(report_of(series(10.0, 2.0)), report_of(series(11.0, 2.0)));
    EXPECT_FALSE(slower(noisy, "deform")) << to_text(noisy);
}

}  // namespace
}  // namespace sffd::profiling
