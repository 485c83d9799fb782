// Builds a streamed SOG (streamed_sog.h: DIR/lod-meta.json and its SOG units) from Gaussians streamed in
// chunks, in bounded memory (what `splatffd convert IN DIR/lod-meta.json` runs).
//
//   1. the source is read once for its count, bounds and SH degree;
//   2. cell_buckets.h sorts its Gaussians into octree cells on disk (unlinked temporaries beside the
//      output), every cell at most as large as the budget allows;
//   3. each cell is built in memory: split as splat-transform splits its tree (the median of the
//      centres along the box's longest side, while a node holds more than chunk_count Gaussians or is
//      wider than chunk_extent and holds more than chunk_min, buckets of 256 never split), each leaf
//      ("chunk") gets its levels:
//      level 0 its own Gaussians, level l + 1 the merges (lod_merge.h) of groups of at most `ratio`
//      level-l Gaussians, the groups split at the median of the longest side as well;
//   4. each level's runs go to that level's current unit ("L_i/meta.json", Morton-ordered per run as
//      splat-transform orders them), written once it holds more than chunk_count Gaussians;
//   5. lod-meta.json last (atomic), its numbers at 7 significant digits as splat-transform writes them.
// The tree above the cells is the octree of the cells, each octree node split into halves along x,
// then y, then z (a binary tree like splat-transform's; one-child nodes collapse).
//
// Memory: the builder counts what it holds (records, cells, chunks and their levels, the open units,
// the scatter buffers) in a MemoryLedger and sizes cells so the count stays below memory_budget; the
// SOG encoder's own work space while it writes a unit (about 200 bytes a Gaussian) is outside it.
// A budget below one input chunk (65,536 Gaussians as records and a cloud, 8 MB at SH degree 0) is
// exceeded by that chunk.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "runtime/core/progress.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::lod {

// Gaussians in chunks; scan() may be called more than once and gives the same Gaussians every time.
struct GaussianSource {
    std::string name;  // for messages
    std::function<Status(const std::function<Status(const GaussianCloud& chunk)>& sink)> scan;
};

// A 3DGS PLY read through ply::Reader 65,536 rows at a time (the files' own space: nothing is turned).
Result<GaussianSource> ply_gaussian_source(const std::filesystem::path& path);
// `count` procedural Gaussians (a sphere of radius 10 with a ripple, SH degree `sh_degree`), made one chunk
// at a time: for tests and measurements of inputs larger than memory.
GaussianSource synthetic_gaussian_source(std::uint64_t count, int sh_degree = 0);
// A cloud already in memory.
GaussianSource cloud_gaussian_source(const GaussianCloud& cloud, std::string name);

struct LodBuildOptions {
    int levels = 4;                          // 1..kMaxLodLevels
    int ratio = 4;                           // level l + 1 merges groups of up to this many (>= 2)
    std::uint64_t chunk_count = 512 * 1024;  // splat-transform's --lod-chunk-count (K) · 1024
    double chunk_extent = 16.0;              // splat-transform's --lod-chunk-extent
    std::uint64_t chunk_min = 8 * 1024;      // splat-transform's --lod-chunk-min (K) · 1024
    std::uint64_t memory_budget = std::uint64_t(1) << 30;
    std::filesystem::path temp_dir;  // default: the output's folder
    ProgressFn progress;
};

struct LodBuildStats {
    std::vector<std::uint64_t> counts;  // per level
    std::size_t units = 0, chunks = 0, cells = 0;
    std::uint64_t peak_bytes = 0;   // the ledger's peak
    std::uint64_t cell_cap = 0;     // the most Gaussians a cell held in memory
    std::uint64_t chunk_count = 0;  // the chunk count used (chunk_count, or less to fit the budget)
};

// `lod_meta` must be named lod-meta.json; its folder is created. Errors name the input or the file.
Result<LodBuildStats> build_streamed_sog(const GaussianSource& source, const std::filesystem::path& lod_meta,
                                         const LodBuildOptions& options = {});

// Sorts `indices` along the Morton curve of the positions as splat-transform's sortMortonColumns does
// (10 bits per axis over the indices' own box, runs of more than 256 equal codes sorted again inside
// their own box).
void sort_morton(const std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices);

}  // namespace sffd::lod
