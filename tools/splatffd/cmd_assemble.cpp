// splatffd assemble DIR [--video OUT.mp4|OUT.gif]
//
// Checks a folder that `splatffd render --shard K/N` runs wrote into (a render farm's shared volume) and,
// when every check passes, writes DIR/render_manifest.json for the whole clip (the same form a single run
// writes) and, with --video, encodes it. Checks: every shard 0..N-1 has a manifest and finished
// ("complete"); all shards have the same settings (scene, range, size, quality, formats, camera, the
// binary's version...); every frame of the clip was written by exactly one shard; every frame file on
// disk has the bytes its shard recorded (a file rewritten by another run is caught); no frame file in DIR
// lies outside the clip. Each problem is printed on its own line, and a shard that must run again is named
// with the command that re-renders it. Shards made on different machines (another SIMD target of the CPU
// kernels, another GL renderer) are assembled with a warning that names their frames: equal settings give
// equal bytes only on equal machines. Exit 0 assembled, 1 a problem (listed), 2 usage.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "tools/splatffd/command.h"
#include "tools/splatffd/frame_files.h"
#include "tools/splatffd/render_manifest.h"
#include "tools/splatffd/video.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

void usage(std::FILE* to) {
    std::fprintf(
        to,
        "usage: splatffd assemble DIR [--video FILE]\n"
        "  DIR           the folder the shards (`splatffd render ... --shard K/N --out DIR`) wrote\n"
        "  --video FILE  also encode the assembled PNG frames (.mp4 or .gif) at the clip's --fps; needs "
        "ffmpeg\n"
        "Checks that every shard finished with the same settings and that every frame is present once with\n"
        "the bytes its shard wrote, then writes DIR/render_manifest.json for the whole clip.\n");
}

struct ShardFile {
    fs::path path;
    cli::RunRecord run;
};

// Shard `r`'s command with its --shard changed to K/N, or "" when the command has no --shard.
std::string command_for_shard(const cli::RunRecord& r, long k, long n) {
    std::string c = r.command;
    const std::string from = " --shard " + std::to_string(r.shard.index) + "/" + std::to_string(n);
    if (auto at = c.find(from); at != std::string::npos)
        return c.replace(at, from.size(), " --shard " + std::to_string(k) + "/" + std::to_string(n));
    return {};
}

// The command that re-renders shard `k` of `n`: the shard's own, or another shard's with --shard changed.
std::string rerender_command(const std::map<long, ShardFile>& shards, long k, long n) {
    if (auto it = shards.find(k); it != shards.end()) return it->second.run.command;
    for (const auto& [index, s] : shards)
        if (std::string c = command_for_shard(s.run, k, n); !c.empty()) return c;
    return "splatffd render ... --shard " + std::to_string(k) + "/" + std::to_string(n);
}

// The shard whose settings the clip keeps: those most shards share, ties going to the lowest shard (shard 0
// when present). A shard with other settings is the odd one, re-rendered with the kept settings.
const ShardFile& kept_settings(const std::map<long, ShardFile>& shards) {
    const ShardFile* best = nullptr;
    long best_count = 0;
    for (const auto& [k, s] : shards) {
        long count = 0;
        for (const auto& [k2, s2] : shards) count += s2.run.settings == s.run.settings;
        if (count > best_count) best = &s, best_count = count;  // strict: the lowest shard wins a tie
    }
    return *best;
}

// The single-run form of a shard's command (its --shard removed), for the assembled manifest.
std::string whole_clip_command(const cli::RunRecord& r) {
    std::string c = r.command;
    const std::string s = " --shard " + std::to_string(r.shard.index) + "/" + std::to_string(r.shard.count);
    if (auto at = c.find(s); at != std::string::npos) c.erase(at, s.size());
    return c;
}

// " (size 160x90 against 200x90, ...)": which settings differ, as the user typed them.
std::string differing_settings(const nlohmann::ordered_json& odd, const nlohmann::ordered_json& kept) {
    std::string s;
    for (const auto& [key, value] : kept.items()) {
        const auto o = odd.find(key);
        if (o != odd.end() && *o == value) continue;
        auto show = [&](const nlohmann::ordered_json& v) {
            if (key == "size" && v.is_array() && v.size() == 2) return v[0].dump() + "x" + v[1].dump();
            return v.is_string() ? v.get<std::string>() : v.dump();
        };
        s += (s.empty() ? " (" : ", ") + key + " " + (o == odd.end() ? std::string("missing") : show(*o)) +
             " against " + show(value);
    }
    return s.empty() ? s : s + ")";
}

