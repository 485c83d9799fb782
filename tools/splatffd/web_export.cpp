#include "tools/splatffd/web_export.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/core/paths.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"
#include "systems/animation/clip_io.h"
#include "systems/animation/components.h"
#include "systems/animation/evaluate.h"
#include "systems/ffd/components.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "systems/splat_render/camera_math.h"
#include "systems/engine/engine_frame.h"

namespace sffd::cli {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kUsage =
    "usage: splatffd export SCENE --web DIR [--force] [--size WxH] [--fps F]\n"
    "  SCENE        a scene with one 3D Gaussian cloud deformed by one lattice that has a keyed clip\n"
    "  --web DIR    write a web player folder: open DIR/index.html in a browser (file:// or a static\n"
    "               server; it needs no network), play, pause, scrub; ?t=SECONDS&paused=1 seeks\n"
    "  --force      write into DIR even when it holds other files (files of the same names are replaced)\n"
    "  --size WxH   the canvas size and the camera's aspect (default 1280x720)\n"
    "  --fps F      frames per second of the scrub slider and of ?frame=K (default 24)\n"
    "The engine (PlayCanvas, npm) is copied into DIR: install it once with tools/fetch_web_engine.sh.\n";

// Lattices the shader hook is built for: at most 11 control points per axis (11^3 in the texture).
constexpr int kMaxWebDivisions = 10;

// Files the player reads, in the order the page loads them (index.html names them).
constexpr const char* kPlayerFiles[] = {"index.html", "player.js", "ffd_glsl.js", "clip.js"};
constexpr const char* kEngineName = "playcanvas.min.js";

struct Options {
    std::string scene;
    std::string dir;
    bool force = false;
    long width = 1280, height = 720;
    double fps = 24.0;
};

std::string base64(std::string_view bytes) {
    static constexpr char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const unsigned v = (unsigned(std::uint8_t(bytes[i])) << 16) |
                           (unsigned(std::uint8_t(bytes[i + 1])) << 8) | unsigned(std::uint8_t(bytes[i + 2]));
        out += table[(v >> 18) & 63], out += table[(v >> 12) & 63], out += table[(v >> 6) & 63],
            out += table[v & 63];
    }
    if (i + 1 == bytes.size()) {
        const unsigned v = unsigned(std::uint8_t(bytes[i])) << 16;
        out += table[(v >> 18) & 63], out += table[(v >> 12) & 63], out += "==";
    } else if (i + 2 == bytes.size()) {
        const unsigned v =
            (unsigned(std::uint8_t(bytes[i])) << 16) | (unsigned(std::uint8_t(bytes[i + 1])) << 8);
        out += table[(v >> 18) & 63], out += table[(v >> 12) & 63], out += table[(v >> 6) & 63], out += '=';
    }
    return out;
}

json vec3(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

// Reads a whole file as bytes (regular files only, through the checked reader).
Result<std::string> slurp(const fs::path& path, std::uint64_t max_bytes = std::uint64_t(1) << 32) {
    return read_file(path, max_bytes);
}

std::optional<fs::path> first_file(std::initializer_list<fs::path> candidates) {
    for (const fs::path& p : candidates) {
        std::error_code ec;
        if (fs::is_regular_file(p, ec)) return p;
    }
    return std::nullopt;
}

// The folder of the player's own files: <exe dir>/web/player (copied by the build) or
// <data root>/content/web/player (source tree, installed share/).
std::optional<fs::path> find_player_dir() {
    const fs::path exe_dir = paths::executable_path().parent_path();
    for (const fs::path& d : {exe_dir / "web" / "player", paths::content_dir() / "web" / "player"}) {
        bool all = true;
        for (const char* f : kPlayerFiles) {
            std::error_code ec;
            all = all && fs::is_regular_file(d / f, ec);
        }
        if (all) return d;
    }
    return std::nullopt;
}

Result<Options> parse(Args args) {
    Options o;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        if (a == "--web" && has_value) o.dir = args[++i];
        else if (a == "--force") o.force = true;
        else if (a == "--size" && has_value) {
            if (Status st = parse_integer_pair("--size", args[++i], 'x', 16, 8192, o.width, o.height); !st)
                return st.error();
        } else if (a == "--fps" && has_value) {
            auto f = parse_number("--fps", args[++i], 1.0, 1000.0);
            if (!f) return f.error();
            o.fps = *f;
        } else if (!a.empty() && a[0] != '-' && o.scene.empty()) o.scene = a;
        else if (a == "--web" || a == "--size" || a == "--fps") return make_error(a + " needs a value");
        else return make_error("unknown argument '" + a + "'");
    }
    if (o.scene.empty()) return make_error("a SCENE is required");
    if (o.dir.empty()) return make_error("--web DIR is required");
    return o;
}

