// splatffd info FILE|SCENE: counts, bounds, attributes and lattices of a file or built-in scene. A scene's
// deformed clouds get two bounds, rest and deformed (by their lattices as saved); each lattice its transform
// and its clip (with an un-keyed edit, if any).
// PLY files are streamed (any size); glTF scene files and built-ins are loaded into a registry and
// every cloud, lattice, binding, camera and light is listed. Gaussian splat files (3DGS and compressed
// PLY, .spz, .splat, .ksplat) end with an "N Gaussians, SH degree D" line.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_order.h"
#include "runtime/scene/point_pages.h"
#include "systems/animation/components.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/convert_lod.h"
#include "tools/splatffd/convert_potree.h"
#include "systems/engine/engine_frame.h"

namespace {

using namespace sffd;

void print_bounds(const char* indent, const glm::dvec3& lo, const glm::dvec3& hi,
                  const char* label = "bounds", const std::string& after = "") {
    std::printf("%s%-8s [%.6g, %.6g, %.6g] .. [%.6g, %.6g, %.6g]  (size %.6g x %.6g x %.6g)%s\n", indent,
                label, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, hi.x - lo.x, hi.y - lo.y, hi.z - lo.z,
                after.c_str());
}

void print_transform(const ecs::Registry& reg, ecs::Entity e) {
    const Transform* t = reg.try_get<Transform>(e);
    const Transform identity;
    const Transform& x = t ? *t : identity;
    std::printf(
        "    transform translation [%.6g, %.6g, %.6g], rotation (x y z w) [%.6g, %.6g, %.6g, %.6g], scale "
        "[%.6g, %.6g, %.6g]%s\n",
        x.translation.x, x.translation.y, x.translation.z, x.rotation.x, x.rotation.y, x.rotation.z,
        x.rotation.w, x.scale.x, x.scale.y, x.scale.z, t ? "" : " (none: identity)");
}

// The cloud's bounds twice when lattices deform it: as authored (rest) and as its lattices deform it as
// saved (the pose render shows at the saved clip time, deform and convert write). Positions only, CPU; both
// in the cloud's own frame (origin + positions, before its Transform), where the lattices deform it.
void print_rest_and_deformed(const ecs::Registry& reg, ecs::Entity e, std::vector<glm::vec3> positions,
                             const glm::dvec3& origin) {
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, origin + glm::dvec3(p));
        hi = glm::max(hi, origin + glm::dvec3(p));
    }
    const Deformers* d = reg.try_get<Deformers>(e);
    if (!d || d->lattices.empty()) return print_bounds("    ", lo, hi);
    print_bounds("    ", lo, hi, "rest");
    std::string names;
    // Each lattice in the cloud's frame (both Transforms), as the engine deforms it.
    const ffd::CloudLattices framed = ffd::cloud_lattices(reg, e, d->lattices);
    for (std::size_t i = 0; i < framed.lattices.size(); ++i) {
        const Lattice* lattice = framed.lattices[i];
        const Name* n = reg.try_get<Name>(framed.entities[i]);
        names += (names.empty() ? "'" : ", '") + (n ? n->value : std::string("?")) + "'";
        if (lattice->current == lattice->rest) continue;
        const ffd::PointsIn in{positions.data(), nullptr, nullptr, nullptr, positions.size(), origin};
        const ffd::PointsOut out{positions.data(), nullptr, nullptr, nullptr};
        if (auto st = ffd::deform(*lattice, in, out); !st) {
            std::printf("    deformed (not computed: %s)\n", st.message().c_str());
            return;
        }
    }
    lo = glm::dvec3(INFINITY), hi = glm::dvec3(-INFINITY);
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, origin + glm::dvec3(p));
        hi = glm::max(hi, origin + glm::dvec3(p));
    }
    print_bounds("    ", lo, hi, "deformed", "  by " + names + " as saved");
}

// "    deformed by 'a' 'b'" for a cloud with Deformers (lattice names, in order).
void print_deformers(const ecs::Registry& reg, ecs::Entity e) {
    const Deformers* d = reg.try_get<Deformers>(e);
    if (!d) return;
    std::printf("    deformed by");
    for (ecs::Entity l : d->lattices) {
        const Name* ln = reg.try_get<Name>(l);
        std::printf(" '%s'", ln ? ln->value.c_str() : "?");
    }
    std::printf("\n");
}

