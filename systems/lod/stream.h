// Streaming a level-of-detail hierarchy: what view, render and profile draw of a streamed SOG
// (lod-meta.json, runtime/assets/formats/lod/streamed_sog.h) or a Potree 2 octree of our surface splats
// (metadata.json, runtime/assets/formats/surface/potree2.h) without reading it whole.
//
// Every frame (update) the stream
//   1. chooses the cut for the camera, under the splat budget, by projected screen-space error (cut.h),
//      each node's box taken through the lattices conservatively (lattice_bounds.h) whenever they moved,
//      so the error is measured on the deformed shape;
//   2. asks its loader thread for the pieces of the cut it does not hold, largest projected size first,
//      while what it holds fits the memory budget: pieces neither wanted nor drawn are dropped, least
//      recently used first, to make room; a piece that still does not fit is not asked for
//      (memory_limited), so the budget holds whatever the splat budget says;
//   3. takes the pieces the loader finished. The frame never waits on the disk.
// What is drawn (assemble) is the cut as far as it is loaded:
//   - streamed SOG: a piece is one leaf at one level, and every level of a leaf covers the same region, so
//     a leaf whose wanted level is not loaded yet is drawn at the nearest loaded level (coarser first),
//     and left out only while none is loaded;
//   - Potree 2 is additive (a node's points add to its parent's): a wanted node is drawn when it and every
//     ancestor are loaded, and a drawn node without all of its children drawn has its splats grown to their
//     sffd_lod_radius (they stand for the points below, as read_potree2_nodes draws a cut).
// The drawn set is one cloud: Gaussians are sorted once over the whole cut, and deformation, picking and
// the editor see an ordinary cloud. Pieces are shifted to one origin (the root box's centre for SOG, the
// octree's own for Potree) when they are loaded, so the cloud's frame never moves.
//
// A still camera and lattice keep asking for the same cut, so the drawn set refines to it as pieces arrive
// and then stops changing (complete). wait_complete() blocks until then: final renders draw exactly the
// cut of their camera and lattice, the same whoever renders frame k, provided the cut fits the memory
// budget (wait_complete refuses one that does not, naming both).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"
#include "systems/ffd/lattice.h"
#include "systems/lod/cut.h"

namespace sffd::lod {

struct StreamOptions {
    std::uint64_t splat_budget = 2'000'000;                // splats the cut may draw
    std::uint64_t memory_budget = std::uint64_t(1) << 30;  // bytes of pieces held (and being decoded)
    double tau_pixels = 1.0;                               // refine while a node projects larger
    bool cull = true;                                      // nodes outside the view stay coarse
    // While lattices keep moving (a drag, a clip), node bounds are taken through them again at most this
    // often, and the cut in between is chosen on the last bounds (bounding a node through an 11^3
    // lattice costs about a millisecond); the first update after the motion stops bounds them again.
    // 0: every update (final renders).
    double rebound_interval_s = 0.25;
};

struct StreamStats {
    std::uint64_t resident_bytes = 0, peak_resident_bytes = 0;  // pieces held, plus the loader's scratch
    std::size_t resident_pieces = 0, queued = 0;
    std::uint64_t loads = 0, evictions = 0;
    std::size_t cut_nodes = 0, wanted_pieces = 0, missing_pieces = 0;  // missing: wanted, not held
    std::uint64_t wanted_splats = 0, drawn_splats = 0;
    bool budget_limited = false;  // the cut stopped refining at the splat budget
    bool memory_limited = false;  // a wanted piece was not asked for: the memory budget is full
    double select_ms = 0.0;       // the last update's cut selection (with the bounds it recomputed)
};

// A lod-meta.json, or a Potree 2 metadata.json whose points carry our splat attributes.
bool is_streamable(const std::filesystem::path& path);

class HierarchyStream {
public:
    // Opens and validates the hierarchy (reading no points) and starts the loader thread.
    static Result<std::unique_ptr<HierarchyStream>> open(const std::filesystem::path& path,
                                                         const StreamOptions& options = {});
    ~HierarchyStream();  // stops the loader (after the piece it is decoding)
    HierarchyStream(const HierarchyStream&) = delete;
    HierarchyStream& operator=(const HierarchyStream&) = delete;

    bool gaussians() const;  // SOG: assemble a GaussianCloud; Potree: a SplatCloud
    const std::filesystem::path& path() const;
    std::uint64_t full_detail() const;  // splats of the finest cut
    ffd::Box bounds() const;            // the root's box, in the cloud's frame
    glm::dvec3 origin() const;          // the assembled clouds' origin
    const StreamOptions& options() const;
    void set_options(const StreamOptions& options);

    // One frame (above). `lattices` are in the cloud's frame (ffd::cloud_lattices); `lattice_stamp` must
    // change whenever one of them (or their order) changed: the node bounds are recomputed only then.
    // `weighted`: the cloud has per-point weights (lattice_bounds.h). True when the drawn set changed
    // since the last assemble.
    bool update(const CutView& view, std::span<const Lattice* const> lattices = {},
                std::uint64_t lattice_stamp = 0, bool weighted = false);
    // The drawn set (above) as one cloud of the stream's kind; the other kind's is left empty.
    void assemble(GaussianCloud& out);
    void assemble(SplatCloud& out);
    // Every piece of the last cut is held and drawn.
    bool complete() const;
    // Blocks until complete (taking finished loads as they come), or refuses: a load failed (the file and
    // its problem), or the cut does not fit the memory budget.
    Status wait_complete();
    StreamStats stats() const;
    // The first load that failed ("path: problem"); a failed piece is not asked for again.
    Status error() const;

    struct Impl;

private:
    explicit HierarchyStream(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sffd::lod
