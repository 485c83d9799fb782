// streaming_system: the first system of the residency phase (runtime/app/frame_loop.h). Clouds opened
// from a level-of-detail hierarchy (stream.h) carry a StreamedCloud; every frame the system updates each
// stream for the scene's camera (the first Camera, as the renderer chooses it), the render size
// (render::RenderSettings) and the cloud's lattices in its frame (ffd::cloud_lattices), and, when the
// drawn set changed, writes it into the entity's GaussianCloud or SplatCloud (patch: a replacement, which
// residency uploads and the deformers deform as any new cloud; the stream owns which splats are drawn, the
// cloud component holds them).
//   reads   StreamSettings, Camera, Transform, Deformers, Lattice, render::RenderSettings
//   writes  StreamedCloud, GaussianCloud, SplatCloud (the streamed entities only), PointFlags and
//           PointWeights (dropped from a streamed entity when its drawn set changes: they were per point
//           of the old set)
// While pieces arrive the drawn set is written at most every StreamSettings::assemble_interval_s, so
// that a frame does not copy and upload the cut for every piece; once the cut is complete it is written
// at once; while the lattices move it is kept (StreamSettings::hold_while_deforming). With
// StreamSettings::wait (final renders, farms) every frame waits for its whole cut first, so frame k is the
// same whoever renders it.
//
// enable_streaming() gives a registry its StreamSettings and a scene file loader that claims hierarchies
// (lod-meta.json; a Potree 2 metadata.json of our splats): load_scene then opens them by streaming. It
// opens the stream, makes the entity (Name, Transform: a capture's upright turn for Gaussians as
// load_gaussian_entity gives it; GaussianSource for Gaussians), draws the coarse cut for a camera
// framing the root's box (waiting for it: the first frame has something to show) and adds that camera
// when the scene has none.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "systems/lod/stream.h"

namespace sffd {
struct SceneHooks;

namespace lod {

struct StreamedCloud {
    std::shared_ptr<HierarchyStream> stream;
    double last_assemble = -1.0;  // steady-clock seconds of the last write of the drawn set
    std::uint64_t frames_waited = 0;
    std::string error;                // the first failure the system met (a load, or a cut over the budget)
    std::uint64_t lattice_stamp = 0;  // the lattices' stamp in the last frame (streaming.cpp)
    std::uint64_t frames_seen = 0;
};

struct StreamSettings {
    StreamOptions options;
    bool wait = false;                         // every frame waits for its cut (final renders)
    double assemble_interval_s = 0.25;         // while pieces arrive
    std::uint64_t first_cut_budget = 200'000;  // splats of the cut the loader waits for
    // While a cloud's lattices move from frame to frame (a drag, a playing clip) its drawn set is kept
    // (the deformers show the edit on it at once; rewriting it would upload and deform the whole cut
    // again), unless it is empty; the first frame they stay still draws the cut of the deformed shape.
    // Not with `wait`.
    bool hold_while_deforming = true;
};

// StreamSettings (replaced when present) and the hierarchy loader in the registry's SceneHooks.
void enable_streaming(ecs::Registry& registry, const StreamSettings& settings = {});
// The loader alone (enable_streaming adds it): a key that sorts before every other loader's, so that it
// claims a hierarchy before the readers that load one whole.
void register_streaming_scene_hooks(SceneHooks& hooks);

void streaming_system(ecs::Registry& registry, const FrameContext& frame);

// The first failure any streamed cloud met (StreamedCloud::error). With StreamSettings::wait the system
// does not print it: a final render refuses the frame and says why.
Status stream_status(const ecs::Registry& registry);

// The streams' statistics summed over the registry's streamed clouds (empty: none).
struct StreamSummary {
    std::size_t clouds = 0;
    StreamStats stats;
};
StreamSummary stream_summary(const ecs::Registry& registry);

}  // namespace lod
}  // namespace sffd
