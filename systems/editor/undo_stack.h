// One undo stack for everything the editor changes: selections, lattice edits, pins, keyframes.
// A command stores the state before and after (never a closure over live pointers), so undo/redo
// restore exactly the bits that were there: a lattice undone and redone is bit-identical. A step's memory
// is what it changed: lattice and un-keyed-pose changes keep only the control points that moved
// (undo_delta.h), every other component a before/after snapshot; UndoStack::bytes() adds them up.
//
//   UndoStack& undo = registry.resource<EditorState>().undo;
//   undo.record<Lattice>(registry, lattice_entity, "stretch", [&](Lattice& l) { ... });   // one step
//
//   ComponentEdit<Lattice> drag(registry, e, "twist");   // begin of a drag: snapshot `before`
//   ... patch the lattice every frame while dragging ...
//   undo.push(drag.finish(registry));                     // mouse up: snapshot `after`, one step
//
// Any component type works (the animation clip, the picking engineer's selection...): the stack is
// generic over what it stores. A component that is absent before (or after) is stored as "absent", so
// adding or removing a component is undoable too. Restoring goes through registry.patch<C>() so other
// systems (deformer, picking) see the change stamp move.
//
// Entities come and go too (entity_undo.h: EntityLife): undoing a deletion creates a new entity with the
// stored components. The registry gives a re-used index a new generation, so the new entity cannot have
// the old id; the stack's EntityMap records old id -> new id, and every command resolves the entity it
// names (and the ids inside the values it restores, remap_entities) through it.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/editor/undo_delta.h"

namespace sffd::editor {

// Old entity id -> the entity that stands for it now (an undone deletion or a redone creation made a new
// one). Chains resolve to the end: deleted, undone, redone and undone again is old -> 2nd -> 3rd.
class EntityMap {
public:
    ecs::Entity operator()(ecs::Entity e) const {
        for (std::size_t guard = 0; guard <= m_to.size(); ++guard) {
            const auto it = m_to.find(e.bits());
            if (it == m_to.end()) return e;
            e = it->second;
        }
        return e;
    }
    void map(ecs::Entity from, ecs::Entity to) {
        if (from != to) m_to[from.bits()] = to;
    }
    std::size_t size() const { return m_to.size(); }
    void clear() { m_to.clear(); }

private:
    std::unordered_map<std::uint64_t, ecs::Entity> m_to;
};

// Entity ids held inside a component's value (a cloud's Deformers list its lattices): restored values are
// mapped so they name the entities that stand for them now.
inline void remap_entities(Deformers& d, const EntityMap& map) {
    for (ecs::Entity& e : d.lattices) e = map(e);
}
template <class C>
void remap_entities(C&, const EntityMap&) {}

class Command {
public:
    virtual ~Command() = default;
    virtual void undo(ecs::Registry& registry, EntityMap& map) const = 0;
    virtual void redo(ecs::Registry& registry, EntityMap& map) const = 0;
    // True when undo and redo would both leave the registry as it is (nothing worth a step).
    virtual bool empty() const { return false; }
    // Memory the step holds (the command and what it stores).
    virtual std::size_t bytes() const = 0;
    const std::string& label() const { return m_label; }

protected:
    explicit Command(std::string label) : m_label(std::move(label)) {}

private:
    std::string m_label;
};

namespace detail {
template <class C>
bool same_state(const std::optional<C>& a, const std::optional<C>& b) {
    if (a.has_value() != b.has_value()) return false;
    if (!a) return true;
    if constexpr (requires(const C& x, const C& y) {
                      { x == y } -> std::convertible_to<bool>;
                  })
        return *a == *b;
    else return false;  // no equality: keep the step (harmless)
}

template <class C>
void restore(ecs::Registry& registry, ecs::Entity e, const std::optional<C>& state, const EntityMap& map) {
    if (!registry.valid(e)) return;  // entity deleted since: nothing to restore into
    if (state) {
        C value = *state;
        remap_entities(value, map);
        if (registry.has<C>(e)) registry.patch<C>(e) = std::move(value);
        else registry.emplace<C>(e, std::move(value));
    } else {
        registry.remove<C>(e);
    }
}
}  // namespace detail

// The change of one component of one entity: whole before/after snapshots (absent = the entity had no
// C then), or, for SparseUndo components whose frame stayed, only the entries that changed.
template <class C>
class ComponentChange final : public Command {
public:
    ComponentChange(std::string label, ecs::Entity entity, std::optional<C> before, std::optional<C> after)
        : Command(std::move(label)), m_entity(entity) {
        if constexpr (SparseUndo<C>::enabled)
            if (before && after)
                if ((m_delta = SparseUndo<C>::diff(*before, *after))) return;
        m_whole = std::make_unique<Whole>(Whole{std::move(before), std::move(after)});
    }

    void undo(ecs::Registry& registry, EntityMap& map) const override { apply(registry, map, false); }
    void redo(ecs::Registry& registry, EntityMap& map) const override { apply(registry, map, true); }
    bool empty() const override {
        if (!m_whole) return SparseUndo<C>::empty(*m_delta);
        return detail::same_state(m_whole->before, m_whole->after);
    }
    std::size_t bytes() const override {
        std::size_t n = sizeof(*this) + label().capacity();
        if (!m_whole) return n + SparseUndo<C>::bytes(*m_delta);
        n += sizeof(Whole);
        for (const auto* s : {&m_whole->before, &m_whole->after})
            if (*s) n += undo_heap_bytes(**s);
        return n;
    }

