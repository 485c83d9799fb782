#include "tools/splatffd/convert_lod.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <string>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/formats/surface/ply.h"
#include "systems/gaussian/gaussian_read.h"
#include "tools/splatffd/convert_gaussians.h"
#include "tools/splatffd/progress.h"

namespace sffd::cli {
namespace fs = std::filesystem;

namespace {

constexpr const char* kUsage =
    "usage: splatffd convert IN DIR/lod-meta.json [--lod-levels N] [--lod-ratio R] [--lod-chunk-count K]\n"
    "                        [--lod-chunk-extent E] [--lod-chunk-min K] [--lod-memory MB] [--progress]\n"
    "  Builds a Gaussian level-of-detail hierarchy as PlayCanvas streamed SOG: DIR/lod-meta.json (the tree,\n"
    "  its bounds and every node's runs) and one SOG folder per unit (DIR/L_i/meta.json). Level 0 is IN's\n"
    "  Gaussians; level l + 1 merges groups of up to R level-l Gaussians (hierarchical 3DGS moments).\n"
    "  IN  a 3DGS .ply (streamed: any size), any other Gaussian file convert reads (.compressed.ply .splat\n"
    "      .spz .ksplat .sog, a SOG folder's meta.json, KHR .glb, a lod-meta.json: read whole), or\n"
    "      synthetic-gaussians:N[:shD] (N procedural Gaussians on a sphere of radius 10, made a chunk at a\n"
    "      time, SH degree D; N takes k and m suffixes: 1m)\n"
    "  --lod-levels N        levels, the finest included (1..32, default 4)\n"
    "  --lod-ratio R         Gaussians merged into one per level up (2..64, default 4)\n"
    "  --lod-chunk-count K   a leaf (chunk) holds at most about K x 1024 Gaussians, and a unit file is\n"
    "                        closed past that many (splat-transform's option; default 512)\n"
    "  --lod-chunk-extent E  a leaf wider than E (file units) is split while it holds more than the chunk\n"
    "                        minimum (default 16)\n"
    "  --lod-chunk-min K     the chunk minimum: K x 1024 Gaussians (splat-transform's option; default 8)\n"
    "  --lod-memory MB       memory budget of the build: cells are bucketed on disk (unlinked temporaries\n"
    "                        in DIR) until each fits (64..1048576, default 1024); the SOG encoder's own\n"
    "                        work space while it writes a unit comes on top (about 200 bytes a Gaussian)\n"
    "  --progress            a line per step at its start, every 10 % and its end (default: only when\n"
    "                        stderr is a terminal); the summary is always printed\n";

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

// IN as a source of Gaussians in chunks. `whole` keeps a cloud read at once alive for the source.
Result<lod::GaussianSource> open_source(const std::string& in, std::optional<GaussianCloud>& whole) {
    constexpr std::string_view kSynthetic = "synthetic-gaussians:";
    if (in.rfind(kSynthetic, 0) == 0) {
        std::string spec = in.substr(kSynthetic.size());
        int degree = 0;
        if (const auto colon = spec.find(':'); colon != std::string::npos) {
            const std::string sh = spec.substr(colon + 1);
            if (sh.size() != 3 || sh.rfind("sh", 0) != 0 || sh[2] < '0' || sh[2] > '3')
                return make_error(in + ": the SH suffix is :sh0 .. :sh3");
            degree = sh[2] - '0';
            spec.resize(colon);
        }
        std::uint64_t n = 0;
        if (!parse_count(spec, n))
            return make_error(in + ": expected synthetic-gaussians:N with N a count (1m, 250k, 5000)");
        return lod::synthetic_gaussian_source(n, degree);
    }
    if (assets::is_builtin_scene(in))
        return make_error(
            in +
            ": a built-in scene of surface splats, not a Gaussian file (a hierarchy is built of "
            "3D Gaussians; first: splatffd convert " +
            in + " g.ply --gaussians)");
    std::error_code ec;
    if (!fs::exists(in, ec)) return make_error(in + ": no such file");
    std::string ext = fs::path(in).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".ply") {
        // A 3DGS PLY streams through ply::Reader; a compressed PLY is read whole below.
        auto r = ply::Reader::open(in);
        if (!r) return r.error();
        const int v = r->header().find("vertex");
        if (v >= 0 && gaussian::is_gaussian_element(r->header().elements[std::size_t(v)]))
            return lod::ply_gaussian_source(in);
    }
    if (!is_gaussian_file(in))
        return make_error(in +
                          ": not a Gaussian file (a hierarchy is built of 3D Gaussians; surface splats "
                          "first: splatffd convert IN g.ply --gaussians)");
    auto g = gaussian::read_gaussians(in);
    if (!g) return g.error();
    whole = std::move(*g);
    return lod::cloud_gaussian_source(*whole, in);
}

std::string counts_text(const std::vector<std::uint64_t>& counts) {
    std::string t;
    for (const std::uint64_t c : counts) t += (t.empty() ? "" : ", ") + std::to_string(c);
    return t;
}

}  // namespace

