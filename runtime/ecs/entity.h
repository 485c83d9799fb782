// Entity: a plain id, index + generation. A destroyed entity's index is reused with a new generation,
// so a stale handle is detected by Registry::valid() instead of silently aliasing a new entity
// (sokol's handle scheme, EnTT's entity type).
#pragma once

#include <cstdint>
#include <functional>

namespace sffd::ecs {

struct Entity {
    static constexpr std::uint32_t null_index = 0xffffffffu;

    std::uint32_t index = null_index;
    std::uint32_t generation = 0;

    constexpr explicit operator bool() const { return index != null_index; }
    constexpr bool operator==(const Entity&) const = default;
    constexpr std::uint64_t bits() const { return (std::uint64_t(generation) << 32) | index; }
    static constexpr Entity from_bits(std::uint64_t b) { return {std::uint32_t(b), std::uint32_t(b >> 32)}; }
};

inline constexpr Entity null_entity{};

}  // namespace sffd::ecs

template <>
struct std::hash<sffd::ecs::Entity> {
    std::size_t operator()(const sffd::ecs::Entity& e) const noexcept {
        return std::hash<std::uint64_t>{}(e.bits());
    }
};
