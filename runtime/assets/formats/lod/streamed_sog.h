// PlayCanvas streamed SOG: a Gaussian level-of-detail hierarchy as splat-transform writes it for an output
// named `lod-meta.json` (src/lib/writers/write-lod.ts), read and checked here; written by lod_build.h.
//
//   DIR/lod-meta.json  {"version": 1, "asset": {"generator": ...}, "count": N, "counts": [n_0 .. n_{L-1}],
//                       "lodLevels": L, "environment": "env/meta.json" (optional),
//                       "filenames": ["0_0/meta.json", "1_0/meta.json", ...], "tree": NODE}
//   NODE               {"bound": {"min": [3], "max": [3]}, "children": [NODE, ...]}          (interior)
//                      {"bound": ..., "lods": {"0": {"file": f, "offset": o, "count": c}, ...}}  (leaf)
//   DIR/L_i/meta.json  one SOG folder (gaussian_sog.h) per file unit: the Gaussians of level L of
//                      consecutive leaves, leaf after leaf, each leaf's run at "offset" (Morton-ordered
//                      within the run); a unit is closed once it holds more than the chunk count.
// Level 0 is full detail; level l + 1 is coarser. Every leaf covers the same region at every level it
// lists. Bounds are the boxes of the Gaussians' 1σ ellipsoids (all levels), in the files' space (stored
// as read, like SOG and 3DGS PLY).
//
// One validation on open, before any image is decoded, every refusal "path: problem" naming the file:
//   lod-meta.json: a regular file of at most kMaxLodMetaBytes, JSON nesting within kMaxJsonDepth; version 1
//   (or absent: manifests older than the version stamp); lodLevels 1..kMaxLodLevels; counts (optional)
//   one whole number per level, count (optional) their sum; at most kMaxLodFiles filenames and
//   kMaxLodNodes nodes; every bound 3 + 3 finite numbers with min <= max; every reference a level below
//   lodLevels, a file in the list, whole offset and count. Folder confinement: each filename (and the
//   environment) is a relative path to a SOG folder's meta.json or a .sog archive that resolves inside
//   DIR (resolve_resource: no absolute path, no "..", no symlink out); no file named twice.
//   Each unit's meta.json (at most kMaxUnitMetaBytes): its "count" (at most kMaxGaussians) and its image
//   names (plain names of regular files beside it, inside DIR after symlinks like the units, whose sizes
//   are recorded); a unit used by one level
//   only; its runs tile [0, count) exactly (no gap, no overlap, nothing past the end); per level the
//   runs add up to counts[level]; and the ratio budget: a unit declares at most kMaxTexelsPerByte
//   Gaussians per byte of its images (a real capture's images are noise-like; a few bytes claiming
//   millions of texels would only make the decoder allocate).
// Decoding a unit goes through read_sog (its own checks), and its count must equal the declared one.
//
// Streaming: a loader thread takes one node at a time: node_parts() names the files (with their byte
// sizes) that hold a node's level, read_unit() decodes one unit, slice() cuts a node's run out of it.
// WebP cannot be decoded in parts, so a unit is the smallest thing read; splat-transform keeps units at
// about the chunk count (512K Gaussians by default).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::lod {

inline constexpr std::uint64_t kMaxLodMetaBytes = std::uint64_t(256) << 20;
inline constexpr std::uint64_t kMaxUnitMetaBytes = std::uint64_t(16) << 20;
inline constexpr int kMaxLodLevels = 32;
inline constexpr std::size_t kMaxLodFiles = std::size_t(1) << 20;
inline constexpr std::size_t kMaxLodNodes = std::size_t(1) << 24;
inline constexpr std::uint64_t kMaxTexelsPerByte = 4096;

struct LodRun {
    std::uint32_t file = 0;
    std::uint64_t offset = 0, count = 0;
};

struct LodNode {
    glm::dvec3 lo{0.0}, hi{0.0};
    std::int32_t parent = -1;
    std::vector<std::uint32_t> children;
    std::vector<std::optional<LodRun>> lods;  // per level (size lodLevels); empty optional: not listed
};

struct LodPart {
    std::filesystem::path path;
    std::uint64_t bytes = 0;
};

struct LodUnit {
    std::string name;            // as listed in lod-meta.json
    std::filesystem::path path;  // resolved inside the folder
    int level = -1;              // the one level whose runs it holds (-1: listed but unused)
    std::uint64_t count = 0;     // its meta.json's "count"
    std::vector<LodPart> parts;  // meta.json (or the .sog archive) first, then its images
};

struct StreamedSog {
    std::filesystem::path path;  // lod-meta.json
    int version = 0;             // 0: no "version" field
    std::string generator;
    int levels = 0;
    std::vector<std::uint64_t> counts;  // per level
    std::vector<LodUnit> units;
    std::vector<LodNode> nodes;  // depth first, the root at 0, children after their parent
    std::optional<std::filesystem::path> environment;
    std::uint64_t total() const;
};

// Reads lod-meta.json and every unit's meta.json, and validates the whole hierarchy (above).
Result<StreamedSog> open_streamed_sog(const std::filesystem::path& lod_meta);

// The files a loader must fetch for node `node` at `level` (empty: the node lists no such level).
std::vector<LodPart> node_parts(const StreamedSog& s, std::uint32_t node, int level);
// One unit decoded (read_sog), its count checked against the declared one.
Result<GaussianCloud> read_unit(const StreamedSog& s, std::uint32_t unit);
// Gaussians [run.offset, run.offset + run.count) of a decoded unit (origin kept).
GaussianCloud slice(const GaussianCloud& unit, const LodRun& run);
// Every leaf's Gaussians at `level`, in tree order (depth first), as one cloud; level 0 is the full
// detail. Refused when the level holds more than kMaxGaussians.
Result<GaussianCloud> read_level(const StreamedSog& s, int level);

// A human-readable summary (levels, counts, units, nodes, depth, bounds), one fact a line.
std::string describe(const StreamedSog& s);

}  // namespace sffd::lod
