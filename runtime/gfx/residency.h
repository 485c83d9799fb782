// GPU residency of a point cloud, shared by both kinds (surface splats: gfx::GpuSplats in splat_store.h;
// 3D Gaussians: gaussian::GpuGaussians in systems/gaussian/gpu_store.h). One state per cloud, one writer
// per transition:
//   rest          residency_system (phase `residency`) uploaded the authored cloud into `rest` when its
//                 change stamp moved, or the cloud has no deformers: draw `rest`;
//   deformed_gpu  a deformation system's compute pass wrote `deformed` (no CPU copy exists);
//   deformed_cpu  a deformation system's CPU path wrote its output and uploaded it into `deformed`;
//   preview_cpu   a deformation system's CPU path deformed only a budgeted preview subset of the cloud
//                 (systems/ffd/preview_budget.h) and uploaded it into `deformed`: `preview_count`
//                 elements, enlarged; drawn only by preview frames, replaced by the next full output.
// Render and picking only read: draw_buffer() and `deformed_version` (bumped on every rewrite of
// `deformed`, so caches of the deformed data key on it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/gfx/gl_object.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"

namespace sffd::gfx {

enum class Residency : std::uint8_t { rest, deformed_gpu, deformed_cpu, preview_cpu };

// The part of a resident cloud that does not depend on its kind (the kinds derive from it and add the
// buffers their data needs).
struct ResidentCloud {
    Buffer rest;                     // authored data, in the kind's GPU layout
    Buffer deformed;                 // written by the deformation (GPU pass or uploaded CPU output)
    std::uint32_t count = 0;         // elements in `rest` (and in `deformed` when it is valid)
    std::uint64_t rest_version = 0;  // change stamp of the authored component that `rest` holds
    Residency state = Residency::rest;
    std::uint64_t deformed_version = 0;  // bumped whenever `deformed` is rewritten
    std::uint32_t preview_count = 0;     // elements in `deformed` in state preview_cpu
    // The cloud's per-point weights (PointWeights, float[count]) for the compute deformations, only while it
    // has some: uploaded and released by the deformation systems (ffd::resident_weights(), systems/ffd/
    // ffd_gpu.h), `weights_key` the stamps they are of. A cloud without weights has no buffer here.
    Buffer weights;
    std::uint64_t weights_key = 0;
    // The compute deformations' counters, per page of the cloud (shaders/ffd/page_stats.glsl; made by
    // ffd::resident_page_stats()): a page-wise redo adds only into its pages', so the sum stays the cloud's.
    Buffer page_stats;
    std::size_t page_stats_words = 0;
    // The cloud's per-point marks for drawing (point_marks.h: flags and weight, 16 bits a point), only
    // while it has PointFlags or PointWeights: written by residency_system alone (sync_point_marks), page
    // by page. `marks_state` says what they hold.
    Buffer marks;
    struct MarksState {
        std::uint64_t flags_version = 0, weights_version = 0;  // the columns' stamps the marks hold (0: none)
        std::uint64_t clock = 0;                               // PointPages::clock as of the last upload
        std::uint64_t rest_version = 0;                        // the rest upload they were made beside
        std::uint32_t count = 0;
        bool flags = false, weights = false;
        std::vector<std::uint32_t> page_selected;  // per page: points selected and not gone
        std::vector<std::uint32_t> page_gone;      // per page: points hidden or deleted
        bool any_selected() const;
        bool any_gone() const;
    } marks_state;
    // In state preview_cpu: the authored index of each drawn element (preview_count of them), set by the
    // preview uploads; on the GPU (`preview_index`, uint[]) only while the cloud has marks, uploaded by
    // sync_preview_index() once per preview (the draw passes read a subset's marks through it).
    std::vector<std::uint32_t> preview_indices;
    Buffer preview_index;
    std::uint64_t preview_index_key = 0;  // deformed_version + 1 of the subset `preview_index` holds

