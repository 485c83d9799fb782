// The one place that lists which system runs in which phase (the phase order itself is written once, in
// runtime/app/frame_loop.h). One add() line per system, in the order they run within the phase, with the
// components and resources it reads and writes (ecs::reads<...>().writes<...>(), runtime/ecs/access.h).
// A declaration is what the system does today, checked by SFFD_CHECK_ACCESS builds: mutable access
// (a non-const get, try_get, try_resource or view) is a write even where the system only reads through
// it. System owners add their own line when their system lands; keep this file compiling with whatever
// exists. The README's frame table is generated from these lines (tools/update_frame_table.sh).
#include "systems/engine/engine.h"

#include "runtime/app/app.h"
#include "runtime/app/pass_timer.h"
#include "runtime/assets/scene.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "systems/editor/editor_state.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/lattice_manage.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/editor/panel_layout.h"
#include "systems/editor/pending_edits.h"
#include "systems/editor/session_state.h"
#include "systems/editor/ui_cache.h"
#include "systems/editor/view_app.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_backend.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/preview_budget.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/lod/streaming.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/picking_system.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/splat_render.h"

// State a system keeps in its own .cpp, named here by its full name only (a declaration needs the type,
// not its definition).
namespace sffd::render {
struct GaussianBoundsCache;
struct GaussianPassState;
namespace detail {
struct CloudGpu;
struct SplatRenderState;
}  // namespace detail
}  // namespace sffd::render
namespace sffd::editor {
struct LatticeOverlayState;
}
namespace sffd::profiling {
struct ProfileOverlay;
}

