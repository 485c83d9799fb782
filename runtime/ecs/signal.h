// Storage signals (EnTT's on_construct / on_destroy): listeners `fn(Registry&, Entity)` connected to one
// component type's storage, told when a component is added or is about to be removed.
//
//   ecs::Connection c = reg.on_destroy<GpuState>().connect([](ecs::Registry& r, ecs::Entity e) { ... });
//   c.disconnect();  // or let a ScopedConnection do it
//
// A listener may connect or disconnect listeners (itself included) and change the registry while the
// signal runs; listeners connected during a call first run on the next one. A Connection outliving its
// registry is harmless: disconnect() then does nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "runtime/ecs/entity.h"

namespace sffd::ecs {

class Registry;
using Listener = std::function<void(Registry&, Entity)>;

namespace detail {
struct Slots {
    struct Slot {
        std::uint64_t id;
        Listener fn;  // empty once disconnected; compacted when no call is running
    };
    std::vector<Slot> slots;
    std::uint64_t next_id = 1;
    int running = 0;  // nested calls in progress
    void compact() {
        std::erase_if(slots, [](const Slot& s) { return !s.fn; });
    }
};
}  // namespace detail

class Connection {
public:
    Connection() = default;
    Connection(std::weak_ptr<detail::Slots> slots, std::uint64_t id) : m_slots(std::move(slots)), m_id(id) {}
    bool connected() const {
        auto slots = m_slots.lock();
        if (!slots) return false;
        for (const auto& s : slots->slots)
            if (s.id == m_id) return bool(s.fn);
        return false;
    }
    void disconnect() {
        auto slots = m_slots.lock();
        m_slots.reset();
        if (!slots) return;
        for (auto& s : slots->slots)
            if (s.id == m_id) s.fn = nullptr;
        if (slots->running == 0) slots->compact();
    }

private:
    std::weak_ptr<detail::Slots> m_slots;
    std::uint64_t m_id = 0;
};

// Disconnects when it goes out of scope (move-only).
class ScopedConnection {
public:
    ScopedConnection() = default;
    ScopedConnection(Connection c) : m_c(std::move(c)) {}  // NOLINT: implicit from connect()
    ScopedConnection(ScopedConnection&& o) noexcept : m_c(std::exchange(o.m_c, {})) {}
    ScopedConnection& operator=(ScopedConnection&& o) noexcept {
        if (this != &o) {
            m_c.disconnect();
            m_c = std::exchange(o.m_c, {});
        }
        return *this;
    }
    ~ScopedConnection() { m_c.disconnect(); }
    void disconnect() { m_c.disconnect(); }
    bool connected() const { return m_c.connected(); }

private:
    Connection m_c;
};

class Signal {
public:
    Signal() : m_slots(std::make_shared<detail::Slots>()) {}
    Connection connect(Listener fn) {
        const std::uint64_t id = m_slots->next_id++;
        m_slots->slots.push_back({id, std::move(fn)});
        return Connection(m_slots, id);
    }
    bool empty() const { return m_slots->slots.empty(); }
    // Calls every listener. Defined in registry.h: listeners run outside the running system's declared
    // access (runtime/ecs/access.h), since they belong to whoever connected them, not to the system whose
    // emplace, remove or destroy set them off.
    void publish(Registry& registry, Entity e) const;
    void publish_unchecked(Registry& registry, Entity e) const {
        detail::Slots& s = *m_slots;
        const std::size_t n = s.slots.size();  // listeners connected during the call wait for the next
        ++s.running;
        for (std::size_t i = 0; i < n; ++i) {
            Listener fn = s.slots[i].fn;  // a copy: the vector may grow, and the slot be cleared, meanwhile
            if (fn) fn(registry, e);
        }
        if (--s.running == 0) s.compact();
    }

private:
    std::shared_ptr<detail::Slots> m_slots;
};

}  // namespace sffd::ecs
