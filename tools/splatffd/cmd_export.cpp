// splatffd export SCENE --format ply|compressed-ply|sog|spz|glb --out DIR [--frames N|A:B] [--fps F]
//                 [--shard K/N] [--cloud NAME] [--force]
//
// Bakes a scene's keyframed lattice clip into a numbered sequence of deformed clouds that other tools
// load (SuperSplat's sequence import, splat-transform, Blender): frame k is the pose render shows in its
// frame k (time k / fps on the same fixed-step clock, the same animation system), the cloud deformed on
// the CPU as `deform` deforms a scene's cloud saved at that clip time (tools/splatffd/export_sequence.h).
// Files DIR/frame0000.<ext> (4 digits, more when the last frame needs them) and DIR/export_manifest.json
// (or DIR/export_manifest.shard-K-of-N.json): what was asked, the clips, the scene file's and every
// frame's fingerprint (bytes and FNV-1a 64, as render's manifest), "state": running | complete | failed.
// The output folder must hold nothing but other shards of the same export unless --force.
// Exit 0 ok, 1 bad scene or unwritable output (the message names the file), 2 usage.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/core/atomic_file.h"
#include "runtime/simd/simd.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/export_sequence.h"
#include "tools/splatffd/frame_files.h"
#include "tools/splatffd/render_manifest.h"
#include "tools/splatffd/unkeyed_note.h"
#include "tools/splatffd/web_export.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

constexpr const char* kUsage =
    "usage: splatffd export SCENE --format ply|compressed-ply|sog|spz|glb --out DIR [--frames N|A:B] [--fps "
    "F]\n"
    "                       [--shard K/N] [--cloud NAME] [--force]\n"
    "       splatffd export SCENE --web DIR [--force] [--size WxH] [--fps F]   (a web player folder:\n"
    "                       splatffd export SCENE --web DIR --help)\n"
    "  SCENE            built-in name (sphere, face) or a scene file (.glb .gltf: the editor's save,\n"
    "                   `convert ... --lattice fit`) whose cloud is bound to a lattice\n"
    "  --format F       ply (3DGS PLY for Gaussians; surface splats: PLY with normals and splat axes),\n"
    "                   compressed-ply (PlayCanvas's quantised PLY), sog (PlayCanvas SOG archive), spz\n"
    "                   (Niantic SPZ v3), glb (KHR_gaussian_splatting for Gaussians; surface splats: GLB\n"
    "                   with normals and splat axes); compressed-ply, sog and spz are for Gaussians only\n"
    "  --out DIR        output folder (created; required): DIR/frame0000.ply ... (4 digits, more when the\n"
    "                   last frame needs them; .compressed.ply .sog .spz .glb by format) and\n"
    "                   DIR/export_manifest.json (frames, fps, clips, format, fingerprints of the scene\n"
    "                   file and of every frame)\n"
    "  --frames N|A:B   N: frames 0..N-1; A:B: frames A..B inclusive (default: the clip once, frames\n"
    "                   0..duration*fps-1; a scene without a clip: frame 0, its saved pose, and no more);\n"
    "                   frame k is the pose at time k / fps, the pose `render` shows in its frame k and\n"
    "                   `deform` gives for the scene saved at that clip time; frames past the clip's end\n"
    "                   are allowed: its play mode decides (loop wraps, once holds the end, ping_pong\n"
    "                   turns back)\n"
    "  --fps F          frames per second of the clock (default 24, the demo clip's rate)\n"
    "  --shard K/N      export only frames FIRST+K, FIRST+K+N, ... into the same folder, with a manifest\n"
    "                   of its own (DIR/export_manifest.shard-K-of-N.json); shards may run at once\n"
    "  --cloud NAME     the deformed cloud to export when the scene has several (a frame holds one)\n"
    "  --force          write into a folder that holds other files, overwriting an earlier export's\n"
    "                   frames (default: refused)\n"
    "SuperSplat opens the ply and compressed-ply frames as a sequence: select the frame files (not the\n"
    "manifest) and drop them together. Progress is shown on a terminal only.\n";

