// Sparse-set component storage: `sparse[entity.index]` -> position in the packed arrays `dense`
// (entities) and `data` (components). Add and remove are O(1); removal swaps the last element into the
// hole, so iteration runs backwards and removing the current element while iterating is safe.
//
// Change tracking: every storage shares the registry's tick counter. emplace/patch/mark_changed stamp
// the component with a new tick, and the storage remembers its latest tick, so a system can ask "did
// anything of this type change since I last looked?" in O(1), then compare per-entity stamps only for
// the few entities it cares about (e.g. the deformer re-runs only for point clouds whose lattice moved).
//
// Signals: on_construct runs after a component is added (not when emplace replaces one), on_destroy
// before one is removed (remove, clear, or its entity's destroy), so a listener still reads it.
#pragma once

#include <cassert>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "runtime/ecs/entity.h"
#include "runtime/ecs/signal.h"

namespace sffd::ecs {

namespace detail {
// One construction rule for components and resources: braces for aggregates (`emplace<Pos>(e, 1.f, 2.f)`),
// parentheses otherwise, so `std::vector<int>(3, 1)` means three ones whether it is added or replaced.
template <class T, class... Args>
T make(Args&&... args) {
    if constexpr (std::is_aggregate_v<T>) return T{std::forward<Args>(args)...};
    else return T(std::forward<Args>(args)...);
}
}  // namespace detail

class StorageBase {
public:
    static constexpr std::uint32_t npos = 0xffffffffu;

    StorageBase(Registry* owner, std::uint64_t* tick) : m_owner(owner), m_tick(tick) {}
    virtual ~StorageBase() = default;
    StorageBase(const StorageBase&) = delete;
    StorageBase& operator=(const StorageBase&) = delete;

    bool contains(Entity e) const {
        return e.index < m_sparse.size() && m_sparse[e.index] != npos && m_dense[m_sparse[e.index]] == e;
    }
    std::size_t size() const { return m_dense.size(); }
    const std::vector<Entity>& entities() const { return m_dense; }
    // Latest change stamp of anything in this storage (add, remove, patch, mark_changed).
    std::uint64_t version() const { return m_version; }
    // Change stamp of one entity's component; 0 when absent.
    std::uint64_t version(Entity e) const { return contains(e) ? m_stamps[m_sparse[e.index]] : 0; }
    void mark_changed(Entity e) {
        assert(contains(e));
        m_stamps[m_sparse[e.index]] = m_version = ++*m_tick;
    }
    virtual void remove(Entity e) = 0;
    virtual void clear() = 0;

    Signal& on_construct() { return m_on_construct; }
    Signal& on_destroy() { return m_on_destroy; }

protected:
    std::uint32_t position(Entity e) const { return m_sparse[e.index]; }

    std::uint32_t push_entity(Entity e) {
        if (e.index >= m_sparse.size()) m_sparse.resize(std::size_t(e.index) + 1, npos);
        const auto pos = static_cast<std::uint32_t>(m_dense.size());
        m_sparse[e.index] = pos;
        m_dense.push_back(e);
        m_stamps.push_back(m_version = ++*m_tick);
        return pos;
    }

    // Swap-and-pop of the entity bookkeeping; returns the freed position (the caller moves data).
    std::uint32_t pop_entity(Entity e) {
        const std::uint32_t pos = m_sparse[e.index];
        const Entity last = m_dense.back();
        m_dense[pos] = last;
        m_stamps[pos] = m_stamps.back();
        m_sparse[last.index] = pos;
        m_sparse[e.index] = npos;
        m_dense.pop_back();
        m_stamps.pop_back();
        m_version = ++*m_tick;
        return pos;
    }

    std::vector<std::uint32_t> m_sparse;
    std::vector<Entity> m_dense;
    std::vector<std::uint64_t> m_stamps;
    std::uint64_t m_version = 0;
    Registry* m_owner;
    std::uint64_t* m_tick;
    Signal m_on_construct;
    Signal m_on_destroy;
};

template <class C>
class Storage final : public StorageBase {
public:
    using StorageBase::StorageBase;

    template <class... Args>
    C& emplace(Entity e, Args&&... args) {
        if (contains(e)) {
            C& slot = m_data[position(e)];
            slot = detail::make<C>(std::forward<Args>(args)...);
            mark_changed(e);
            return slot;
        }
        // Construct before touching the bookkeeping, so a throwing constructor leaves the storage intact.
        C value = detail::make<C>(std::forward<Args>(args)...);
        push_entity(e);
        m_data.emplace_back(std::move(value));
        if (m_on_construct.empty()) return m_data.back();
        m_on_construct.publish(*m_owner, e);
        return get(e);  // a listener may have added components of this type, moving the data
    }

    void remove(Entity e) override {
        if (!contains(e)) return;
        m_on_destroy.publish(*m_owner, e);
        if (!contains(e)) return;  // a listener removed it already
        const std::uint32_t pos = pop_entity(e);
        if (pos != m_data.size() - 1) m_data[pos] = std::move(m_data.back());
        m_data.pop_back();
    }

    void clear() override {
        if (!m_on_destroy.empty()) {
            const std::vector<Entity> doomed = m_dense;
            for (const Entity e : doomed)
                if (contains(e)) m_on_destroy.publish(*m_owner, e);
        }
        for (const Entity e : m_dense) m_sparse[e.index] = npos;
        m_dense.clear();
        m_stamps.clear();
        m_data.clear();
        m_version = ++*m_tick;
    }

    C& get(Entity e) {
        assert(contains(e));
        return m_data[position(e)];
    }
    const C& get(Entity e) const {
        assert(contains(e));
        return m_data[position(e)];
    }
    C* try_get(Entity e) { return contains(e) ? &m_data[position(e)] : nullptr; }
    const C* try_get(Entity e) const { return contains(e) ? &m_data[position(e)] : nullptr; }

    // Unchecked access by packed position (views use it after checking membership).
    C& at(std::uint32_t pos) { return m_data[pos]; }
    std::uint32_t position_of(Entity e) const { return position(e); }

private:
    std::vector<C> m_data;
};

}  // namespace sffd::ecs
