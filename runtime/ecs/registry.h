// Registry: owns entities, their components (one sparse set per type) and singleton resources.
//
//   ecs::Registry reg;
//   ecs::Entity e = reg.create();
//   reg.emplace<Position>(e, 1.f, 2.f);
//   reg.view<const Velocity, Position>().each([](ecs::Entity, const Velocity& v, Position& p) { ... });
//
// `const` in a view means read-only. Views iterate the smallest of their storages backwards, so
// removing the *current* entity's components, or destroying it, while iterating is safe; any other
// structural change during iteration goes through destroy_later()/defer() and flush().
//
// Change detection: patch<C>(e) returns a mutable reference and stamps the component as changed;
// version<C>(e) and storage_version<C>() let a system skip work when nothing it depends on moved.
//
// Signals: on_construct<C>() / on_destroy<C>() (runtime/ecs/signal.h) tell listeners when a C is added
// or removed (destroy included), so state kept per entity elsewhere is cleaned up in one place.
// Context: the resources are the registry's context, per-registry services (scene loaders, GPU state).
// Declared access: with SFFD_CHECK_ACCESS defined, every accessor checks the running system's declared
// access (runtime/ecs/access.h); without it the checks compile to nothing.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <functional>
#include <memory>
#include <tuple>
#include <type_traits>
#include <vector>

#include "runtime/ecs/access.h"
#include "runtime/ecs/entity.h"
#include "runtime/ecs/signal.h"
#include "runtime/ecs/storage.h"
#include "runtime/ecs/type_info.h"

namespace sffd::ecs {

class Registry;

template <class... C>
class View {
    static_assert(sizeof...(C) > 0);
    using Storages = std::tuple<Storage<std::remove_const_t<C>>*...>;

public:
    explicit View(Storages storages) : m_storages(storages) {
        const StorageBase* smallest = nullptr;
        std::apply(
            [&](auto*... s) {
                ((smallest = (!smallest || s->size() < smallest->size()) ? s : smallest), ...);
            },
            m_storages);
        m_lead = smallest;
    }

    // fn(Entity, C&...) or fn(C&...). Iterates backwards over the smallest storage.
    template <class Fn>
    void each(Fn&& fn) const {
        const std::vector<Entity>& lead = m_lead->entities();
        for (std::size_t i = lead.size(); i-- > 0;) {
            if (i >= lead.size()) continue;  // several entries removed during the call
            const Entity e = lead[i];
            // The lead storage holds e at position i by construction: only the others are looked up.
            if (!contains_others(e)) continue;
            call(fn, e, static_cast<std::uint32_t>(i));
        }
    }

    bool contains(Entity e) const { return contains_all(e); }
    std::size_t size_hint() const { return m_lead->size(); }

    // Range-for support: for (auto [e, a, b] : view) { ... }
    class iterator {
    public:
        iterator(const View* view, std::size_t i) : m_view(view), m_i(i) { skip(); }
        std::tuple<Entity, C&...> operator*() const {
            const Entity e = m_view->m_lead->entities()[m_i - 1];
            return std::tuple<Entity, C&...>(e, m_view->template get<C>(e)...);
        }
        iterator& operator++() {
            --m_i;
            skip();
            return *this;
        }
        bool operator==(const iterator& o) const { return m_i == o.m_i; }

    private:
        void skip() {
            const auto& lead = m_view->m_lead->entities();
            while (m_i > 0 && (m_i > lead.size() || !m_view->contains_all(lead[m_i - 1]))) --m_i;
        }
        const View* m_view;
        std::size_t m_i;
    };
    iterator begin() const { return iterator(this, m_lead->size()); }
    iterator end() const { return iterator(this, 0); }

private:
    bool contains_all(Entity e) const {
        return std::apply([&](auto*... s) { return (s->contains(e) && ...); }, m_storages);
    }
    bool contains_others(Entity e) const {
        return std::apply([&](auto*... s) { return ((s == m_lead || s->contains(e)) && ...); }, m_storages);
    }
    // Component of e, which sits at `lead_pos` in the lead storage.
    template <class T>
    T& get_at(Entity e, std::uint32_t lead_pos) const {
        auto* s = std::get<Storage<std::remove_const_t<T>>*>(m_storages);
        return s->at(s == m_lead ? lead_pos : s->position_of(e));
    }
    template <class T>
    T& get(Entity e) const {
        auto* s = std::get<Storage<std::remove_const_t<T>>*>(m_storages);
        return s->at(s->position_of(e));
    }
    template <class Fn>
    void call(Fn& fn, Entity e, std::uint32_t lead_pos) const {
        if constexpr (std::is_invocable_v<Fn&, Entity, C&...>) fn(e, get_at<C>(e, lead_pos)...);
        else fn(get_at<C>(e, lead_pos)...);
    }

    Storages m_storages;
    const StorageBase* m_lead = nullptr;
};

class Registry {
public:
    Registry() = default;
    Registry(const Registry&) = delete;
    Registry& operator=(const Registry&) = delete;