// "frames 0, 2, 4" or "frames 0..94, one in 2" for a shard's share of the clip.
std::string frames_of(const cli::RunRecord& r) {
    if (r.frames.count <= 6) {
        std::string s = r.frames.count == 1 ? "frame " : "frames ";
        for (long i = 0; i < r.frames.count; ++i) s += (i ? ", " : "") + std::to_string(r.frames.at(i));
        return s;
    }
    return "frames " + std::to_string(r.frames.first) + ".." +
           std::to_string(r.frames.at(r.frames.count - 1)) +
           (r.frames.step > 1 ? ", one in " + std::to_string(r.frames.step) : "");
}

// Shards that agree on the settings but ran on another SIMD target or GL renderer: the clip is whole, but
// its frames may differ in the last bits from a single run's. One line per machine, naming its frames.
void warn_mixed_machines(const std::map<long, ShardFile>& shards, long first, long last) {
    std::vector<std::pair<cli::MachineRecord, std::vector<long>>> groups;
    for (const auto& [k, s] : shards) {
        auto g = std::find_if(groups.begin(), groups.end(),
                              [&](const auto& e) { return e.first == s.run.machine; });
        if (g == groups.end()) groups.push_back({s.run.machine, {}}), g = groups.end() - 1;
        g->second.push_back(k);
    }
    if (groups.size() < 2) return;
    const long n = long(shards.size());
    std::fprintf(stderr,
                 "splatffd assemble: warning: the shards of frames %ld..%ld ran on %zu different machines; "
                 "their frames may differ from a single run's (pin SFFD_SIMD and use one GL renderer for "
                 "identical bytes):\n",
                 first, last, groups.size());
    for (const auto& [m, ks] : groups)
        for (long k : ks) {
            const cli::RunRecord& r = shards.at(k).run;
            std::fprintf(stderr, "splatffd assemble:   shard %ld/%ld (%s): simd %s, GL renderer %s\n", k, n,
                         frames_of(r).c_str(), m.simd.empty() ? "(not recorded)" : m.simd.c_str(),
                         m.gl_renderer.empty() ? "(not recorded)" : m.gl_renderer.c_str());
        }
}

