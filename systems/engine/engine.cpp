// The one place that lists which system runs in which phase (the phase order itself is written once, in
// runtime/app/frame_loop.h). One add() line per system, in the order they run within the phase. System
// owners add their own line when their system lands; keep this file compiling with whatever exists.
#include "systems/engine/engine.h"

#include "runtime/app/app.h"
#include "systems/animation/animation_system.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/editor/view_app.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/picking/picking_system.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/splat_render.h"

namespace sffd {

Schedule make_engine_schedule(const EngineScheduleOptions& options) {
    Schedule s;

    // --- input: window events -> editor tools -> edit commands on lattices (editor) -----------------
    s.add(Phase::input, "editor", editor::editor_input_system);  // no-op without an EditorState resource

    // --- animation: clips write lattice control points at the frame time (animation) ----------------
    s.add(Phase::animation, "animation", animation_system);

    // --- residency: upload authored clouds whose change stamp moved; owns the GPU stores (residency) ----
    s.add(Phase::residency, "residency", residency_system);  // no-op without a GL context

    // --- deformation: re-deform point clouds whose rest data or lattices changed (ffd) --------------
    s.add(Phase::deformation, "ffd", ffd_system);  // GPU compute when a context is current, else CPU
    s.add(Phase::deformation, "gaussian", gaussian_deform_system);  // 3D Gaussian clouds, CPU

    // --- picking: only when a pick was requested (picking); then the editor's gestures that waited for
    // their pick (click select, brush, alt+click pivot) -------------------------------------------------
    s.add(Phase::picking, "picking", picking::picking_system);
    s.add(Phase::picking, "editor.picks", editor::editor_pick_system);  // no-op without an EditorState

    // --- rendering: splat passes, overlays, UI, capture (splat_render, editor overlay) ---------------
    s.add(Phase::rendering, "splat_render", render::render_system);  // culling + HQ/preview splat passes
    if (options.editor) {
        s.add(Phase::rendering, "editor.overlay", editor::lattice_overlay_system);  // into the linear target
        s.add(Phase::rendering, "editor.requests", editor::requests_system);        // save, screenshot, quit
    }

    // --- present: sRGB display pass straight into the window (after every overlay; the blit only copies
    // when the window's size differs from the frame's), window UI on top (editor), swap ----------------
    if (options.present) {
        s.add(Phase::present, "render.display", render::display_system);
        s.add(Phase::present, "present.blit", app::present_blit_system);
        if (options.editor) s.add(Phase::present, "editor.ui", editor::ui_system);
        s.add(Phase::present, "present.swap", app::present_swap_system);
    }

    return s;
}

}  // namespace sffd