    ecs::Entity entity() const { return m_entity; }
    bool sparse() const { return !m_whole; }

private:
    void apply(ecs::Registry& registry, const EntityMap& map, bool forward) const {
        const ecs::Entity e = map(m_entity);
        if (m_whole) return detail::restore(registry, e, forward ? m_whole->after : m_whole->before, map);
        if constexpr (SparseUndo<C>::enabled)
            if (registry.valid(e) && registry.has<C>(e))
                SparseUndo<C>::apply(registry.patch<C>(e), *m_delta, forward);
    }

    struct Whole {
        std::optional<C> before;
        std::optional<C> after;
    };
    using Delta = typename SparseUndo<C>::Delta;

    ecs::Entity m_entity;
    std::unique_ptr<Whole> m_whole;  // null when the step is a delta
    std::optional<Delta> m_delta;
};

// Several changes undone and redone as one step (e.g. resampling a lattice also clears its selection).
// Undo runs the parts in reverse order.
class CommandGroup final : public Command {
public:
    explicit CommandGroup(std::string label) : Command(std::move(label)) {}
    void add(std::unique_ptr<Command> part) {
        if (part && !part->empty()) m_parts.push_back(std::move(part));
    }
    void undo(ecs::Registry& registry, EntityMap& map) const override {
        for (std::size_t i = m_parts.size(); i-- > 0;) m_parts[i]->undo(registry, map);
    }
    void redo(ecs::Registry& registry, EntityMap& map) const override {
        for (const auto& p : m_parts) p->redo(registry, map);
    }
    bool empty() const override { return m_parts.empty(); }
    std::size_t bytes() const override {
        std::size_t n = sizeof(*this) + label().capacity() + m_parts.capacity() * sizeof(m_parts[0]);
        for (const auto& p : m_parts) n += p->bytes();
        return n;
    }
    std::size_t size() const { return m_parts.size(); }

private:
    std::vector<std::unique_ptr<Command>> m_parts;
};

// Snapshot of one component taken now; finish() snapshots again and returns the command. Used for
// drags: the edit is applied live every frame, the step is recorded once at the end.
template <class C>
class ComponentEdit {
public:
    ComponentEdit(const ecs::Registry& registry, ecs::Entity entity, std::string label)
        : m_entity(entity), m_label(std::move(label)), m_before(snapshot(registry, entity)) {}

    ecs::Entity entity() const { return m_entity; }
    const std::optional<C>& before() const { return m_before; }

    std::unique_ptr<ComponentChange<C>> finish(const ecs::Registry& registry) {
        return std::make_unique<ComponentChange<C>>(m_label, m_entity, m_before,
                                                    snapshot(registry, m_entity));
    }

    static std::optional<C> snapshot(const ecs::Registry& registry, ecs::Entity e) {
        if (!registry.valid(e)) return std::nullopt;
        if (const C* c = registry.try_get<C>(e)) return *c;
        return std::nullopt;
    }

private:
    ecs::Entity m_entity;
    std::string m_label;
    std::optional<C> m_before;
};

class UndoStack {
public:
    UndoStack() = default;
    explicit UndoStack(std::size_t limit) : m_limit(limit) {}

    // Adds an already-applied step; drops the redo history. Empty commands are ignored (returns false).
    bool push(std::unique_ptr<Command> command);

    // Applies `edit` to C of `entity` (through patch<C>) and records it as one step. Returns false and
    // records nothing if the entity has no C.
    template <class C, class Fn>
    bool record(ecs::Registry& registry, ecs::Entity entity, std::string label, Fn&& edit) {
        if (!registry.valid(entity) || !registry.has<C>(entity)) return false;
        ComponentEdit<C> change(registry, entity, std::move(label));
        edit(registry.patch<C>(entity));
        return push(change.finish(registry));
    }

    bool undo(ecs::Registry& registry);
    bool redo(ecs::Registry& registry);
    bool can_undo() const { return m_next > 0; }
    bool can_redo() const { return m_next < m_commands.size(); }
    void clear() {
        m_commands.clear();
        m_next = 0;
        m_map.clear();
    }
    // The entity that stands for `e` now (itself unless an undo or redo re-created it).
    ecs::Entity resolve(ecs::Entity e) const { return m_map(e); }
    const EntityMap& entity_map() const { return m_map; }

    std::size_t size() const { return m_commands.size(); }
    // Memory held by every step (done and undone).
    std::size_t bytes() const;
    std::size_t position() const { return m_next; }  // commands [0, position) are applied
    const Command& at(std::size_t i) const { return *m_commands[i]; }
    std::size_t limit() const { return m_limit; }

private:
    std::vector<std::unique_ptr<Command>> m_commands;
    std::size_t m_next = 0;
    std::size_t m_limit = 256;
    EntityMap m_map;
};

}  // namespace sffd::editor
