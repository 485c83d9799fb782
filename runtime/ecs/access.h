// Declared access (flecs's system signatures): what a system reads and writes, as component and
// resource types.
//
//   s.add(Phase::deformation, "ffd", ffd_system,
//         ecs::reads<SplatCloud, Deformers, Lattice, Transform>().writes<DeformedSplats>());
//
// Builds that define SFFD_CHECK_ACCESS (Debug and sanitizer builds; the CMake option of that name) check it:
// while a system runs (an AccessScope is open on the registry), reading a type needs reads<> or writes<>,
// and mutable access (non-const get/try_get/view/resource, patch, emplace, remove, set_resource) needs
// writes<>; anything else prints the system and the type and aborts. The declarations are also the
// README's frame table (`splatffd schedule --markdown`). Entity creation and destruction, and deferred
// commands (they run at flush, between phases), are not part of a declaration.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/ecs/type_info.h"

namespace sffd::ecs {

struct TypeRef {
    std::uint32_t id;
    std::string_view name;
    bool operator==(const TypeRef& o) const { return id == o.id; }
};

class Access {
public:
    template <class... T>
    Access& reads() & {
        m_declared = true;
        (add<T>(m_reads), ...);
        return *this;
    }
    template <class... T>
    Access&& reads() && {
        return std::move(reads<T...>());
    }
    template <class... T>
    Access& writes() & {
        m_declared = true;
        (add<T>(m_writes), ...);
        return *this;
    }
    template <class... T>
    Access&& writes() && {
        return std::move(writes<T...>());
    }

    // Reads exclude what is also written (a write implies the read).
    const std::vector<TypeRef>& read_types() const { return m_reads; }
    const std::vector<TypeRef>& write_types() const { return m_writes; }
    bool declared() const { return m_declared; }
    bool can_read(std::uint32_t id) const { return contains(m_reads, id) || contains(m_writes, id); }
    bool can_write(std::uint32_t id) const { return contains(m_writes, id); }

private:
    template <class T>
    void add(std::vector<TypeRef>& to) {
        const TypeRef t{detail::type_id<T>(), detail::type_name<T>()};
        if (std::find(to.begin(), to.end(), t) == to.end()) to.push_back(t);
        if (&to == &m_writes) std::erase(m_reads, t);
        else if (contains(m_writes, t.id)) std::erase(m_reads, t);
    }
    static bool contains(const std::vector<TypeRef>& v, std::uint32_t id) {
        return std::any_of(v.begin(), v.end(), [&](const TypeRef& t) { return t.id == id; });
    }
    std::vector<TypeRef> m_reads;
    std::vector<TypeRef> m_writes;
    bool m_declared = false;
};

template <class... T>
Access reads() {
    return Access().reads<T...>();
}
template <class... T>
Access writes() {
    return Access().writes<T...>();
}
// A system that touches no component or resource (declared, so the check refuses any access).
inline Access no_access() { return Access().reads<>(); }

// The system whose access is being checked, while one runs.
struct ActiveAccess {
    std::string_view system;
    const Access* access = nullptr;
};

namespace detail {
// Prints the violation and aborts; with SFFD_ACCESS_WARN=1 in the environment it prints each distinct
// violation once and carries on, so one run lists every missing declaration.
inline void access_violation(std::string_view system, std::string_view verb, std::string_view type) {
    static const bool warn_only = [] {
        const char* v = std::getenv("SFFD_ACCESS_WARN");
        return v && *v && *v != '0';
    }();
    char line[512];
    std::snprintf(line, sizeof line,
                  "access check: system '%.*s' %.*s %.*s, which it does not declare (declare it where the "
                  "system is added to the schedule)\n",
                  int(system.size()), system.data(), int(verb.size()), verb.data(), int(type.size()),
                  type.data());
    if (warn_only) {
        static std::mutex mutex;
        static std::set<std::string> seen;
        const std::lock_guard lock(mutex);
        if (seen.insert(line).second) std::fputs(line, stderr);
        return;
    }
    std::fputs(line, stderr);
    std::fflush(stderr);
    std::abort();
}
}  // namespace detail

}  // namespace sffd::ecs