// "    clip     'paper demo': 24 tracks, 96 keys, 4 s, loop, speed 1; opens at clip time 0 s" for a lattice
// with a clip, then its un-keyed edit if it has one (the rule every command follows: systems/animation).
void print_clip(const ecs::Registry& reg, ecs::Entity e) {
    const AnimationClip* clip = reg.try_get<AnimationClip>(e);
    if (!clip) return;
    std::size_t keys = 0;
    for (const AnimationTrack& t : clip->tracks) keys += t.keys.size();
    const char* mode = clip->mode == PlayMode::loop   ? "loop"
                       : clip->mode == PlayMode::once ? "once"
                                                      : "ping_pong";
    const AnimationState* state = reg.try_get<AnimationState>(e);
    std::printf("    clip     '%s': %zu tracks, %zu keys, %.6g s, %s, speed %g; opens at clip time %.6g s\n",
                clip->name.c_str(), clip->tracks.size(), keys, clip->duration, mode,
                clip->speed * (state ? state->speed : 1.0), state ? state->time : 0.0);
    for (const UnkeyedEditReport& edit : unkeyed_edits(reg))
        if (edit.lattice == e) {
            std::printf("    WARNING  %s\n", describe_unkeyed_edit(edit).c_str());
        }
}

// "min 0, max 1, mean 0.5" of a weight column.
std::string weight_stats(double lo, double hi, double sum, std::size_t n) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "min %.6g, max %.6g, mean %.6g", lo, hi, n ? sum / double(n) : 0.0);
    return buf;
}

// The cloud's columns (runtime/scene/point_columns.h, the one table): every present one with its type,
// then the optional ones' contents: the flags' counts, the weights' range.
void print_columns(const std::vector<ColumnRef>& columns, const char* indent = "    ") {
    std::string line;
    const ColumnRef* flags = nullptr;
    const ColumnRef* weights = nullptr;
    for (const ColumnRef& c : columns) {
        if (!c.present()) continue;
        line += (line.empty() ? "" : ", ") + std::string(c.spec->name) + " " +
                std::string(column_type_name(c.spec->type));
        if (c.values > 1) line += " x" + std::to_string(c.values);
        if (c.spec->name == "flags") flags = &c;
        if (c.spec->name == "weight") weights = &c;
    }
    std::printf("%scolumns  %s\n", indent, line.c_str());
    if (flags) {
        std::size_t selected = 0, hidden = 0, deleted = 0;
        const StridedView<const std::uint8_t> bits = typed_column<const std::uint8_t>(*flags);
        for (std::size_t i = 0; i < bits.size(); ++i) {
            const std::uint8_t b = bits[i];
            selected += (b & kPointSelected) != 0, hidden += (b & kPointHidden) != 0;
            deleted += (b & kPointDeleted) != 0;
        }
        std::printf("%sflags    %zu selected, %zu hidden, %zu deleted of %zu points\n", indent, selected,
                    hidden, deleted, flags->count);
    }
    if (weights) {
        double lo = INFINITY, hi = -INFINITY, sum = 0.0;
        const StridedView<const float> values = typed_column<const float>(*weights);
        for (std::size_t i = 0; i < values.size(); ++i) {
            const double w = double(values[i]);
            lo = std::min(lo, w), hi = std::max(hi, w), sum += w;
        }
        std::printf("%sweight   %s\n", indent, weight_stats(lo, hi, sum, weights->count).c_str());
    }
}

// Gaussian files without a header to list: read whole (the readers' budgets apply), then summarised.
int info_gaussians(const std::string& file, const char* format) {
    auto g = gaussian::read_gaussians(file);
    if (!g) {
        std::fprintf(stderr, "splatffd info: %s\n", g.message().c_str());
        return 1;
    }
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(file, ec);
    std::printf("%s: %s, %llu bytes\n", file.c_str(), format,
                static_cast<unsigned long long>(ec ? 0 : bytes));
    std::printf("  %zu Gaussians, SH degree %d\n", g->size(), g->sh_degree);
    print_columns(point_columns(*g), "  ");
    if (g->size()) {
        glm::dvec3 lo(INFINITY), hi(-INFINITY);
        for (const glm::vec3& p : g->positions) {
            lo = glm::min(lo, g->origin + glm::dvec3(p));
            hi = glm::max(hi, g->origin + glm::dvec3(p));
        }
        print_bounds("  ", lo, hi);
    }
    return 0;
}

