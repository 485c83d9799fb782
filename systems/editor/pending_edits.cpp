#include "systems/editor/pending_edits.h"

namespace sffd::editor {

PendingEdits& pending_edits(ecs::Registry& registry) {
    if (PendingEdits* p = registry.try_resource<PendingEdits>()) return *p;
    return registry.set_resource<PendingEdits>();
}

void post_edit(ecs::Registry& registry, std::string label,
               std::function<void(ecs::Registry&, EditorState&)> apply) {
    pending_edits(registry).queue.push_back({std::move(label), std::move(apply)});
}

void apply_pending_edits(ecs::Registry& registry, EditorState& state) {
    PendingEdits* pending = registry.try_resource<PendingEdits>();
    if (!pending || pending->queue.empty()) return;
    // An edit may post another (it never does today); those wait for the next frame.
    std::vector<PendingEdits::Edit> edits;
    edits.swap(pending->queue);
    for (PendingEdits::Edit& edit : edits) {
        edit.apply(registry, state);
        ++pending->applied;
    }
}

}  // namespace sffd::editor