// What the player needs from the scene, checked: the one Gaussian cloud, its one lattice and its clip.
struct WebScene {
    const GaussianCloud* cloud = nullptr;
    Transform transform;
    const Lattice* lattice = nullptr;
    const AnimationClip* clip = nullptr;
    double playback_speed = 1.0;
    Camera camera;
    glm::dmat4 to_cloud{1.0};  // the lattice's frame to the cloud's (ffd::lattice_to_cloud)
    std::vector<std::string> notes;
};

Result<WebScene> pick_scene(const ecs::Registry& r, const Options& o) {
    WebScene s;
    const std::string& name = o.scene;
    std::vector<ecs::Entity> clouds;
    r.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud&) { clouds.push_back(e); });
    std::size_t surface = 0;
    r.view<const SplatCloud>().each([&](const SplatCloud&) { ++surface; });
    if (clouds.empty()) {
        if (surface)
            return make_error(name +
                              ": the scene holds surface splats, and the web player plays 3D Gaussians only "
                              "(PlayCanvas has no surface splatting, so a conversion would not look like "
                              "`splatffd render`); convert them first: splatffd convert " +
                              name + " OUT.ply --gaussians, then give OUT.ply a lattice and a clip");
        return make_error(name + ": the scene has no 3D Gaussian cloud");
    }
    if (clouds.size() > 1)
        return make_error(name + ": the scene has " + std::to_string(clouds.size()) +
                          " Gaussian clouds; the web player plays one");
    const ecs::Entity ce = clouds.front();
    s.cloud = &r.get<GaussianCloud>(ce);
    if (const Transform* t = r.try_get<Transform>(ce)) s.transform = *t;
    const Deformers* d = r.try_get<Deformers>(ce);
    if (!d || d->lattices.empty())
        return make_error(name +
                          ": the Gaussian cloud has no lattice: nothing to animate (add one with "
                          "splatffd convert IN OUT.glb --lattice fit, or in the editor)");
    if (d->lattices.size() > 1)
        return make_error(name + ": the cloud follows " + std::to_string(d->lattices.size()) +
                          " lattices in a chain; the web player evaluates one");
    const ecs::Entity le = d->lattices.front();
    s.lattice = r.try_get<Lattice>(le);
    if (!s.lattice) return make_error(name + ": the cloud's deformer is not a lattice entity");
    if (Status st = validate_lattice(*s.lattice, name); !st) return st.error();
    const glm::ivec3 div = s.lattice->divisions;
    if (div.x > kMaxWebDivisions || div.y > kMaxWebDivisions || div.z > kMaxWebDivisions)
        return make_error(name + ": the lattice has " + std::to_string(div.x + 1) + "x" +
                          std::to_string(div.y + 1) + "x" + std::to_string(div.z + 1) +
                          " control points; the web player takes at most 11 per axis");
    // Deformed in the cloud's frame with the lattice mapped there, as the engine does (lattice_frame.h);
    // the clip still runs in the lattice's own frame, so its poses are mapped by the page.
    s.to_cloud = ffd::lattice_to_cloud(r, ce, le);
    s.clip = r.try_get<AnimationClip>(le);
    std::size_t keys = 0;
    if (s.clip)
        for (const AnimationTrack& t : s.clip->tracks)
            if (!t.points.empty()) keys += t.keys.size();
    // Refused rather than exported as a still: a player of one pose is almost always a scene saved
    // before its clip was keyed, and `splatffd render` already makes the still.
    if (!s.clip || keys == 0)
        return make_error(name +
                          ": the lattice's clip has no keys: nothing to play (key a pose in the "
                          "editor's timeline, or render the still with splatffd render)");
    if (Status st = validate_clip(*s.clip, s.lattice->size()); !st)
        return make_error(name + ": " + st.message());
    if (const AnimationState* st = r.try_get<AnimationState>(le)) s.playback_speed = st->speed;
    if (r.try_get<UnkeyedEdit>(le))
        s.notes.push_back("the lattice has an un-keyed edit; the player shows the clip's pose at every time");
    if (const PointWeights* w = r.try_get<PointWeights>(ce); w && !w->values.empty())
        s.notes.push_back(
            "the cloud has per-point weights, which the player does not apply (every Gaussian "
            "follows the lattice fully; splatffd render applies them)");
    s.camera = render::scene_camera(r, double(o.width) / double(o.height));
    return s;
}