    // --- entities --------------------------------------------------------------------------------
    Entity create() {
        if (!m_free.empty()) {
            const std::uint32_t index = m_free.back();
            m_free.pop_back();
            m_alive[index] = 1;
            return {index, m_generations[index]};
        }
        m_generations.push_back(0);
        m_alive.push_back(1);
        return {static_cast<std::uint32_t>(m_generations.size() - 1), 0};
    }

    bool valid(Entity e) const {
        return e.index < m_generations.size() && m_alive[e.index] && m_generations[e.index] == e.generation;
    }

    // Immediate destruction: removes every component, bumps the generation (stale handles die).
    void destroy(Entity e) {
        assert(valid(e) && "destroy(): stale or null entity");
        for (auto& s : m_storages)
            if (s) s->remove(e);
        ++m_generations[e.index];
        m_alive[e.index] = 0;
        m_free.push_back(e.index);
    }

    // Deferred structural changes, applied by flush() (the frame loop calls it between phases).
    void destroy_later(Entity e) { m_pending_destroy.push_back(e); }
    void defer(std::function<void(Registry&)> command) { m_deferred.push_back(std::move(command)); }
    void flush() {
        auto commands = std::move(m_deferred);
        m_deferred.clear();
        for (auto& c : commands) c(*this);
        auto doomed = std::move(m_pending_destroy);
        m_pending_destroy.clear();
        for (Entity e : doomed)
            if (valid(e)) destroy(e);
    }

    std::size_t alive() const { return m_generations.size() - m_free.size(); }

    // Every live entity (in index order).
    template <class Fn>
    void each_entity(Fn&& fn) const {
        for (std::uint32_t i = 0; i < m_generations.size(); ++i)
            if (m_alive[i]) fn(Entity{i, m_generations[i]});
    }

    // --- components ------------------------------------------------------------------------------
    template <class C, class... Args>
    C& emplace(Entity e, Args&&... args) {
        assert(valid(e));
        check_write<C>();
        return storage_of<C>().emplace(e, std::forward<Args>(args)...);
    }
    template <class C>
    void remove(Entity e) {
        check_write<C>();
        if (auto* s = find_storage<C>()) s->remove(e);
    }
    template <class C>
    bool has(Entity e) const {
        check_read<C>();
        const auto* s = find_storage<C>();
        return s && s->contains(e);
    }
    template <class C>
    C& get(Entity e) {
        check_write<C>();
        return storage_of<C>().get(e);
    }
    template <class C>
    const C& get(Entity e) const {
        check_read<C>();
        const auto* s = find_storage<C>();
        assert(s);
        return s->get(e);
    }
    template <class C>
    C* try_get(Entity e) {
        check_write<C>();
        auto* s = find_storage<C>();
        return s ? s->try_get(e) : nullptr;
    }
    template <class C>
    const C* try_get(Entity e) const {
        check_read<C>();
        const auto* s = find_storage<C>();
        return s ? s->try_get(e) : nullptr;
    }

    // Mutable access that records a change (use it for edits other systems must react to).
    template <class C>
    C& patch(Entity e) {
        check_write<C>();
        auto& s = storage_of<C>();
        s.mark_changed(e);
        return s.get(e);
    }
    template <class C>
    void mark_changed(Entity e) {
        check_write<C>();
        storage_of<C>().mark_changed(e);
    }
    // Change stamp of e's C (0 if absent), and the latest stamp of any C.
    template <class C>
    std::uint64_t version(Entity e) const {
        check_read<C>();
        const auto* s = find_storage<C>();
        return s ? s->version(e) : 0;
    }
    template <class C>
    std::uint64_t storage_version() const {
        check_read<C>();
        const auto* s = find_storage<C>();
        return s ? s->version() : 0;
    }
    std::uint64_t tick() const { return m_tick; }

    // `const C` in the list is read access, plain C write access.
    template <class... C>
    View<C...> view() {
        (check_view<C>(), ...);
        return View<C...>(std::make_tuple(&storage_of<std::remove_const_t<C>>()...));
    }
    template <class... C>
    View<const C...> view() const {
        (check_read<std::remove_const_t<C>>(), ...);
        return View<const C...>(
            std::make_tuple(&const_cast<Registry*>(this)->storage_of<std::remove_const_t<C>>()...));
    }

    template <class C>
    std::size_t count() const {
        check_read<C>();
        const auto* s = find_storage<C>();
        return s ? s->size() : 0;
    }

    template <class C>
    Storage<C>& storage() {
        check_write<C>();
        return storage_of<C>();
    }

    // Listeners fn(Registry&, Entity) for a C being added / about to be removed (destroy included).
    template <class C>
    Signal& on_construct() {
        return storage_of<C>().on_construct();
    }
    template <class C>
    Signal& on_destroy() {
        return storage_of<C>().on_destroy();
    }