struct ExportOptions {
    std::string scene, out_dir, cloud;
    std::optional<cli::ExportFormat> format;
    bool frames_given = false, force = false;
    long first = 0, last = 0;
    double fps = 24.0;  // the built-in demo clip (systems/animation/paper_demo.h) is authored at 24 fps
    std::optional<cli::Shard> shard;
    std::string command;  // the shell line that re-runs this export (in the manifest)
};

std::optional<int> parse_export_args(cli::Args args, ExportOptions& o) {
    o.command = "splatffd export";
    for (const std::string& a : args) {
        o.command += ' ';
        o.command += cli::shell_quote(a);
    }
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        auto refuse = [](const std::string& message) { return cli::usage_error("export", message, ""); };
        if (cli::is_help(a)) {
            return cli::help(kUsage);
        } else if (a == "--out" && has_value) {
            o.out_dir = args[++i];
        } else if (a == "--format" && has_value) {
            o.format = cli::parse_export_format(args[++i]);
            if (!o.format)
                return refuse("--format expects ply, compressed-ply, sog, spz or glb, got '" + args[i] + "'");
        } else if (a == "--frames" && has_value) {
            auto range = cli::parse_frames(args[++i]);
            if (!range) return refuse(range.message());
            o.first = range->first, o.last = range->last;
            o.frames_given = true;
        } else if (a == "--fps" && has_value) {
            auto f = cli::parse_number("--fps", args[++i], 1e-6, 1e6);
            if (!f) return refuse(f.message());
            o.fps = *f;
        } else if (a == "--shard" && has_value) {
            auto s = cli::parse_shard(args[++i]);
            if (!s) return refuse(s.message());
            o.shard = *s;
        } else if (a == "--cloud" && has_value) {
            o.cloud = args[++i];
        } else if (a == "--force") {
            o.force = true;
        } else if (!a.empty() && a[0] != '-' && o.scene.empty()) {
            o.scene = a;
        } else {
            return cli::usage_error("export", "unknown or incomplete option '" + a + "'", kUsage);
        }
    }
    if (o.scene.empty()) return cli::usage_error("export", "SCENE is required", kUsage);
    if (o.out_dir.empty()) return cli::usage_error("export", "--out DIR is required", kUsage);
    if (!o.format)
        return cli::usage_error("export", "--format is required (ply, compressed-ply, sog, spz or glb)",
                                kUsage);
    return std::nullopt;
}

// The frames to export and what the scene's clips say about them; an exit code when refused.
std::optional<int> check_clips(ExportOptions& o, const cli::ExportScene& s) {
    bool any_clip = false, any_key = false;
    double longest = 0.0;
    for (const cli::ExportClip& c : s.clips) {
        if (!c.has_clip) continue;
        any_clip = true;
        any_key = any_key || c.keys > 0;
        if (c.speed != 0.0) longest = std::max(longest, c.duration / std::abs(c.speed));
    }
    if (!any_clip) {
        // Without a clip every frame is the saved pose: one frame says all of it, more would be copies.
        if (o.frames_given && o.last > o.first)
            return cli::command_error(
                "export", o.scene + ": no clip on " +
                              (s.clips.size() == 1 ? "the lattice '" : "the lattices of '") +
                              (s.clips.size() == 1 ? s.clips[0].lattice : s.cloud_name) +
                              "': every frame would be the saved pose; export one frame (--frames " +
                              std::to_string(o.first) + ":" + std::to_string(o.first) +
                              ") or key a clip first (splatffd view " + o.scene + ")");
        if (!o.frames_given) o.first = o.last = 0;
        std::fprintf(stderr, "splatffd export: note: %s has no clip: frame %ld is the pose as saved\n",
                     o.scene.c_str(), o.first);
        return std::nullopt;
    }
    if (!any_key)
        // Exported, not refused: render plays such a clip (the rest pose in every frame), and export writes
        // what render shows.
        std::fprintf(stderr,
                     "splatffd export: warning: %s: the clip has no keys: every frame is the rest pose (as "
                     "render shows it)\n",
                     o.scene.c_str());
    if (!o.frames_given) {
        const long n = std::max(1L, long(std::llround(longest * o.fps)));
        o.first = 0, o.last = n - 1;
    }
    return std::nullopt;
}