json scene_json(const WebScene& s, const Options& o, const std::string& capture_format) {
    json j;
    j["version"] = 1;
    j["generator"] = std::string("splatffd ") + SFFD_VERSION;
    j["capture"] = {{"script", "capture.js"},
                    {"format", capture_format},
                    {"count", s.cloud->size()},
                    {"sh_degree", s.cloud->sh_degree}};
    j["transform"] = {{"translation", vec3(s.transform.translation)},
                      {"rotation", json::array({s.transform.rotation.w, s.transform.rotation.x,
                                                s.transform.rotation.y, s.transform.rotation.z})},
                      {"scale", vec3(s.transform.scale)}};
    const Lattice& l = *s.lattice;
    json rest = json::array();
    for (const glm::dvec3& p : l.rest) rest.push_back(vec3(p));
    // origin and axes in the cloud's frame (what the shader reads), rest points in the lattice's (what the
    // clip transforms); to_cloud (rows of the affine map) takes each pose's displacements across.
    const glm::dmat4& m = s.to_cloud;
    const glm::dmat3 lin(m);
    json to_cloud = json::array();
    for (int row = 0; row < 3; ++row) to_cloud.push_back({m[0][row], m[1][row], m[2][row], m[3][row]});
    j["lattice"] = {
        {"origin", vec3(glm::dvec3(m * glm::dvec4(l.origin, 1.0)))},
        {"axes", json::array({vec3(lin * l.axes[0]), vec3(lin * l.axes[1]), vec3(lin * l.axes[2])})},
        {"to_cloud", std::move(to_cloud)},
        {"divisions", json::array({l.divisions.x, l.divisions.y, l.divisions.z})},
        {"basis", l.basis == LatticeBasis::bspline ? "bspline" : "bernstein"},
        {"rest", std::move(rest)}};
    j["clip"] = clip_to_json(*s.clip);
    j["playback_speed"] = s.playback_speed;
    j["camera"] = {{"eye", vec3(s.camera.eye)},   {"target", vec3(s.camera.target)},
                   {"up", vec3(s.camera.up)},     {"fov_y_degrees", s.camera.fov_y_degrees},
                   {"near", s.camera.near_plane}, {"far", s.camera.far_plane}};
    j["size"] = json::array({o.width, o.height});
    j["fps"] = o.fps;
    return j;
}

// DIR is new, empty, or (with --force) anything; a file in the way of DIR is refused.
Status check_output_dir(const Options& o) {
    std::error_code ec;
    const fs::path dir(o.dir);
    if (!fs::exists(dir, ec)) return {};
    if (!fs::is_directory(dir, ec)) return make_error(o.dir + ": exists and is not a folder");
    if (o.force) return {};
    std::size_t n = 0;
    std::string first;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
        if (n++ == 0) first = entry.path().filename().string();
    }
    if (ec) return make_error(o.dir + ": cannot list the folder (" + ec.message() + ")");
    if (n)
        return make_error(o.dir + ": the folder is not empty (" + std::to_string(n) + " entries, e.g. '" +
                          first + "'); choose a new folder, or pass --force to write the player into it");
    return {};
}

// The capture as SOG bytes (PlayCanvas's own compressed format: about a tenth of a 3DGS PLY), written
// through the writer's atomic path into a hidden temporary beside the output, read back, removed.
Result<std::string> capture_bytes(const GaussianCloud& cloud, const fs::path& dir, std::string& format) {
    const fs::path tmp = dir / ".capture.tmp.sog";
    format = "sog";
    if (Status st = gaussian::write_sog(tmp, cloud); !st) return st.error();
    auto bytes = slurp(tmp);
    std::error_code ec;
    fs::remove(tmp, ec);
    return bytes;
}

}  // namespace

