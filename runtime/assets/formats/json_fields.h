// Reading typed values out of a parsed JSON manifest (lod-meta.json, Potree 2's metadata.json): each
// returns false instead of throwing, so a reader turns a wrong type into one message naming its file.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

namespace sffd::assets::json_fields {

// The largest whole number a JSON writer in JavaScript can state exactly.
inline constexpr std::uint64_t kMaxInteger = (std::uint64_t(1) << 53) - 1;

// o[key], or a null value when o is not an object or has no such key.
inline const nlohmann::json& member(const nlohmann::json& o, const char* key) {
    static const nlohmann::json null;
    if (!o.is_object()) return null;
    auto it = o.find(key);
    return it == o.end() ? null : *it;
}

// A whole number in [0, kMaxInteger]; 3.0 counts, as a JavaScript writer may write it so.
inline bool whole(const nlohmann::json& j, std::uint64_t& out) {
    if (j.is_number_unsigned() || (j.is_number_integer() && j.get<long long>() >= 0)) {
        out = j.get<std::uint64_t>();
        return out <= kMaxInteger;
    }
    if (j.is_number_float()) {
        const double d = j.get<double>();
        if (!(d >= 0) || d > double(kMaxInteger) || std::floor(d) != d) return false;
        out = std::uint64_t(d);
        return true;
    }
    return false;
}

// An array of three finite numbers.
inline bool vec3(const nlohmann::json& j, glm::dvec3& out) {
    if (!j.is_array() || j.size() != 3) return false;
    for (int a = 0; a < 3; ++a) {
        if (!j[std::size_t(a)].is_number()) return false;
        out[a] = j[std::size_t(a)].get<double>();
        if (!std::isfinite(out[a])) return false;
    }
    return true;
}

}  // namespace sffd::assets::json_fields