bool is_temporary(const std::string& name) { return name.find(".sffd-tmp-") != std::string::npos; }

// Another shard's file of an export in this format: frame files, their PLY textures, shard manifests.
bool looks_like_export_file(const std::string& name, cli::ExportFormat format) {
    if (name.rfind("export_manifest", 0) == 0 && name.size() > 5 && name.substr(name.size() - 5) == ".json")
        return true;
    if (name.rfind("frame", 0) != 0) return false;
    std::size_t i = 5;
    while (i < name.size() && std::isdigit(static_cast<unsigned char>(name[i]))) ++i;
    if (i == 5) return false;
    const std::string rest = name.substr(i);
    return rest == cli::export_extension(format) || rest == "_texture.png";
}

// The folder may hold other shards' files of this export; this run's own names (an earlier export) and
// anything else only with --force.
std::optional<int> check_output_folder(const ExportOptions& o, const std::set<std::string>& ours) {
    std::vector<std::string> earlier, other;
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(o.out_dir, ec)) {
        const std::string name = e.path().filename().string();
        if (is_temporary(name)) continue;  // a save in progress (a shard running beside this one)
        if (ours.count(name)) earlier.push_back(name);
        else if (!(o.shard && looks_like_export_file(name, *o.format))) other.push_back(name);
    }
    if (ec)
        return cli::command_error("export",
                                  o.out_dir + ": cannot list the output folder (" + ec.message() + ")");
    if (o.force) {
        if (!other.empty())
            std::fprintf(stderr,
                         "splatffd export: note: %s holds %zu other files (e.g. '%s'); left as they are\n",
                         o.out_dir.c_str(), other.size(), other.front().c_str());
        return std::nullopt;
    }
    if (!earlier.empty())
        return cli::command_error("export", o.out_dir + ": holds " + std::to_string(earlier.size()) +
                                                " files of an earlier export (e.g. '" + earlier.front() +
                                                "'); pass --force to overwrite them");
    if (!other.empty())
        return cli::command_error("export", o.out_dir + ": holds " + std::to_string(other.size()) +
                                                " other files (e.g. '" + other.front() +
                                                "'); export into an empty folder, or pass --force to write "
                                                "beside them");
    return std::nullopt;
}

fs::path manifest_path(const ExportOptions& o) {
    if (!o.shard) return fs::path(o.out_dir) / "export_manifest.json";
    return fs::path(o.out_dir) / ("export_manifest.shard-" + std::to_string(o.shard->index) + "-of-" +
                                  std::to_string(o.shard->count) + ".json");
}

ojson print_json(const cli::FilePrint& p) {
    return ojson{{"bytes", p.bytes}, {"fnv1a64", cli::hex64(p.fnv1a64)}};
}

struct FrameRecord {
    long frame = 0;
    std::vector<std::pair<std::string, cli::FilePrint>> files;  // name in DIR, print
};

struct ExportRun {
    std::string state = "running";
    long long started_unix = 0;
    ojson scene_file;  // the scene's path and fingerprint
    cli::FrameSequence frames;
    long written = 0;
    std::vector<FrameRecord> files;  // written when the run ends
};