std::optional<fs::path> find_web_engine() {
    if (const char* env = std::getenv("SPLATFFD_WEB_ENGINE"); env && *env) return first_file({fs::path(env)});
    const fs::path exe_dir = paths::executable_path().parent_path();
    return first_file({exe_dir / "web" / kEngineName, paths::data_root() / "web" / kEngineName,
                       paths::cache_dir() / "web" / "node_modules" / "playcanvas" / "build" / kEngineName});
}

int run_export_web(Args args) {
    for (const std::string& a : args)
        if (is_help(a)) return help(kUsage);
    auto parsed = parse(args);
    if (!parsed) return usage_error("export", parsed.message(), kUsage);
    const Options& o = *parsed;

    if (Status st = check_output_dir(o); !st) return command_error("export", st.message());
    ecs::Registry registry;
    sffd::use_engine_scene_hooks(registry);
    if (Status st = load_scene(registry, o.scene); !st) return command_error("export", st.message());
    // The capture is an export: no hidden or deleted Gaussian goes into it (runtime/scene/point_subset.h).
    std::vector<ecs::Entity> gaussians;
    registry.each_entity([&](ecs::Entity e) {
        if (registry.has<GaussianCloud>(e)) gaussians.push_back(e);
    });
    for (ecs::Entity e : gaussians)
        if (auto gone = drop_gone_points(registry, e, PointDrop::hidden_and_deleted); !gone)
            return command_error("export", o.scene + ": " + gone.message());
    auto scene = pick_scene(registry, o);
    if (!scene) return command_error("export", scene.message());
    const auto engine = find_web_engine();
    if (!engine)
        return command_error("export", "the PlayCanvas engine is not installed (" + std::string(kEngineName) +
                                           " not found): run tools/fetch_web_engine.sh");
    const auto player = find_player_dir();
    if (!player)
        return command_error("export", "the player's files (content/web/player) are missing from " +
                                           paths::content_dir().string());
    for (const std::string& n : scene->notes) std::fprintf(stderr, "splatffd export: note: %s\n", n.c_str());

    std::error_code ec;
    fs::create_directories(o.dir, ec);
    if (ec) return command_error("export", o.dir + ": cannot create the folder (" + ec.message() + ")");
    const fs::path dir(o.dir);

    std::string format;
    auto bytes = capture_bytes(*scene->cloud, dir, format);
    if (!bytes) return command_error("export", bytes.message());
    // Classic scripts, not fetched files: file:// pages may not fetch, and may not load modules.
    const std::string capture_js =
        "window.SFFD_CAPTURE = {format: \"" + format + "\", base64: \"" + base64(*bytes) + "\"};\n";
    const std::string scene_js = "window.SFFD_SCENE = " + scene_json(*scene, o, format).dump() + ";\n";
    if (Status st = write_file_atomic(dir / "capture.js", capture_js); !st)
        return command_error("export", st.message());
    if (Status st = write_file_atomic(dir / "scene.js", scene_js); !st)
        return command_error("export", st.message());
    for (const char* f : kPlayerFiles) {
        auto text = slurp(*player / f);
        if (!text) return command_error("export", text.message());
        if (Status st = write_file_atomic(dir / f, *text); !st) return command_error("export", st.message());
    }
    auto engine_bytes = slurp(*engine);
    if (!engine_bytes) return command_error("export", engine_bytes.message());
    if (Status st = write_file_atomic(dir / kEngineName, *engine_bytes); !st)
        return command_error("export", st.message());

    std::uintmax_t total = 0;
    for (const auto& entry : fs::directory_iterator(dir, ec))
        if (entry.is_regular_file(ec)) total += entry.file_size(ec);
    std::printf(
        "wrote %s: web player, %zu Gaussians, lattice %dx%dx%d %s, clip '%s' (%.3g s), %.1f MB; open "
        "%s\n",
        o.dir.c_str(), scene->cloud->size(), scene->lattice->divisions.x + 1, scene->lattice->divisions.y + 1,
        scene->lattice->divisions.z + 1,
        scene->lattice->basis == LatticeBasis::bspline ? "B-spline" : "Bernstein", scene->clip->name.c_str(),
        scene->clip->duration, double(total) / 1e6, (dir / "index.html").c_str());
    return 0;
}

}  // namespace sffd::cli