int info_ply(const std::string& file) {
    auto r = ply::Reader::open(file);
    if (!r) {
        std::fprintf(stderr, "splatffd info: %s\n", r.message().c_str());
        return 1;
    }
    const ply::Header& h = r->header();
    std::printf("%s: PLY %s, %llu bytes\n", file.c_str(), ply::format_name(h.format),
                static_cast<unsigned long long>(r->file_size()));
    for (const auto& c : h.comments) std::printf("  comment  %s\n", c.c_str());
    for (const auto& e : h.elements) {
        std::printf("  element  %s: %llu\n", e.name.c_str(), static_cast<unsigned long long>(e.count));
        for (const auto& p : e.properties)
            if (p.is_list)
                std::printf("    list %s %s %s\n", ply::type_name(p.count_type), ply::type_name(p.type),
                            p.name.c_str());
            else std::printf("    %s %s\n", ply::type_name(p.type), p.name.c_str());
    }
    const int vi = h.find("vertex");
    if (vi < 0) return 0;
    const ply::Element& ve = h.elements[static_cast<std::size_t>(vi)];
    if (gaussian::is_compressed_ply(h))
        return info_gaussians(file, "compressed PLY (PlayCanvas chunk + packed vertex elements)");
    if (gaussian::is_gaussian_element(ve)) {
        // The header alone gives the count and degree; a bad layout is the reader's message.
        auto layout = gaussian::ply_layout(ve, file);
        if (!layout) {
            std::fprintf(stderr, "splatffd info: %s\n", layout.message().c_str());
            return 1;
        }
        std::printf("  %llu Gaussians, SH degree %d (3DGS PLY)\n", static_cast<unsigned long long>(ve.count),
                    layout->degree);
    }
    const int x = ve.find("x"), y = ve.find("y"), z = ve.find("z");
    if (x < 0 || y < 0 || z < 0) return 0;
    const int weight = assets::ply_weight_property(ve);  // PointWeights, read by render, view and deform
    double wlo = INFINITY, whi = -INFINITY, wsum = 0.0;
    std::size_t wbad = 0;
    if (auto s = r->seek_element("vertex"); !s) {
        std::fprintf(stderr, "splatffd info: %s\n", s.message().c_str());
        return 1;
    }
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    std::size_t bad = 0;
    ply::Chunk c;
    while (true) {
        auto n = r->read_rows(1 << 16, c);
        if (!n) {
            std::fprintf(stderr, "splatffd info: %s\n", n.message().c_str());
            return 1;
        }
        if (*n == 0) break;
        for (std::size_t i = 0; i < *n; ++i) {
            const glm::dvec3 p(c.columns[static_cast<std::size_t>(x)].values[i],
                               c.columns[static_cast<std::size_t>(y)].values[i],
                               c.columns[static_cast<std::size_t>(z)].values[i]);
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
                ++bad;
                continue;
            }
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        if (weight >= 0)
            for (std::size_t i = 0; i < *n; ++i) {
                const double w = c.columns[static_cast<std::size_t>(weight)].values[i];
                if (!(w >= 0.0 && w <= 1.0)) ++wbad;
                wlo = std::min(wlo, w), whi = std::max(whi, w), wsum += w;
            }
    }
    if (lo.x <= hi.x) print_bounds("  ", lo, hi);
    if (weight >= 0)
        std::printf("  weight   %s (column weight f32: the deformation's per-point weight)\n",
                    weight_stats(wlo, whi, wsum, std::size_t(ve.count)).c_str());
    if (wbad)
        std::printf("  WARNING  %zu weights are not in [0, 1] (render, view and deform refuse this file)\n",
                    wbad);
    if (bad)
        std::printf("  WARNING  %zu vertices have non-finite coordinates (import refuses this file)\n", bad);
    return 0;
}

// How compact the cloud's pages are in space (runtime/scene/point_order.h): a file stored in scan or band
// order has pages as wide as the cloud; `convert --order morton` makes them small blocks.
void print_pages(const std::vector<glm::vec3>& positions) {
    const PageCompactness p = page_compactness(positions);
    std::printf(
        "    pages    %zu of %zu points; mean page box %.3g%% of the cloud box's volume, %.3g%% of its "
        "diagonal\n",
        p.pages, kPagePoints, 100.0 * p.mean_volume_share, 100.0 * p.mean_diagonal_share);
}