    bool is_deformed() const { return state != Residency::rest; }
    // Elements of draw_buffer(): a preview subset holds fewer than the cloud.
    std::uint32_t drawn_count() const { return state == Residency::preview_cpu ? preview_count : count; }
    GLuint draw_buffer() const { return is_deformed() ? deformed.id() : rest.id(); }
};

// Allocates `b` (labelled) at `bytes` (at least 16: GL needs a store to bind) when it is missing or of
// another size, then uploads `data` (none when null). The one upload primitive both kinds use.
void fill_buffer(Buffer& b, const char* label, const void* data, std::size_t bytes);

// Allocates `b` as fill_buffer() does and lets `write(void* dst)` fill its `bytes` in place, through a
// mapping: the data is packed straight into the buffer, so no CPU-side copy of it exists beside the
// buffer, not even for the time of the upload (on a software rasterizer GL buffers are host memory).
// A mapping the implementation reports lost (glUnmapNamedBuffer false) is written again.
void* map_for_fill(Buffer& b, const char* label, std::size_t bytes);
bool unmap_fill(Buffer& b);  // false: the contents were lost, write them again
template <class Write>
void fill_buffer_in_place(Buffer& b, const char* label, std::size_t bytes, Write&& write) {
    for (int attempt = 0; attempt < 3; ++attempt) {
        void* dst = map_for_fill(b, label, bytes);
        if (!dst) return;  // nothing to write (0 bytes), or the map failed (logged by the GL debug output)
        write(dst);
        if (unmap_fill(b)) return;
    }
}

// How the CPU reads a resident buffer: decided here, once, for every kind and every reader (the CPU cull
// of surface splats). True on a software rasterizer, whose GL buffers are host memory: the buffer is
// mapped for reading and read in place, so no CPU mirror of any GPU buffer is kept. False on a hardware
// GPU: a copy read back once per version of the buffer (mapping device memory every frame would read it
// across the bus every frame).
bool cpu_reads_in_place();

// Grows `b` (labelled) to hold at least `bytes` without uploading (the deformation's output buffers).
void reserve_buffer(Buffer& b, const char* label, std::size_t bytes);

// The state transitions, written once. set_rest: `rest` now holds `version` (count elements) and nothing
// deformed from an older rest is drawn. set_deformed: `deformed` was just rewritten by `how`.
void set_rest(ResidentCloud& cloud, std::uint64_t version, std::uint32_t count);
void set_deformed(ResidentCloud& cloud, Residency how);
void set_preview(ResidentCloud& cloud, std::uint32_t preview_count);
inline void drop_deformed(ResidentCloud& cloud) { cloud.state = Residency::rest; }

// The columns a cloud's marks are made of (any may be null) and their change stamps
// (registry.version<PointFlags>, <PointWeights>); `pages`: the cloud's PointPages, whose selection,
// visibility and weight stamps bound an upload to the pages that changed (null: every page).
struct PointMarkSources {
    const PointFlags* flags = nullptr;
    const PointWeights* weights = nullptr;
    const PointPages* pages = nullptr;
    std::uint64_t flags_version = 0, weights_version = 0;
};
// Brings `cloud.marks` in step with the columns of its `points` points: released when the cloud has
// neither column (nor a non-empty one of the right size); else the pages whose stamps moved since the last
// upload (all of them after a rest upload, a size change or an unmarked edit) packed and uploaded. Touches
// no other buffer. Returns the points uploaded (0: the marks were current).
std::size_t sync_point_marks(ResidentCloud& cloud, std::size_t points, const PointMarkSources& sources);
// Uploads `preview_indices` into `preview_index` when the cloud has marks and is in state preview_cpu
// with a subset not uploaded yet (the preview uploads call it, and sync_point_marks when marks appear).
void sync_preview_index(ResidentCloud& cloud);
// The draw passes' marks mode bits (bindings.h SFFD_MARKS_*) for the buffers the cloud holds now: present
// (indexed in a preview subset) when it has marks, 0 without (or when a subset's indices are missing).
std::uint32_t resident_marks_mode(const ResidentCloud& cloud);

// True when a GL context (EGL or GLFW) is current on the calling thread: the stores exist only then.
bool context_current();

// Counters of the upload step (a registry resource that residency_system and the deformation systems'
// CPU paths bump; tests and the profiler read it). Not settings: nothing here changes behaviour.
struct ResidencyStats {
    std::uint64_t rest_uploads = 0;      // authored clouds uploaded (per-element CPU work each)
    std::uint64_t deformed_uploads = 0;  // CPU deformation outputs uploaded
    std::uint64_t dropped = 0;           // store entries removed with their entity or component
    std::uint64_t marks_uploads = 0;     // uploads of per-point marks (flags, weights), whole or by page
    std::uint64_t marks_points = 0;      // points those uploads packed
};

}  // namespace sffd::gfx
