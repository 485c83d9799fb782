// splatffd pick [SCENE] --at X,Y [--size WxH] [--xray] [--tolerance PX] [--first-gaussian]
//
// Loads a scene (built-in name or file; default `sphere`), looks through its camera (or the default
// framing camera, render::scene_camera, the same one `splatffd render` uses) at a WxH viewport, picks at
// the centre of pixel (X, Y) (origin top-left, y down; fractional values allowed) and prints one JSON
// object:
//   {"hit":true,"kind":"control_point","entity":4,"generation":0,"name":"lattice","index":665,
//    "lattice_ijk":[6,0,5],"position":[x,y,z],"distance":d,"pixel":[X,Y]}
//   {"hit":true,"kind":"surface","entity":3,...,"index":1234,"position":[...],"distance":d,...}
//   {"hit":true,"kind":"gaussian","entity":0,"name":"scene.ply","index":42,"position":[...],"distance":d,...}
//   {"hit":false,"pixel":[X,Y]}
// SCENE may be a 3D Gaussian file (3DGS PLY, .splat, SPZ, KHR glb): one Gaussian-cloud entity, seen
// through the camera `splatffd render` frames it with; Gaussians are picked as the ellipsoids where
// their 3DGS alpha reaches 1/255 (systems/picking/gaussian_source.h). Deformed scenes are picked as
// deformed: picking computes what it needs (splats: the FFD CPU path; Gaussians: centres + Jacobians).
// A miss is an answer, not an error: exit 0 (scripts test "hit"). Exit 1: the scene cannot be loaded;
// exit 2: usage. Deformed scenes are picked as deformed (picking deforms on the CPU).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "runtime/assets/scene.h"
#include "runtime/core/json_text.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/components.h"
#include "systems/picking/picking_system.h"
#include "systems/splat_render/camera_math.h"
#include "tools/splatffd/command.h"
#include "systems/engine/engine_frame.h"

namespace {

using namespace sffd;

constexpr const char* kUsage =
    "usage: splatffd pick [SCENE] --at X,Y [--size WxH] [--xray] [--tolerance PX] [--first-gaussian]\n"
    "  SCENE         built-in name (sphere, face), a scene/point-cloud file or a 3D Gaussian file\n"
    "                (3DGS .ply, .splat, .spz, .ksplat, .sog, a SOG folder, KHR .glb; default: sphere)\n"
    "  --at X,Y      pixel to pick (origin top-left, y down; picks the pixel's centre)\n"
    "  --size WxH    viewport in pixels (default 1280x720, as `splatffd render`)\n"
    "  --xray        control points hidden behind the surface can be picked (default: only visible ones)\n"
    "  --tolerance P control points within P pixels of the cursor win (default 6)\n"
    "  --first-gaussian  the first Gaussian ellipsoid on the ray wins (default: the Gaussian\n"
    "                contributing most to the pixel)\n"
    "prints the hit as JSON; a miss prints {\"hit\":false} and exits 0\n";

bool parse_pair(const std::string& s, char sep, double& a, double& b) {
    const auto at = s.find(sep);
    if (at == std::string::npos) return false;
    try {
        std::size_t n1 = 0, n2 = 0;
        const std::string first = s.substr(0, at), second = s.substr(at + 1);
        a = std::stod(first, &n1);
        b = std::stod(second, &n2);
        return n1 == first.size() && n2 == second.size() && std::isfinite(a) && std::isfinite(b);
    } catch (...) {
        return false;
    }
}

// Names come from file names and glTF strings (any bytes): json_quote() keeps the output valid UTF-8.
std::string json_string(const std::string& s) { return sffd::json_quote(s); }

int run_pick(sffd::cli::Args args) {
    std::string scene = "sphere";
    bool have_at = false, scene_given = false;
    double x = 0, y = 0, w = 1280, h = 720, tolerance = 6.0;
    bool xray = false, first_gaussian = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        if (cli::is_help(a)) {
            return cli::help(kUsage);
        } else if (a == "--at" && has_value) {
            if (!parse_pair(args[++i], ',', x, y)) {
                std::fprintf(stderr, "splatffd pick: --at expects X,Y (numbers), got '%s'\n",
                             args[i].c_str());
                return 2;
            }
            have_at = true;
        } else if (a == "--size" && has_value) {
            if (!parse_pair(args[++i], 'x', w, h) || w < 1 || h < 1 || w != std::floor(w) ||
                h != std::floor(h) || w > 65536 || h > 65536) {
                std::fprintf(stderr, "splatffd pick: --size expects WxH (positive integers), got '%s'\n",
                             args[i].c_str());
                return 2;
            }
        } else if (a == "--tolerance" && has_value) {
            auto t = sffd::cli::parse_number("--tolerance", args[++i], 0.0, 1e6);  // the shared number parser
            if (!t) {
                std::fprintf(stderr, "splatffd pick: %s (pixels)\n", t.message().c_str());
                return 2;
            }
            tolerance = *t;
        } else if (a == "--xray") {
            xray = true;
        } else if (a == "--first-gaussian") {
            first_gaussian = true;
        } else if (!a.empty() && a[0] != '-' && !scene_given) {
            scene = a;
            scene_given = true;
        } else {
            return cli::usage_error("pick", "unexpected argument '" + a + "'", kUsage);
        }
    }
    if (!have_at) {
        return cli::usage_error("pick", "--at X,Y is required", kUsage);
    }
    if (x < 0 || y < 0 || x >= w || y >= h) {
        std::fprintf(stderr, "splatffd pick: pixel %g,%g is outside the %gx%g viewport\n", x, y, w, h);
        return 2;
    }

