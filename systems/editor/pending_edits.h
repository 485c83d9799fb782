// Edits the UI posts and the input phase applies. The panels run in the present phase, after this frame's
// deformation, picking and rendering; a component they wrote there would be seen by those phases only
// next frame, after a second writer (the input system) had already run. So a panel never writes a scene
// component: each widget posts what it wants into this queue (a registry resource), and
// editor_input_system applies the queue first thing in the next frame's input phase, in posting order,
// before that frame's events (which came later), recording undo steps as the shortcuts do.
//
//   post_edit(registry, "undo", [](ecs::Registry& r, EditorState& s) { undo(r, s); });
//   post_component(registry, e, transform_copy);                        // a drag's live value
//   post_component_step(registry, e, before, transform_copy, "move entity");  // on release: one step
//
// View state (tools, axes, panel toggles, which entity the outliner selects, the fit settings) is the
// editor's own and the panels set it directly; it is not scene content.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/ecs/type_info.h"
#include "systems/editor/editor_state.h"

namespace sffd::editor {

struct PendingEdits {
    struct Edit {
        std::string label;  // for logs and tests
        std::function<void(ecs::Registry&, EditorState&)> apply;
    };
    std::vector<Edit> queue;
    std::size_t applied = 0;  // edits applied so far (tests)
    // The widget held now (ImGui has one active widget at a time): the entity and component type it
    // edits and the component's value when it became active, kept by the panels until it is released.
    struct Gesture {
        ecs::Entity entity = ecs::null_entity;
        std::uint32_t type = 0;
        std::shared_ptr<const void> before;
    } gesture;
};

PendingEdits& pending_edits(ecs::Registry& registry);

// Posts an operation; it runs in the next input phase with the registry and the editor state. The
// operations of editor_system.h and lattice_manage.h each record their own undo step.
void post_edit(ecs::Registry& registry, std::string label,
               std::function<void(ecs::Registry&, EditorState&)> apply);

// A widget's value of component C while it is being dragged or typed: set in the next input phase
// (through patch, so the systems that read C see the stamp move), no undo step yet.
template <class C>
void post_component(ecs::Registry& registry, ecs::Entity e, C value) {
    post_edit(registry, "set", [e, value = std::move(value)](ecs::Registry& r, EditorState&) {
        if (r.valid(e) && r.has<C>(e)) r.patch<C>(e) = value;
    });
}

// The widget was released after an edit: `value` is set (if it is not yet) and the gesture becomes one
// undo step from `before` (the value when the widget became active) to the component as it then is.
template <class C>
void post_component_step(ecs::Registry& registry, ecs::Entity e, C before, C value, std::string label) {
    post_edit(
        registry, label,
        [e, before = std::move(before), value = std::move(value), label](ecs::Registry& r, EditorState& s) {
            if (!r.valid(e) || !r.has<C>(e)) return;
            r.patch<C>(e) = value;
            s.undo.push(std::make_unique<ComponentChange<C>>(label, e, before, r.get<C>(e)));
        });
}

// The panels' side of a held widget on C of `e`: `shown` is the component before this frame's widget
// ran, `value` the widget's copy after it. Activation keeps `shown`; a change posts `value`; release
// after an edit posts the step from the kept value (one undo step per gesture).
template <class C>
void post_widget_gesture(ecs::Registry& registry, ecs::Entity e, const C& shown, const C& value,
                         bool activated, bool changed, bool released_after_edit, const char* label) {
    PendingEdits::Gesture& g = pending_edits(registry).gesture;
    const std::uint32_t type = ecs::detail::type_id<C>();
    if (activated) g = {e, type, std::make_shared<const C>(shown)};
    if (changed) post_component<C>(registry, e, value);
    if (released_after_edit && g.before && g.entity == e && g.type == type) {
        post_component_step<C>(registry, e, *static_cast<const C*>(g.before.get()), value, label);
        g = {};
    }
}

// Applies every posted edit in order and empties the queue (editor_input_system's first step).
void apply_pending_edits(ecs::Registry& registry, EditorState& state);

}  // namespace sffd::editor