ojson manifest_json(const ExportOptions& o, const cli::ExportScene& s, const ExportRun& run) {
    ojson j;
    j["generator"] = "splatffd export " SFFD_VERSION;
    j["state"] = run.state;
    j["complete"] = run.state == "complete";
    j["started_unix"] = run.started_unix;
    j["command"] = o.command;
    j["scene"] = run.scene_file;
    j["cloud"] = ojson{
        {"name", s.cloud_name}, {"kind", s.gaussians ? "gaussians" : "surface splats"}, {"count", s.count}};
    j["format"] = std::string(cli::export_format_name(*o.format));
    j["fps"] = o.fps;
    j["first"] = o.first, j["last"] = o.last;
    ojson clips = ojson::array();
    for (const cli::ExportClip& c : s.clips)
        clips.push_back(ojson{{"lattice", c.lattice},
                              {"clip", c.has_clip ? ojson{{"name", c.name},
                                                          {"duration", c.duration},
                                                          {"mode", c.mode},
                                                          {"speed", c.speed},
                                                          {"keys", c.keys}}
                                                  : ojson(nullptr)}});
    j["clips"] = std::move(clips);
    j["simd"] = simd::chosen();
    j["shard"] = ojson{{"index", o.shard ? o.shard->index : 0},
                       {"count", o.shard ? o.shard->count : 1},
                       {"sharded", o.shard.has_value()}};
    j["frames"] = ojson{{"first", run.frames.first}, {"step", run.frames.step}, {"count", run.frames.count}};
    j["frames_written"] =
        ojson{{"count", run.written},
              {"last", run.written > 0 ? ojson(run.frames.at(run.written - 1)) : ojson(nullptr)}};
    if (run.state != "running") {
        ojson files = ojson::array();
        for (const FrameRecord& f : run.files) {
            ojson e{{"frame", f.frame}, {"time", double(f.frame) / o.fps}};
            for (std::size_t i = 0; i < f.files.size(); ++i) {
                ojson p = print_json(f.files[i].second);
                p["file"] = f.files[i].first;
                e[i == 0 ? "file" : "texture"] = std::move(p);
            }
            files.push_back(std::move(e));
        }
        j["files"] = std::move(files);
    }
    return j;
}

Status write_manifest(const ExportOptions& o, const cli::ExportScene& s, const ExportRun& run) {
    return write_file_atomic(
        manifest_path(o),
        manifest_json(o, s, run).dump(2, ' ', false, ojson::error_handler_t::replace) + "\n");
}