namespace sffd {

Schedule make_engine_schedule(const EngineScheduleOptions& options) {
    Schedule s;

    // --- input: window events -> editor tools -> edit commands on lattices (editor) -----------------
    // Point mode (point_mode.h): the selection reads the shown points (picking's sources: the deformed
    // outputs, a GPU output read back); hide/delete/separate write the flags and make or destroy clouds.
    s.add(Phase::input, "editor", editor::editor_input_system,  // no-op without an EditorState resource
          ecs::reads<DeformedSplats, gfx::GpuSplatStore>()
              .writes<AnimationClip, AnimationState, Camera, DeformedGaussians, Deformers, GaussianCloud,
                      Lattice, Name, PointFlags, PointPages, PointWeights, PreviewBudget, SplatCloud,
                      SplatMaterial, Transform, UnkeyedEdit, editor::EditorState, editor::LatticeFitSettings,
                      editor::PendingEdits, editor::SceneBoundsCache, gaussian::GpuGaussianStore,
                      picking::LatticeSelection, picking::PickRequests, render::RenderSettings>());

    // --- animation: clips write lattice control points at the frame time (animation) ----------------
    s.add(Phase::animation, "animation", animation_system,
          ecs::reads<AnimationClip>().writes<AnimationState, Lattice, UnkeyedEdit>());

    // --- residency: streamed hierarchies write the cut they draw (lod), then authored clouds whose
    // change stamp moved are uploaded; residency owns the GPU stores -----------------------------------
    s.add(Phase::residency, "streaming", lod::streaming_system,  // no-op without streamed clouds
          ecs::reads<Camera, Deformers, Lattice, Transform, lod::StreamSettings, render::RenderSettings>()
              .writes<GaussianCloud, PointFlags, PointWeights, SplatCloud, lod::StreamedCloud>());
    s.add(Phase::residency, "residency", residency_system,  // no-op without a GL context
          ecs::reads<Deformers, GaussianCloud, PointFlags, PointPages, PointWeights, SplatCloud>()
              .writes<ResidencyConnections, gaussian::GpuGaussianStore, gfx::GpuSplatStore,
                      gfx::ResidencyStats>());

    // --- deformation: re-deform point clouds whose rest data or lattices changed (ffd) --------------
    s.add(Phase::deformation, "ffd", ffd_system,  // GPU compute when a context is current, else CPU
          ecs::reads<Deformers, Lattice, PointWeights, PreviewBudget, SplatCloud>()
              .writes<DeformedSplats, FfdSettings, FfdStats, PointPages, Transform,
                      ffd::GpuDeformerState<ffd::GpuDeformer>, gfx::GpuSplatStore, gfx::ResidencyStats>());
    s.add(Phase::deformation, "gaussian", gaussian_deform_system,  // 3D Gaussian clouds
          ecs::reads<Deformers, GaussianCloud, Lattice, PointWeights, PreviewBudget, SplatCloud, Transform>()
              .writes<DeformedGaussians, FfdSettings, GaussianDeformSettings, GaussianDeformStats, PointPages,
                      ffd::GpuDeformerState<gaussian::GpuGaussianDeformer>, gaussian::GpuGaussianStore,
                      gfx::ResidencyStats>());

    // --- picking: only when a pick was requested (picking); then the editor's gestures that waited for
    // their pick (click select, brush, alt+click pivot) -------------------------------------------------
    s.add(Phase::picking, "picking", picking::picking_system,
          ecs::reads<DeformedSplats, Deformers, Lattice, PointFlags, PointWeights, SplatCloud>()
              .writes<DeformedGaussians, GaussianCloud, Transform, picking::PickRequests,
                      picking::PickResults, picking::PickSettings, picking::PickingState>());
    s.add(Phase::picking, "editor.picks", editor::editor_pick_system,  // no-op without an EditorState
          ecs::reads<DeformedSplats, Deformers, SplatMaterial, gfx::GpuSplatStore, picking::PickResults>()
              .writes<DeformedGaussians, GaussianCloud, Lattice, PointFlags, PointPages, PointWeights,
                      SplatCloud, Transform, editor::EditorState, gaussian::GpuGaussianStore,
                      picking::LatticeSelection, picking::PickSettings, picking::PickingState>());

    // --- rendering: splat passes, overlays, UI, capture (splat_render, editor overlay) ---------------
    s.add(Phase::rendering, "splat_render", render::render_system,  // culling + HQ/preview splat passes
          ecs::reads<AmbientLight, Camera, DirectionalLight, PointFlags, PointWeights, SplatCloud>()
              .writes<DeformedSplats, GaussianCloud, SplatMaterial, Transform, gaussian::GpuGaussianStore,
                      gfx::GpuSplatStore, profiling::PassTimer, render::GaussianBoundsCache,
                      render::GaussianPassState, render::RenderSettings, render::RenderStats,
                      render::detail::CloudGpu, render::detail::SplatRenderState>());
    if (options.editor) {
        s.add(Phase::rendering, "editor.overlay", editor::lattice_overlay_system,  // into the linear target
              ecs::reads<GaussianCloud, Lattice, SplatCloud, Transform, editor::SceneBoundsCache,
                         picking::LatticeSelection>()
                  .writes<Camera, editor::EditorState, editor::EditorViewRect, editor::LatticeOverlayState,
                          editor::OverlayOptions, render::detail::SplatRenderState>());
        // Save (every component a scene file holds, through the scene's hooks), screenshot, quit.
        s.add(Phase::rendering, "editor.requests", editor::requests_system,
              ecs::reads<AmbientLight, AnimationClip, AnimationState, Camera, Deformers, DirectionalLight,
                         DeformedGaussians, GaussianCloud, GaussianSource, Lattice, Name, PointFlags,
                         PointWeights, SceneHooks, SplatCloud, SplatMaterial, Transform, UnkeyedEdit>()
                  .writes<app::AppContext, editor::EditorState, editor::detail::ViewSession,
                          render::detail::SplatRenderState>());
    }

    // --- present: sRGB display pass straight into the window (after every overlay; the blit only copies
    // when the window's size differs from the frame's), window UI on top (editor), swap ----------------
    if (options.present) {
        s.add(Phase::present, "render.display", render::display_system,
              ecs::writes<app::AppContext, app::PresentSource, render::DisplayViewport,
                          render::detail::SplatRenderState>());
        s.add(Phase::present, "present.blit", app::present_blit_system,
              ecs::writes<app::AppContext, app::PresentSource>());
        // The window UI: panels show the scene and post their edits (editor::PendingEdits) for the input
        // phase; File > Open replaces the scene (so it writes what loading makes).
        if (options.editor)
            s.add(Phase::present, "editor.ui", editor::ui_system,
                  ecs::reads<AmbientLight, AnimationClip, AnimationState, Deformers, DirectionalLight,
                             GaussianCloud, Lattice, Name, PointFlags, SceneHooks, SplatCloud, Transform,
                             editor::SceneBoundsCache, picking::LatticeSelection>()
                      .writes<Camera, SplatMaterial, editor::EditorState, editor::EditorViewRect,
                              editor::LatticeFitSettings, editor::UiCacheOptions, editor::UiCacheState,
                              editor::detail::FileDialog, editor::detail::FrameTimeShown,
                              editor::detail::LayoutState, editor::detail::PanelEntries,
                              editor::detail::ViewSession, profiling::ProfileOverlay,
                              render::DisplayViewport>());
        s.add(Phase::present, "present.swap", app::present_swap_system, ecs::writes<app::AppContext>());
    }

    return s;
}

}  // namespace sffd