    // The running system's declared access; the frame loop sets it (ecs::AccessScope) around each
    // system. Does nothing unless SFFD_CHECK_ACCESS is defined.
    void set_active_access([[maybe_unused]] const ActiveAccess* active) {
#if defined(SFFD_CHECK_ACCESS)
        m_active = active;
#endif
    }
    const ActiveAccess* active_access() const {
#if defined(SFFD_CHECK_ACCESS)
        return m_active;
#else
        return nullptr;
#endif
    }

    // --- singleton resources (camera settings, editor state, GPU state objects...) --------------
    template <class R, class... Args>
    R& set_resource(Args&&... args) {
        check_write<R>();
        const std::uint32_t id = detail::type_id<R>();
        if (id >= m_resources.size()) m_resources.resize(id + 1);
        auto holder = std::make_unique<Holder<R>>(std::forward<Args>(args)...);
        R& ref = holder->value;
        m_resources[id] = std::move(holder);
        return ref;
    }
    template <class R>
    R* try_resource() {
        check_write<R>();
        return find_resource<R>();
    }
    template <class R>
    const R* try_resource() const {
        check_read<R>();
        return const_cast<Registry*>(this)->find_resource<R>();
    }
    template <class R>
    R& resource() {
        R* r = try_resource<R>();
        assert(r && "resource(): not set");
        return *r;
    }
    template <class R>
    const R& resource() const {
        const R* r = try_resource<R>();
        assert(r && "resource(): not set");
        return *r;
    }
    template <class R>
    void erase_resource() {
        check_write<R>();
        const std::uint32_t id = detail::type_id<R>();
        if (id < m_resources.size()) m_resources[id].reset();
    }

private:
    struct HolderBase {
        virtual ~HolderBase() = default;
    };
    template <class R>
    struct Holder final : HolderBase {
        template <class... Args>
        explicit Holder(Args&&... args) : value(detail::make<R>(std::forward<Args>(args)...)) {}
        R value;
    };

    template <class R>
    R* find_resource() {
        const std::uint32_t id = detail::type_id<R>();
        return id < m_resources.size() && m_resources[id] ? &static_cast<Holder<R>&>(*m_resources[id]).value
                                                          : nullptr;
    }
    template <class C>
    Storage<C>& storage_of() {
        const std::uint32_t id = detail::type_id<C>();
        if (id >= m_storages.size()) m_storages.resize(id + 1);
        if (!m_storages[id]) m_storages[id] = std::make_unique<Storage<C>>(this, &m_tick);
        return static_cast<Storage<C>&>(*m_storages[id]);
    }
    template <class C>
    Storage<C>* find_storage() {
        const std::uint32_t id = detail::type_id<C>();
        return id < m_storages.size() ? static_cast<Storage<C>*>(m_storages[id].get()) : nullptr;
    }
    template <class C>
    const Storage<C>* find_storage() const {
        return const_cast<Registry*>(this)->find_storage<C>();
    }

    std::vector<std::uint32_t> m_generations;
    std::vector<std::uint8_t> m_alive;
    std::vector<std::uint32_t> m_free;
    std::vector<std::unique_ptr<StorageBase>> m_storages;
    std::vector<std::unique_ptr<HolderBase>> m_resources;
    std::vector<Entity> m_pending_destroy;
    std::vector<std::function<void(Registry&)>> m_deferred;
    std::uint64_t m_tick = 0;

    template <class T>
    void check_read() const {
#if defined(SFFD_CHECK_ACCESS)
        if (m_active && m_active->access && m_active->access->declared() &&
            !m_active->access->can_read(detail::type_id<T>()))
            detail::access_violation(m_active->system, "reads", detail::type_name<T>());
#endif
    }
    template <class T>
    void check_write() const {
#if defined(SFFD_CHECK_ACCESS)
        if (m_active && m_active->access && m_active->access->declared() &&
            !m_active->access->can_write(detail::type_id<T>()))
            detail::access_violation(m_active->system, "writes", detail::type_name<T>());
#endif
    }
    template <class T>
    void check_view() const {
        if constexpr (std::is_const_v<T>) check_read<std::remove_const_t<T>>();
        else check_write<T>();
    }
#if defined(SFFD_CHECK_ACCESS)
    const ActiveAccess* m_active = nullptr;
#endif
};

inline void Signal::publish(Registry& registry, Entity e) const {
    if (empty()) return;
    const ActiveAccess* running = registry.active_access();
    registry.set_active_access(nullptr);
    publish_unchecked(registry, e);
    registry.set_active_access(running);
}

// Declares `access` as the running system's for as long as it lives (restores the previous one).
class AccessScope {
public:
    AccessScope(Registry& registry, const ActiveAccess& active)
        : m_registry(registry), m_previous(registry.active_access()) {
        registry.set_active_access(&active);
    }
    ~AccessScope() { m_registry.set_active_access(m_previous); }
    AccessScope(const AccessScope&) = delete;
    AccessScope& operator=(const AccessScope&) = delete;

private:
    Registry& m_registry;
    const ActiveAccess* m_previous;
};

}  // namespace sffd::ecs