    ecs::Registry registry;
    sffd::use_engine_scene_hooks(registry);
    Camera camera;
    // Surface scenes and Gaussian files alike (splatffd's main registers the Gaussian scene hooks): the
    // camera is the one `render` sees them through.
    if (const Status st = load_scene(registry, scene); !st) {
        return cli::command_error("pick", st.message());
    }
    camera = render::scene_camera(registry, w / h);
    const glm::ivec2 size{int(w), int(h)};
    const picking::ScreenView view = picking::make_screen_view(camera, size);
    picking::PickQuery query = picking::query_at_pixel(view, {x + 0.5, y + 0.5});
    query.xray = xray;
    query.tolerance_px = tolerance;

    if (first_gaussian) {
        picking::PickSettings settings = registry.try_resource<picking::PickSettings>()
                                             ? *registry.try_resource<picking::PickSettings>()
                                             : picking::PickSettings{};
        settings.gaussians = picking::GaussianPick::first_ellipsoid;
        registry.set_resource<picking::PickSettings>(settings);
    }
    // Through the engine's picking system, as the editor does: request, run the phase, read the result.
    const std::uint64_t pick_id = picking::post_pick(registry, query);
    picking::picking_system(registry, FrameContext{});
    const picking::PickHit* answer = picking::find_pick_answer(registry, pick_id);
    const picking::PickHit hit = answer ? *answer : picking::PickHit{};

    if (!hit) {
        std::printf("{\"hit\":false,\"pixel\":[%.17g,%.17g]}\n", x, y);
        return 0;
    }
    std::string out = "{\"hit\":true,\"kind\":\"" + std::string(picking::pick_kind_name(hit.kind)) + "\"";
    out += ",\"entity\":" + std::to_string(hit.entity.index) +
           ",\"generation\":" + std::to_string(hit.entity.generation);
    if (const Name* name = registry.try_get<Name>(hit.entity)) out += ",\"name\":" + json_string(name->value);
    out += ",\"index\":" + std::to_string(hit.index);
    if (hit.kind == picking::PickKind::control_point) {
        if (const Lattice* l = registry.try_get<Lattice>(hit.entity)) {
            const int n1 = l->divisions.z + 1, m1 = l->divisions.y + 1;
            const int idx = int(hit.index);
            out += ",\"lattice_ijk\":[" + std::to_string(idx / (m1 * n1)) + "," +
                   std::to_string((idx / n1) % m1) + "," + std::to_string(idx % n1) + "]";
        }
    }
    if (hit.kind == picking::PickKind::gaussian) {
        if (const GaussianCloud* g = registry.try_get<GaussianCloud>(hit.entity);
            g && hit.index < g->opacities.size()) {
            char op[64];
            std::snprintf(op, sizeof op, ",\"opacity\":%.9g", double(g->opacities[hit.index]));
            out += op;
        }
    }
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  ",\"position\":[%.17g,%.17g,%.17g],\"distance\":%.17g,\"pixel\":[%.17g,%.17g]}",
                  hit.position.x, hit.position.y, hit.position.z, hit.distance, x, y);
    out += buf;
    std::printf("%s\n", out.c_str());
    return 0;
}

}  // namespace

SFFD_COMMAND(pick, "ray-pick a control point or surface point and print it as JSON", run_pick);
