// Builds a Potree 2 octree of surface splats (potree2.h: DIR/metadata.json, hierarchy.bin, octree.bin)
// from splats streamed in chunks, in bounded memory (what `splatffd convert IN DIR/metadata.json` runs).
//
//   1. the source is read once for its count, bounds and which columns it has;
//   2. lod/cell_buckets.h sorts its splats into octree cells on disk (unlinked temporaries beside the
//      output, PotreeConverter's chunking), every cell at most as large as the budget allows;
//   3. each cell is built in memory as PotreeConverter's indexer builds a chunk: split into octants while
//      a node holds more than max_leaf splats (down to kMaxPotreeDepth), then bottom up each inner node
//      takes its representatives out of its children: one splat per occupied cell of a grid_cells³ grid
//      over the node (the one nearest the cell's centre; an inner child always keeps one splat, so no
//      node is empty). Leaves left empty are dropped. Then, bottom up over the final sets, each splat's
//      sffd_lod_radius R: its own radius, grown to max(|p - q| + R_p) over the children's splats p whose
//      nearest representative it is, so a node's splats cover every splat of its subtree. The cell's nodes
//      below its root go to octree.bin at once; the root (and its children's positions and radii) waits;
//   4. the octree above the cells is built from the waiting roots the same way (representatives bottom
//      up, then every waiting node's radii bottom up), and written;
//   5. hierarchy.bin (PotreeConverter's chunks of 4 levels), then metadata.json last (atomic).
// Memory: the records of one cell (at most the budget's share), the scatter buffers, and the waiting cell
// roots with their children's positions and radii (a surface: about grid_cells² · a few splats each),
// counted in a MemoryLedger.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "runtime/core/progress.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::assets {

// Splats in chunks; scan() may be called more than once and gives the same splats every time. Every
// chunk has normals and axes; colours, uvs and uv frames are in every chunk or in none.
struct SplatSource {
    std::string name;  // for messages
    SplatTexture texture;
    std::function<Status(const std::function<Status(const SplatCloud& chunk)>& sink)> scan;
};

// A cloud already in memory (its texture kept).
SplatSource cloud_splat_source(const SplatCloud& cloud, std::string name);
// `count` splats on a unit sphere (a Fibonacci spiral, outward normals, radii that close the surface, a
// colour gradient), made one chunk at a time: inputs larger than memory for tests and measurements.
SplatSource synthetic_splat_source(std::uint64_t count);
// A splat PLY as export.h writes it (x y z, nx ny nz, axis_u*, axis_v*, optional colour, u v and the uv
// frame) read through ply::Reader 65,536 rows at a time; anything else is refused (import it instead).
Result<SplatSource> ply_splat_source(const std::filesystem::path& path);

struct Potree2BuildOptions {
    std::uint64_t max_leaf = 16384;  // a node with more splats is split
    int grid_cells = 128;            // the subsampling grid per node and axis (Potree's spacing: size / 128)
    std::uint64_t memory_budget = std::uint64_t(1) << 30;
    std::filesystem::path temp_dir;  // default: the output's folder
    std::string name;                // metadata.json "name" (default: the folder's name)
    ProgressFn progress;
};

struct Potree2BuildStats {
    std::uint64_t points = 0;
    std::size_t nodes = 0, cells = 0, chunks = 0;
    int depth = 0;
    std::uint64_t peak_bytes = 0;  // the ledger's peak
    std::uint64_t cell_cap = 0;    // the most splats a cell held in memory
    std::uint64_t octree_bytes = 0, hierarchy_bytes = 0;
};

// `metadata` must be named metadata.json; its folder is created. Errors name the input or the file.
Result<Potree2BuildStats> build_potree2(const SplatSource& source, const std::filesystem::path& metadata,
                                        const Potree2BuildOptions& options = {});

}  // namespace sffd::assets