void summarise_registry(const ecs::Registry& reg) {
    std::size_t total = 0;
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) {
        const Name* n = reg.try_get<Name>(e);
        total += c.size();
        std::printf("  cloud    '%s': %zu splats; origin [%.9g, %.9g, %.9g]\n", n ? n->value.c_str() : "?",
                    c.size(), c.origin.x, c.origin.y, c.origin.z);
        print_columns(point_columns(reg, e));
        if (!c.texture.rgba8.empty())
            std::printf("    texture  %dx%d%s%s\n", c.texture.width, c.texture.height,
                        c.texture.path.empty() ? "" : " ", c.texture.path.c_str());
        if (c.size()) {
            double rmin = INFINITY, rmax = 0, rsum = 0;
            for (std::size_t i = 0; i < c.size(); ++i) {
                if (!c.axis_u.empty()) {
                    const double rr = static_cast<double>(glm::length(c.axis_u[i]));
                    rmin = std::min(rmin, rr);
                    rmax = std::max(rmax, rr);
                    rsum += rr;
                }
            }
            print_rest_and_deformed(reg, e, c.positions, c.origin);
            print_pages(c.positions);
            if (!c.axis_u.empty())
                std::printf("    radius   min %.4g, mean %.4g, max %.4g\n", rmin,
                            rsum / static_cast<double>(c.size()), rmax);
        }
        print_deformers(reg, e);
    });
    std::size_t gaussians = 0;
    reg.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& g) {  // 3D Gaussian entities
        const Name* n = reg.try_get<Name>(e);
        const GaussianSource* src = reg.try_get<GaussianSource>(e);
        gaussians += g.size();
        std::printf("  gaussians '%s': %zu Gaussians, SH degree %d%s%s\n", n ? n->value.c_str() : "?",
                    g.size(), g.sh_degree, src ? "; file " : "", src ? src->path.string().c_str() : "");
        print_columns(point_columns(reg, e));
        if (g.size()) print_rest_and_deformed(reg, e, g.positions, g.origin), print_pages(g.positions);
        print_deformers(reg, e);
    });
    reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice& l) {
        const Name* n = reg.try_get<Name>(e);
        std::size_t moved = 0;
        double max_move = 0;
        for (std::size_t i = 0; i < l.rest.size() && i < l.current.size(); ++i) {
            const double d = glm::length(l.current[i] - l.rest[i]);
            if (d > 0) ++moved;
            max_move = std::max(max_move, d);
        }
        std::printf(
            "  lattice  '%s': %s, divisions %d x %d x %d (%zu control points), %zu displaced (max %.4g)\n",
            n ? n->value.c_str() : "?", l.basis == LatticeBasis::bernstein ? "bernstein" : "bspline",
            l.divisions.x, l.divisions.y, l.divisions.z, l.size(), moved, max_move);
        const bool aligned = l.axes[0].y == 0 && l.axes[0].z == 0 && l.axes[1].x == 0 && l.axes[1].z == 0 &&
                             l.axes[2].x == 0 && l.axes[2].y == 0;
        if (aligned) {
            print_bounds("    ", l.origin, l.origin + l.axes[0] + l.axes[1] + l.axes[2]);
        } else {  // an oriented box: origin and edge vectors
            std::printf("    origin   [%.6g, %.6g, %.6g]\n", l.origin.x, l.origin.y, l.origin.z);
            for (int a = 0; a < 3; ++a)
                std::printf("    axis %c   [%.6g, %.6g, %.6g]  (length %.6g)\n", "STU"[a],
                            l.axes[std::size_t(a)].x, l.axes[std::size_t(a)].y, l.axes[std::size_t(a)].z,
                            glm::length(l.axes[std::size_t(a)]));
        }
        print_transform(reg, e);
        print_clip(reg, e);
    });
    if (reg.count<Lattice>() == 0 && (reg.count<SplatCloud>() > 0 || reg.count<GaussianCloud>() > 0))
        std::printf(
            "  lattices none (add one: splatffd convert IN OUT.glb --lattice fit[:L,M,N], or shift+a in "
            "splatffd view)\n");
    reg.view<const Camera>().each([&](const Camera& c) {
        std::printf("  camera   eye [%.4g, %.4g, %.4g] target [%.4g, %.4g, %.4g] fov %.1f\n", c.eye.x,
                    c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z,
                    static_cast<double>(c.fov_y_degrees));
    });
    reg.view<const DirectionalLight>().each([&](const DirectionalLight& d) {
        std::printf("  light    directional [%.3g, %.3g, %.3g] intensity %.3g\n",
                    static_cast<double>(d.direction.x), static_cast<double>(d.direction.y),
                    static_cast<double>(d.direction.z), static_cast<double>(d.intensity));
    });
    reg.view<const AmbientLight>().each([&](const AmbientLight& a) {
        std::printf("  light    ambient intensity %.3g\n", static_cast<double>(a.intensity));
    });
    std::printf("  total    %zu splats\n", total);
    if (gaussians) std::printf("  total    %zu Gaussians\n", gaussians);
}

