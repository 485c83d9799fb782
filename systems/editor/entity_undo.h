// Undoable creation and deletion of entities (undo_stack.h). A deletion keeps the entity's components
// (the types listed, as values) and destroys the entity, so nothing empty is left in the registry; undoing
// it creates a new entity with those components. A creation is the same step the other way round.
//
// The registry never gives an id back: a destroyed entity's index returns with a new generation, so the
// re-created entity has a new id. The step records old id -> new id in the stack's EntityMap; every
// other step resolves the entity it names through it, and values that hold ids (a cloud's Deformers) are
// mapped when restored, so a cloud bound to a deleted lattice follows the re-created one after undo. The
// editor maps its own references (active lattice, selection, un-keyed edit) after each undo and redo.
//
// Only the listed components come back. Derived ones (a cloud's deformed output, GPU state, caches) are
// not kept: their systems rebuild them from the restored components, which get new change stamps.
#pragma once

#include <optional>
#include <string>
#include <tuple>

#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/editor/undo_stack.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"

namespace sffd::editor {

template <class... C>
class EntityLife final : public Command {
public:
    enum class Kind : bool { created, destroyed };

    // Snapshots the entity's components now: call right after creating it (created), or right before
    // destroying it (destroyed; destroy() below does both).
    EntityLife(std::string label, const ecs::Registry& registry, ecs::Entity entity, Kind kind)
        : Command(std::move(label)), m_entity(entity), m_kind(kind) {
        capture(registry, entity);
    }

    // Records the components of `entity` and destroys it; returns the step.
    static std::unique_ptr<EntityLife> destroy(std::string label, ecs::Registry& registry,
                                               ecs::Entity entity) {
        auto step = std::make_unique<EntityLife>(std::move(label), registry, entity, Kind::destroyed);
        registry.destroy(entity);
        return step;
    }

    void undo(ecs::Registry& registry, EntityMap& map) const override {
        if (m_kind == Kind::created) kill(registry, map);
        else revive(registry, map);
    }
    void redo(ecs::Registry& registry, EntityMap& map) const override {
        if (m_kind == Kind::created) revive(registry, map);
        else kill(registry, map);
    }
    std::size_t bytes() const override {
        std::size_t n = sizeof(*this) + label().capacity();
        std::apply([&](const auto&... part) { ((n += part ? undo_heap_bytes(*part) : 0), ...); }, m_parts);
        return n;
    }
    ecs::Entity entity() const { return m_entity; }

private:
    template <class T>
    static void take(const ecs::Registry& registry, ecs::Entity e, std::optional<T>& out) {
        const T* c = registry.try_get<T>(e);
        out = c ? std::optional<T>(*c) : std::nullopt;
    }
    template <class T>
    static void put(ecs::Registry& registry, ecs::Entity e, const std::optional<T>& in,
                    const EntityMap& map) {
        if (!in) return;
        T value = *in;
        remap_entities(value, map);
        registry.emplace<T>(e, std::move(value));
    }
    void capture(const ecs::Registry& registry, ecs::Entity e) const {
        std::apply([&](auto&... part) { (take(registry, e, part), ...); }, m_parts);
    }
    // The entity is there (the stack is linear): keep its components as they are now, then destroy it.
    void kill(ecs::Registry& registry, EntityMap& map) const {
        const ecs::Entity e = map(m_entity);
        if (!registry.valid(e)) return;
        capture(registry, e);
        registry.destroy(e);
    }
    // A new entity with the kept components; the old id now resolves to it.
    void revive(ecs::Registry& registry, EntityMap& map) const {
        const ecs::Entity old = map(m_entity);
        if (registry.valid(old)) return;
        const ecs::Entity e = registry.create();
        std::apply([&](const auto&... part) { (put(registry, e, part, map), ...); }, m_parts);
        map.map(old, e);
    }

    ecs::Entity m_entity;
    Kind m_kind;
    mutable std::tuple<std::optional<C>...> m_parts;  // re-captured at each deletion (derived fields move)
};

// What a lattice entity is made of, as the editor creates, deletes and restores it.
using LatticeLife = EntityLife<Name, Transform, Lattice, AnimationClip, AnimationState, UnkeyedEdit,
                               picking::LatticeSelection>;

}  // namespace sffd::editor