int export_frames(const ExportOptions& o, cli::ExportScene& s, ExportRun& run) {
    const long count = run.frames.count;
    if (count == 0) run.state = "complete";
    if (Status st = write_manifest(o, s, run); !st) return cli::command_error("export", st.message());
    int status = 0;
    const auto start = std::chrono::steady_clock::now();
    const bool show_progress = cli::stderr_is_terminal();
    bool line_open = false;
    const auto end_line = [&] {
        if (line_open) std::fputc('\n', stderr);
        line_open = false;
    };
    std::size_t inverted = 0, not_finite = 0;
    for (long i = 0; i < count; ++i) {
        const long k = run.frames.at(i);
        cli::pose_export_frame(s, o.fps, k);
        const fs::path file = fs::path(o.out_dir) / cli::export_frame_name(k, o.last, *o.format);
        auto frame = cli::write_export_frame(s, *o.format, file);
        if (!frame) {
            end_line();
            cli::command_error("export", o.scene + ": frame " + std::to_string(k) + ": " + frame.message());
            status = 1;
            break;
        }
        inverted += frame->inverted, not_finite += frame->not_finite;
        FrameRecord record{k, {}};
        for (const fs::path& f : frame->files) {
            auto p = cli::fingerprint(f);
            if (!p) {
                end_line();
                cli::command_error("export", p.message());
                status = 1;
                break;
            }
            record.files.emplace_back(f.filename().string(), *p);
        }
        if (status != 0) break;
        run.files.push_back(std::move(record));
        run.written = i + 1;
        if (i == 0 && count > 1) {
            double bytes = 0.0;
            for (const auto& f : run.files.back().files) bytes += double(f.second.bytes);
            if (Status st = cli::check_free_space(o.out_dir, count - 1, bytes,
                                                  "at the size of the first frame", "export");
                !st) {
                end_line();
                cli::command_error("export", st.message());
                status = 1;
                break;
            }
        }
        if (i + 1 == count) run.state = "complete";
        if (Status st = write_manifest(o, s, run); !st) {
            end_line();
            cli::command_error("export", st.message());
            status = 1;
            break;
        }
        if (show_progress) {
            const double elapsed =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const long done = i + 1;
            std::fprintf(stderr, "\rsplatffd export: frame %ld (%ld/%ld, %.0f%%) %.2f s/frame, ETA %.0f s   ",
                         k, done, count, 100.0 * double(done) / double(count), elapsed / double(done),
                         elapsed / double(done) * double(count - done));
            std::fflush(stderr);
            line_open = true;
        }
    }
    end_line();
    if (status != 0) {
        run.state = "failed";
        (void)write_manifest(o, s, run);
        return status;
    }
    if (count > 0)
        std::fprintf(stderr,
                     "splatffd export: wrote frames %ld..%ld (%ld %s files, %zu %s each) to %s in %.1f s\n",
                     run.frames.at(0), run.frames.at(count - 1), count,
                     std::string(cli::export_format_name(*o.format)).c_str(), s.count,
                     s.gaussians ? "Gaussians" : "splats", o.out_dir.c_str(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (not_finite > 0)
        std::fprintf(
            stderr,
            "splatffd export: warning: %zu deformed Gaussians were not finite (written transparent)\n",
            not_finite);
    (void)inverted;
    return 0;
}

int run_export(sffd::cli::Args args) {
    if (std::find(args.begin(), args.end(), "--web") != args.end()) return cli::run_export_web(args);
    ExportOptions o;
    if (auto rc = parse_export_args(args, o)) return *rc;
    cli::ExportScene scene;
    if (Status st = cli::open_export_scene(o.scene, o.cloud, scene); !st)
        return cli::command_error("export", st.message());
    if (!scene.gaussians && cli::gaussian_only(*o.format))
        return cli::command_error("export", o.scene + ": '" + scene.cloud_name +
                                                "' is surface splats; --format " +
                                                std::string(cli::export_format_name(*o.format)) +
                                                " is for 3D Gaussians: surface splats export as ply or glb "
                                                "(or convert them first: splatffd convert " +
                                                o.scene + " g.glb --gaussians --lattice fit)");
    if (auto rc = check_clips(o, scene)) return *rc;
    cli::note_unkeyed_edits("export", scene.registry, o.fps);

    ExportRun run;
    run.started_unix =
        std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
            .count();
    run.frames = cli::shard_frames(o.first, o.last, o.shard.value_or(cli::Shard{}));
    // The scene file's fingerprint ties the frames to the file they were made from (a built-in has none).
    run.scene_file = ojson{{"path", o.scene}};
    if (std::error_code ec; fs::is_regular_file(o.scene, ec)) {
        auto p = cli::fingerprint(o.scene);
        if (!p) return cli::command_error("export", p.message());
        run.scene_file["bytes"] = p->bytes;
        run.scene_file["fnv1a64"] = cli::hex64(p->fnv1a64);
    } else {
        run.scene_file["built_in"] = true;
    }

    if (!cli::create_output_folder(o.out_dir)) return 1;
    std::set<std::string> ours{manifest_path(o).filename().string()};
    for (long i = 0; i < run.frames.count; ++i) {
        const std::string name = cli::export_frame_name(run.frames.at(i), o.last, *o.format);
        ours.insert(name);
        if (*o.format == cli::ExportFormat::ply && !scene.gaussians)
            ours.insert(fs::path(name).stem().string() + "_texture.png");
    }
    if (auto rc = check_output_folder(o, ours)) return *rc;
    // A low estimate before the first frame (the smallest format, SPZ, is about 10 bytes a Gaussian at
    // SH degree 0), so no export that fits is refused; the first frame's real size is used after it.
    if (Status st = cli::check_free_space(o.out_dir, run.frames.count, 4.0 * double(scene.count),
                                          "a low estimate of 4 bytes a splat", "export");
        !st)
        return cli::command_error("export", st.message());
    return export_frames(o, scene, run);
}

}  // namespace

SFFD_COMMAND(export, "bake a scene's lattice clip into numbered deformed clouds (ply, spz, glb, ...)",
             run_export);
