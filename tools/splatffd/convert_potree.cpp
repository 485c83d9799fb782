#include "tools/splatffd/convert_potree.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "systems/engine/engine_frame.h"
#include "tools/splatffd/progress.h"

namespace sffd::cli {
namespace fs = std::filesystem;

namespace {

constexpr const char* kUsage =
    "usage: splatffd convert IN DIR/metadata.json [--potree-leaf N] [--potree-grid G] [--potree-memory MB]\n"
    "                        [--progress]\n"
    "  Builds a Potree 2 octree of surface splats (PotreeConverter 2's layout: DIR/metadata.json,\n"
    "  hierarchy.bin, octree.bin; Potree opens it): every splat in exactly one node, an inner node holding\n"
    "  one representative per occupied cell of a G^3 grid over it, its radius grown to cover what it stands\n"
    "  for (the sffd_lod_radius attribute; runtime/assets/README.md, \"Potree 2\").\n"
    "  IN  any surface input convert reads (.ply .obj .off .gltf .glb, a built-in scene, a scene file: its\n"
    "      one surface cloud at rest, without its lattices; read whole),\n"
    "      a splat .ply as convert writes it (streamed: any size), or synthetic:N (N splats on a\n"
    "      unit sphere, made a chunk at a time; N takes k and m suffixes: 10m)\n"
    "  --potree-leaf N     a node with more than N splats is split (64..4194304, default 16384)\n"
    "  --potree-grid G     the subsampling grid per node and axis (2..1024, default 128: Potree's spacing)\n"
    "  --potree-memory MB  memory budget of the build: cells are bucketed on disk (unlinked temporaries in\n"
    "                      DIR) until each fits (64..1048576, default 1024)\n"
    "  --progress          a line per step at its start, every 10 % and its end (default: only when\n"
    "                      stderr is a terminal); the summary is always printed\n";

bool parse_count(std::string s, std::uint64_t& out) {
    double mult = 1.0;
    if (!s.empty() && (s.back() == 'k' || s.back() == 'K')) mult = 1e3, s.pop_back();
    else if (!s.empty() && (s.back() == 'm' || s.back() == 'M')) mult = 1e6, s.pop_back();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !(v >= 1) || v * mult > 1e12) return false;
    out = std::uint64_t(v * mult + 0.5);
    return true;
}

// A splat PLY that streams: our own layout (normals and axes) and no texture to carry.
bool streams(const std::string& in) {
    std::string ext = fs::path(in).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".ply") return false;
    auto r = ply::Reader::open(in);
    if (!r) return false;
    const int v = r->header().find("vertex");
    if (v < 0) return false;
    const ply::Element& e = r->header().elements[std::size_t(v)];
    for (const std::string& c : r->header().comments)
        if (c.rfind("TextureFile ", 0) == 0) return false;
    return e.find("axis_ux") >= 0 && e.find("nx") >= 0 && !e.has_lists();
}

// IN as a source of splats. `whole` keeps a cloud read at once alive for the source.
Result<assets::SplatSource> open_source(const std::string& in, std::optional<SplatCloud>& whole) {
    constexpr std::string_view kSynthetic = "synthetic:";
    if (in.rfind(kSynthetic, 0) == 0) {
        std::uint64_t n = 0;
        if (!parse_count(in.substr(kSynthetic.size()), n))
            return make_error(in + ": expected synthetic:N with N a count (1m, 250k, 5000)");
        return assets::synthetic_splat_source(n);
    }
    if (streams(in)) return assets::ply_splat_source(in);
    // Everything else as render loads it: the one surface cloud of the scene (rest pose).
    ecs::Registry r;
    use_engine_scene_hooks(r);
    if (Status s = load_scene(r, in); !s) return s.error();
    std::size_t clouds = 0;
    r.each_entity([&](ecs::Entity e) {
        if (const SplatCloud* c = r.try_get<SplatCloud>(e)) {
            if (!whole) whole = *c;
            ++clouds;
        }
    });
    if (clouds == 0) return make_error(in + ": no surface splats (a Potree octree holds surface splats)");
    if (clouds > 1)
        return make_error(in + ": " + std::to_string(clouds) + " surface clouds; an octree holds one");
    return assets::cloud_splat_source(*whole, in);
}

}  // namespace

bool names_potree_output(Args args) {
    bool seen_in = false;
    for (const std::string& a : args) {
        if (a.empty() || a[0] == '-') continue;
        if (seen_in && fs::path(a).filename() == "metadata.json") return true;
        seen_in = true;
    }
    return false;
}

int run_convert_potree(Args args) {
    std::string in, out;
    assets::Potree2BuildOptions o;
    bool progress = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto integer = [&](long long min, long long max) -> std::optional<long long> {
            if (i + 1 >= args.size()) {
                std::fprintf(stderr, "splatffd convert: %s needs a value\n", a.c_str());
                return std::nullopt;
            }
            auto v = parse_integer(a, args[++i], min, max);
            if (!v) std::fprintf(stderr, "splatffd convert: %s\n", v.message().c_str());
            return v ? std::optional<long long>(*v) : std::nullopt;
        };
        if (is_help(a)) return help(kUsage);
        if (a == "--potree-leaf") {
            auto v = integer(64, 1 << 22);
            if (!v) return 2;
            o.max_leaf = std::uint64_t(*v);
        } else if (a == "--potree-grid") {
            auto v = integer(2, 1024);
            if (!v) return 2;
            o.grid_cells = int(*v);
        } else if (a == "--potree-memory") {
            auto v = integer(64, 1 << 20);
            if (!v) return 2;
            o.memory_budget = std::uint64_t(*v) << 20;
        } else if (a == "--progress") {
            progress = true;
        } else if (!a.empty() && a[0] == '-') {
            return usage_error("convert",
                               "'" + a +
                                   "' does not apply to a metadata.json output (its options: --potree-leaf, "
                                   "--potree-grid, --potree-memory, --progress)",
                               kUsage);
        } else if (in.empty()) {
            in = a;
        } else if (out.empty()) {
            out = a;
        } else {
            return usage_error("convert", "more than two files given ('" + a + "')", kUsage);
        }
    }
    if (in.empty() || out.empty()) return usage_error("convert", "expected IN and DIR/metadata.json", kUsage);
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<SplatCloud> whole;
    auto source = open_source(in, whole);
    if (!source) return command_error("convert", source.message());
    ProgressPrinter printer("convert", ProgressPrinter::mode_for(progress));
    o.progress = printer.fn();
    auto stats = assets::build_potree2(*source, out, o);
    if (!stats) return command_error("convert", stats.message());
    printer.summary();
    std::fprintf(
        stderr,
        "wrote %s: %llu splats in %zu nodes, depth %d, %zu hierarchy chunks, %zu cells (largest %llu), "
        "octree.bin %.1f MB, build memory peak %.1f MB of %.1f MB (%.2f s)\n",
        out.c_str(), static_cast<unsigned long long>(stats->points), stats->nodes, stats->depth,
        stats->chunks, stats->cells, static_cast<unsigned long long>(stats->cell_cap),
        double(stats->octree_bytes) / 1e6, double(stats->peak_bytes) / 1e6, double(o.memory_budget) / 1e6,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

int info_potree(const std::string& file) {
    auto o = assets::open_potree2(file);
    if (!o) return command_error("info", o.message());
    std::printf("%s: %s", file.c_str(), assets::describe(*o).c_str());
    return 0;
}

}  // namespace sffd::cli