int run_assemble(cli::Args args) {
    std::string dir_text, video;
    for (std::size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--help" || args[i] == "-h") {
            usage(stdout);
            return 0;
        } else if (args[i] == "--video" && i + 1 < args.size()) {
            video = args[++i];
        } else if (!args[i].empty() && args[i][0] != '-' && dir_text.empty()) {
            dir_text = args[i];
        } else {
            std::fprintf(stderr, "splatffd assemble: unknown or incomplete option '%s'\n", args[i].c_str());
            usage(stderr);
            return 2;
        }
    }
    if (dir_text.empty()) {
        usage(stderr);
        return 2;
    }
    std::string ffmpeg;
    if (!video.empty()) {
        bool usage_error = false;
        auto f = cli::check_video_output(video, usage_error);
        if (!f) {
            std::fprintf(stderr, "splatffd assemble: %s\n", f.message().c_str());
            return usage_error ? 2 : 1;
        }
        ffmpeg = *f;
    }
    const fs::path dir(dir_text);
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        cli::command_error("assemble", dir_text + ": not a folder");
        return 1;
    }

    // Every shard manifest and every frame file in DIR.
    const std::regex manifest_name(R"(render_manifest\.shard-(\d+)-of-(\d+)\.json)"),
        frame_name(R"(frame_(\d+)\.(png|exr))");
    std::vector<std::string> problems;
    std::map<long, std::map<long, ShardFile>> by_count;  // N -> K -> manifest
    std::vector<std::pair<long, std::string>> frame_files;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        const std::string name = e.path().filename().string();
        std::smatch m;
        if (std::regex_match(name, m, manifest_name)) {
            auto r = cli::read_manifest(e.path());
            if (!r) {
                problems.push_back(r.message());
                continue;
            }
            by_count[r->shard.count][r->shard.index] = ShardFile{e.path(), std::move(*r)};
        } else if (std::regex_match(name, m, frame_name) && m[1].length() < 10) {
            frame_files.emplace_back(std::stol(m[1]), m[2]);
        }
    }
    if (ec) {
        cli::command_error("assemble", dir_text + ": cannot list the folder (" + ec.message() + ")");
        return 1;
    }
    if (by_count.empty()) {
        for (const std::string& p : problems) std::fprintf(stderr, "splatffd assemble: %s\n", p.c_str());
        std::fprintf(stderr,
                     "splatffd assemble: %s: no shard manifests (render_manifest.shard-K-of-N.json); render "
                     "with --shard K/N\n",
                     dir_text.c_str());
        return 1;
    }
    if (by_count.size() > 1) {
        std::string counts;
        for (const auto& [n, s] : by_count)
            counts += (counts.empty() ? "" : ", ") + std::to_string(s.size()) + " of " + std::to_string(n);
        std::fprintf(stderr,
                     "splatffd assemble: %s holds shards of runs split differently (%s shards); keep one "
                     "run's files in a folder\n",
                     dir_text.c_str(), counts.c_str());
        return 1;
    }
    const long n = by_count.begin()->first;
    const std::map<long, ShardFile>& shards = by_count.begin()->second;
    const ShardFile& reference = kept_settings(shards);
    const auto& settings = reference.run.settings;
    const long first = settings.at("first").get<long>(), last = settings.at("last").get<long>();
    const std::string formats = settings.at("formats").get<std::string>();

    // Per shard: present, finished, same settings; its frames and their recorded fingerprints.
    std::map<long, std::vector<std::pair<long, const cli::FramePrint*>>> writers;  // frame -> (shard, print)
    for (long k = 0; k < n; ++k) {
        const auto it = shards.find(k);
        const std::string shard = "shard " + std::to_string(k) + "/" + std::to_string(n);
        const std::string again = "; re-render it with: " + rerender_command(shards, k, n);
        if (it == shards.end()) {
            problems.push_back(shard + ": no manifest (not started, or its output went elsewhere)" + again);
            continue;
        }
        const cli::RunRecord& r = it->second.run;
        if (r.settings != settings) {
            // Re-rendered with the kept settings (the reference shard's command), not its own odd ones.
            std::string fix = command_for_shard(reference.run, k, n);
            if (fix.empty()) fix = rerender_command(shards, k, n);
            problems.push_back(
                it->second.path.string() + ": settings differ from " + reference.path.filename().string() +
                differing_settings(r.settings, settings) +
                " (another run's shard, or another version of splatffd); re-render it with: " + fix);
            continue;
        }
        if (r.state != "complete") {
            problems.push_back(shard + ": " + r.state + " after " + std::to_string(r.written) + " of " +
                               std::to_string(r.frames.count) + " frames" +
                               (r.state == "running" ? " (still running, or interrupted)" : "") + again);
            continue;
        }
        const cli::FrameSequence expect = cli::shard_frames(first, last, r.shard);
        if (long(r.files.size()) != expect.count || r.frames.first != expect.first ||
            r.frames.step != expect.step) {
            problems.push_back(it->second.path.string() + ": lists " + std::to_string(r.files.size()) +
                               " frames, its share is " + std::to_string(expect.count) + again);
            continue;
        }
        for (const cli::FramePrint& f : r.files) writers[f.frame].emplace_back(k, &f);
    }

    // Every frame once, and on disk with the bytes its shard wrote.
    std::vector<cli::FramePrint> files;
    for (long frame = first; frame <= last; ++frame) {
        const auto w = writers.find(frame);
        if (w == writers.end()) continue;  // its shard's problem is listed above
        if (w->second.size() > 1) {
            problems.push_back("frame " + std::to_string(frame) + " is listed by " +
                               std::to_string(w->second.size()) + " shards");
            continue;
        }
        const auto [k, print] = w->second.front();
        const fs::path base = cli::frame_file_base(dir_text, frame);
        bool ok = true;
        for (const auto& [ext, expected] : {std::pair{".png", print->png}, std::pair{".exr", print->exr}}) {
            if (!expected) continue;
            const fs::path file = base.string() + ext;
            auto actual = cli::fingerprint(file);
            if (!actual) {
                problems.push_back(file.string() + ": missing (shard " + std::to_string(k) + "/" +
                                   std::to_string(n) +
                                   " wrote it); re-render with: " + rerender_command(shards, k, n));
                ok = false;
            } else if (actual->bytes != expected->bytes || actual->fnv1a64 != expected->fnv1a64) {
                problems.push_back(
                    file.string() + ": not the bytes shard " + std::to_string(k) + "/" + std::to_string(n) +
                    " wrote (" + std::to_string(actual->bytes) + " bytes, FNV-1a " +
                    cli::hex64(actual->fnv1a64) + "; recorded " + std::to_string(expected->bytes) + ", " +
                    cli::hex64(expected->fnv1a64) +
                    "): rewritten by another run?; re-render with: " + rerender_command(shards, k, n));
                ok = false;
            }
        }
        if (ok) files.push_back(*print);
    }
    // Frame files this clip did not write: another run's, which a video or a copy of DIR would pick up.
    std::sort(frame_files.begin(), frame_files.end());
    for (const auto& [frame, ext] : frame_files) {
        const bool in_range = frame >= first && frame <= last;
        const bool format = formats.find(ext) != std::string::npos;
        if (!in_range || !format)
            problems.push_back(cli::frame_file_base(dir_text, frame).string() + "." + ext +
                               ": not a frame of this clip (frames " + std::to_string(first) + ".." +
                               std::to_string(last) + ", " + formats +
                               "): another run's file; move it out of the folder");
    }

    if (!problems.empty()) {
        for (const std::string& p : problems) std::fprintf(stderr, "splatffd assemble: %s\n", p.c_str());
        std::fprintf(stderr, "splatffd assemble: %s: %zu problem%s; nothing assembled\n", dir_text.c_str(),
                     problems.size(), problems.size() == 1 ? "" : "s");
        return 1;
    }

    warn_mixed_machines(shards, first, last);

    cli::RunRecord whole;
    whole.state = "complete";
    whole.started_unix = reference.run.started_unix;
    for (const auto& [k, s] : shards) whole.started_unix = std::min(whole.started_unix, s.run.started_unix);
    whole.command = whole_clip_command(reference.run);
    whole.settings = settings;
    whole.frames = cli::FrameSequence{first, 1, last - first + 1};
    whole.written = whole.frames.count;
    whole.files = std::move(files);
    if (Status st = cli::write_manifest(dir / "render_manifest.json", whole); !st) {
        std::fprintf(stderr, "splatffd assemble: %s\n", st.message().c_str());
        return 1;
    }
    std::fprintf(stderr,
                 "splatffd assemble: %ld shards, frames %ld..%ld (%s) all present once with the bytes their "
                 "shard wrote; wrote %s\n",
                 n, first, last, formats.c_str(), (dir / "render_manifest.json").c_str());
    if (!video.empty()) {
        if (formats.find("png") == std::string::npos) {
            std::fprintf(stderr, "splatffd assemble: --video encodes PNG frames; this clip has only %s\n",
                         formats.c_str());
            return 1;
        }
        const double fps = settings.at("fps").get<double>();
        // The same background a single run's --video uses: the shards' --background, or black.
        glm::vec3 background(0.0f);
        if (const auto bg = settings.find("background");
            bg != settings.end() && bg->is_array() && bg->size() == 3)
            background = glm::vec3((*bg)[0].get<float>(), (*bg)[1].get<float>(), (*bg)[2].get<float>());
        if (Status st = cli::encode_video(ffmpeg, dir, first, last, fps, video, background); !st) {
            std::fprintf(stderr, "splatffd assemble: %s\n", st.message().c_str());
            return 1;
        }
        std::fprintf(stderr, "wrote %s: %ld frames at %g fps\n", video.c_str(), last - first + 1, fps);
        if (const auto size = settings.find("size");
            size != settings.end() && size->is_array() && size->size() == 2)
            if (const std::string note =
                    cli::video_size_note(video, (*size)[0].get<long>(), (*size)[1].get<long>());
                !note.empty())
                std::fprintf(stderr, "splatffd assemble: note: %s\n", note.c_str());
    }
    return 0;
}

}  // namespace

SFFD_COMMAND(assemble, "check a folder of render shards and assemble the clip's manifest (and video)",
             run_assemble);