constexpr const char* kUsage =
    "usage: splatffd info FILE|sphere|face\n"
    "  FILE   .ply (point cloud, 3DGS or compressed Gaussians: header, counts, bounds), .obj .off (mesh or\n"
    "         points), .gltf .glb (scene: clouds, Gaussians, lattices with their transform and clip, "
    "camera,\n"
    "         lights; a deformed cloud's bounds at rest and deformed by its lattices as saved), .spz .splat "
    ".ksplat\n"
    "         .sog, a SOG folder's meta.json (Gaussians: count, SH degree, bounds), DIR/lod-meta.json (a\n"
    "         streamed SOG hierarchy: levels, Gaussians and units per level, tree nodes, bounds),\n"
    "         DIR/metadata.json (a Potree 2 octree: points, nodes, depth, chunks, points per level,\n"
    "         attributes)\n"
    "  sphere, face   the built-in scenes\n";

int run_info(cli::Args args) {
    for (const std::string& a : args)
        if (cli::is_help(a)) return cli::help(kUsage);
    if (args.size() != 1)
        return cli::usage_error("info", args.empty() ? "expected a FILE" : "expected one FILE", kUsage);
    const std::string file = args[0];
    std::string ext = std::filesystem::path(file).extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (std::filesystem::path(file).filename() == "lod-meta.json") return cli::info_lod(file);
    if (std::filesystem::path(file).filename() == "metadata.json") return cli::info_potree(file);
    if (ext == ".ply") return info_ply(file);
    if (ext == ".spz") return info_gaussians(file, "SPZ (Niantic)");
    if (ext == ".splat") return info_gaussians(file, ".splat (antimatter15)");
    if (ext == ".ksplat") return info_gaussians(file, ".ksplat (GaussianSplats3D)");
    if (ext == ".sog") return info_gaussians(file, "SOG (PlayCanvas)");
    std::error_code ec;
    if (std::filesystem::path(file).filename() == "meta.json" ||
        std::filesystem::is_regular_file(std::filesystem::path(file) / "meta.json", ec))
        return info_gaussians(file, "SOG folder (PlayCanvas)");
    if (ext != ".obj" && ext != ".off" && ext != ".gltf" && ext != ".glb" &&
        !assets::is_builtin_scene(file)) {
        std::fprintf(stderr,
                     "splatffd info: %s: unknown file type '%s' (expected .ply, .obj, .off, .gltf, .glb, "
                     ".spz, .splat, .ksplat, .sog or a SOG folder's meta.json)\n",
                     file.c_str(), ext.c_str());
        return 1;
    }
    if (assets::is_builtin_scene(file) || ext == ".gltf" || ext == ".glb") {
        ecs::Registry reg;
        sffd::use_engine_scene_hooks(reg);
        if (auto s = load_scene(reg, file); !s) {
            std::fprintf(stderr, "splatffd info: %s\n", s.message().c_str());
            return 1;
        }
        std::printf("%s: %s\n", file.c_str(),
                    assets::is_builtin_scene(file) ? "built-in scene" : "glTF scene");
        // The declaration is in the JSON: reading the whole file again doubled the command's time.
        if (!assets::is_builtin_scene(file) && gaussian::gltf_declaration(file).sffd_scene)
            std::printf("  SFFD_scene extension present\n");
        summarise_registry(reg);
        return 0;
    }
    auto g = assets::read_geometry(file);
    if (!g) {
        std::fprintf(stderr, "splatffd info: %s\n", g.message().c_str());
        return 1;
    }
    std::printf("%s: %zu points, %zu triangles, %zu materials, %zu textures\n", file.c_str(),
                g->positions.size(), g->triangle_count(), g->materials.size(), g->textures.size());
    std::string attrs;
    for (const auto& a : g->attributes) attrs += (attrs.empty() ? "" : ", ") + a;
    std::printf("  attributes %s\n", attrs.c_str());
    if (!g->positions.empty()) {
        glm::dvec3 lo(INFINITY), hi(-INFINITY);
        for (const auto& p : g->positions) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        print_bounds("  ", lo, hi);
    }
    return 0;
}

}  // namespace

SFFD_COMMAND(info, "print counts, bounds, attributes and lattices of a file or built-in scene", run_info);
