// Run-time ids and readable names of component and resource types, shared by the registry (one storage
// per id) and declared access (runtime/ecs/access.h), so both name a type the same way.
#pragma once

#include <atomic>
#include <cstdint>
#include <string_view>

namespace sffd::ecs::detail {

inline std::uint32_t next_type_id() {
    static std::atomic<std::uint32_t> counter{0};
    return counter++;
}
template <class T>
std::uint32_t type_id() {
    static const std::uint32_t id = next_type_id();
    return id;
}

// "sffd::render::RenderSettings" -> "render::RenderSettings": the project's namespace is implied, the
// system's is kept. Taken from the compiler's function signature (GCC and Clang spell it "T = ...").
template <class T>
constexpr std::string_view type_name() {
    std::string_view s = __PRETTY_FUNCTION__;
    const auto begin = s.find("T = ") + 4;
    const auto end = s.find_first_of(";]", begin);
    s = s.substr(begin, end - begin);
    if (s.substr(0, 6) == "sffd::") s.remove_prefix(6);
    return s;
}

}  // namespace sffd::ecs::detail