bool names_lod_output(Args args) {
    bool seen_in = false;
    for (const std::string& a : args) {
        if (a.empty() || a[0] == '-') continue;
        if (seen_in && fs::path(a).filename() == "lod-meta.json") return true;
        seen_in = true;
    }
    return false;
}

int run_convert_lod(Args args) {
    std::string in, out;
    lod::LodBuildOptions o;
    bool progress = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto next = [&]() -> std::optional<std::string> {
            if (i + 1 >= args.size()) {
                std::fprintf(stderr, "splatffd convert: %s needs a value\n", a.c_str());
                return std::nullopt;
            }
            return args[++i];
        };
        auto integer = [&](long long min, long long max) -> std::optional<long long> {
            auto t = next();
            if (!t) return std::nullopt;
            auto v = parse_integer(a, *t, min, max);
            if (!v) std::fprintf(stderr, "splatffd convert: %s\n", v.message().c_str());
            return v ? std::optional<long long>(*v) : std::nullopt;
        };
        if (is_help(a)) return help(kUsage);
        if (a == "--lod-levels") {
            auto v = integer(1, lod::kMaxLodLevels);
            if (!v) return 2;
            o.levels = int(*v);
        } else if (a == "--lod-ratio") {
            auto v = integer(2, 64);
            if (!v) return 2;
            o.ratio = int(*v);
        } else if (a == "--lod-chunk-count") {
            auto v = integer(1, 16384);
            if (!v) return 2;
            o.chunk_count = std::uint64_t(*v) * 1024;
        } else if (a == "--lod-chunk-extent") {
            auto t = next();
            if (!t) return 2;
            auto v = parse_number(a, *t, 1e-6, 1e12);
            if (!v) return usage_error("convert", v.message(), "");
            o.chunk_extent = *v;
        } else if (a == "--lod-chunk-min") {
            auto v = integer(0, 16384);
            if (!v) return 2;
            o.chunk_min = std::uint64_t(*v) * 1024;
        } else if (a == "--lod-memory") {
            auto v = integer(64, 1 << 20);
            if (!v) return 2;
            o.memory_budget = std::uint64_t(*v) << 20;
        } else if (a == "--progress") {
            progress = true;
        } else if (!a.empty() && a[0] == '-') {
            return usage_error(
                "convert",
                "'" + a +
                    "' does not apply to a lod-meta.json output (its options: --lod-levels, "
                    "--lod-ratio, --lod-chunk-count, --lod-chunk-extent, --lod-chunk-min, --lod-memory, "
                    "--progress)",
                kUsage);
        } else if (in.empty()) {
            in = a;
        } else if (out.empty()) {
            out = a;
        } else {
            return usage_error("convert", "more than two files given ('" + a + "')", kUsage);
        }
    }
    if (in.empty() || out.empty()) return usage_error("convert", "expected IN and DIR/lod-meta.json", kUsage);
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<GaussianCloud> whole;
    auto source = open_source(in, whole);
    if (!source) return command_error("convert", source.message());
    // A hierarchy already there is replaced: its units that the new one does not name are removed after
    // the new lod-meta.json is written (only the files its manifest lists, inside the folder).
    std::error_code ec;
    auto before =
        fs::exists(out, ec) ? lod::open_streamed_sog(out) : Result<lod::StreamedSog>(make_error(""));
    ProgressPrinter printer("convert", ProgressPrinter::mode_for(progress));
    o.progress = printer.fn();
    auto stats = lod::build_streamed_sog(*source, out, o);
    if (!stats) return command_error("convert", stats.message());
    printer.summary();
    if (before) {
        auto now = lod::open_streamed_sog(out);
        std::set<fs::path> kept;
        if (now)
            for (const lod::LodUnit& u : now->units) kept.insert(u.path.lexically_normal());
        std::size_t removed = 0;
        for (const lod::LodUnit& u : before->units) {
            if (!now || kept.count(u.path.lexically_normal())) continue;
            for (const lod::LodPart& p : u.parts) fs::remove(p.path, ec);
            fs::remove(u.path.parent_path(), ec);  // only when empty
            ++removed;
        }
        if (removed > 0)
            std::fprintf(stderr, "removed %zu units of the hierarchy %s held before\n", removed, out.c_str());
    }
    std::uint64_t total = 0;
    for (const std::uint64_t c : stats->counts) total += c;
    std::fprintf(stderr,
                 "wrote %s: %llu Gaussians in %d levels (%s), %zu units, %zu chunks, %zu cells, chunk count "
                 "%llu, build memory peak %.1f MB of %.1f MB (%.2f s)\n",
                 out.c_str(), static_cast<unsigned long long>(total), o.levels,
                 counts_text(stats->counts).c_str(), stats->units, stats->chunks, stats->cells,
                 static_cast<unsigned long long>(stats->chunk_count), double(stats->peak_bytes) / 1e6,
                 double(o.memory_budget) / 1e6,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

int info_lod(const std::string& file) {
    auto s = lod::open_streamed_sog(file);
    if (!s) return command_error("info", s.message());
    std::printf("%s: %s", file.c_str(), lod::describe(*s).c_str());
    return 0;
}

}  // namespace sffd::cli
