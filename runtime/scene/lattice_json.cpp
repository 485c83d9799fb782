#include "runtime/scene/lattice_json.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>

#include <nlohmann/json.hpp>

namespace sffd {

using nlohmann::json;

namespace {

// The three numbers a[at], a[at+1], a[at+2] (a is an array holding them): finite and at most
// kMaxLatticeCoordinate in magnitude. `what` names them and `shape` says what they must be.
Result<glm::dvec3> xyz(const json& a, std::size_t at, const std::string& where, const std::string& what,
                       const char* shape) {
    glm::dvec3 v(0.0);
    for (int i = 0; i < 3; ++i) {
        const json& e = a[at + std::size_t(i)];
        if (!e.is_number()) return make_error(where + ": " + what + " must be " + shape);
        v[i] = e.get<double>();
        if (!std::isfinite(v[i])) return make_error(where + ": " + what + " is not finite");
        if (std::abs(v[i]) > kMaxLatticeCoordinate)
            return make_error(where + ": " + what + " is larger than 1e30 in magnitude");
    }
    return v;
}

constexpr const char* kVec3 = "an array of 3 numbers";

Result<glm::dvec3> vec3(const json& j, const std::string& where, const std::string& what) {
    if (!j.is_array() || j.size() != 3) return make_error(where + ": " + what + " must be " + kVec3);
    return xyz(j, 0, where, what, kVec3);
}

// `count` points under `key`: [[x,y,z], ...], or flat [x0,y0,z0, x1,y1,z1, ...] as older scene files
// store them (told apart by the first entry).
Result<std::vector<glm::dvec3>> points(const json& j, const std::string& where, const std::string& key,
                                       std::size_t count) {
    if (!j.is_array()) return make_error(where + ": \"" + key + "\" must be an array of [x,y,z]");
    const bool flat = !j.empty() && !j.front().is_array();
    if (flat && j.size() != 3 * count)
        return make_error(where + ": \"" + key + "\" must hold " + std::to_string(3 * count) + " numbers (" +
                          std::to_string(count) + " points x, y, z in a row), got " +
                          std::to_string(j.size()));
    if (!flat && j.size() != count)
        return make_error(where + ": expected " + std::to_string(count) + " " + key +
                          " ((l+1)(m+1)(n+1)), got " + std::to_string(j.size()));
    std::vector<glm::dvec3> out;
    out.reserve(count);
    for (std::size_t c = 0; c < count; ++c) {
        const std::string what = key + "[" + std::to_string(c) + "]";
        auto v = flat ? xyz(j, 3 * c, where, what, "3 numbers x, y, z") : vec3(j[c], where, what);
        if (!v) return v.error();
        out.push_back(*v);
    }
    return out;
}

// The points stored under `key` or under its older scene-file name `legacy` (at most one of the two) into
// `out`, which is left alone when neither is given or the value is null.
Status read_points(const json& j, const std::string& where, const char* key, const char* legacy,
                   std::size_t count, std::vector<glm::dvec3>& out) {
    const bool has_key = j.contains(key), has_legacy = j.contains(legacy);
    if (has_key && has_legacy)
        return make_error(where + ": both \"" + key + "\" and \"" + legacy +
                          "\" given (the same points under two names; keep \"" + key + "\")");
    if (!has_key && !has_legacy) return {};
    const char* name = has_key ? key : legacy;
    if (j[name].is_null()) return {};
    auto p = points(j[name], where, name, count);
    if (!p) return p.error();
    out = std::move(*p);
    return {};
}

json array3(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

json point_list(const std::vector<glm::dvec3>& pts) {
    json a = json::array();
    for (const auto& p : pts) a.push_back(array3(p));
    return a;
}

}  // namespace

Result<Lattice> lattice_from_json(const json& j, const std::string& where) {
    if (!j.is_object()) return make_error(where + ": expected a JSON object");
    for (const auto& item : j.items()) {
        const std::string& key = item.key();
        static constexpr const char* kKeys[] = {
            "origin",         "axes", "divisions", "basis", "rest_control_points",
            "control_points", "rest", "current"};
        if (std::none_of(std::begin(kKeys), std::end(kKeys), [&](const char* k) { return key == k; }))
            return make_error(
                where + ": unknown key \"" + key.substr(0, 80) +
                "\" (expected origin, axes, divisions, basis, rest_control_points, control_points)");
    }
    for (const char* key : {"origin", "axes", "divisions"})
        if (!j.contains(key)) return make_error(where + ": missing \"" + key + "\"");
    Lattice l;
    auto origin = vec3(j["origin"], where, "\"origin\"");
    if (!origin) return origin.error();
    l.origin = *origin;
    const json& axes = j["axes"];
    if (!axes.is_array() || axes.size() != 3)
        return make_error(where + ": \"axes\" must be 3 vectors [S, T, U]");
    for (int a = 0; a < 3; ++a) {
        auto v = vec3(axes[std::size_t(a)], where, std::string("axis ") + "STU"[a]);
        if (!v) return v.error();
        l.axes[std::size_t(a)] = *v;
    }
    const json& div = j["divisions"];
    if (!div.is_array() || div.size() != 3) return make_error(where + ": \"divisions\" must be [l, m, n]");
    for (int a = 0; a < 3; ++a) {
        const json& d = div[std::size_t(a)];
        // Whole numbers written as 4.0 count: older scene files were read that way.
        if (!d.is_number() || d.get<double>() != std::floor(d.get<double>()))
            return make_error(where + ": \"divisions\" must be integers (got " + d.dump().substr(0, 40) +
                              ")");
        const double v = d.get<double>();
        if (!(v >= 1 && v <= kMaxLatticeDivisions))
            return make_error(where + ": divisions must be between 1 and " +
                              std::to_string(kMaxLatticeDivisions) + " (got " + d.dump() + ")");
        l.divisions[a] = int(v);
    }
    if (j.contains("basis")) {
        if (!j["basis"].is_string())
            return make_error(where + ": \"basis\" must be \"bernstein\" or \"bspline\"");
        const std::string b = j["basis"].get<std::string>();
        if (b == "bernstein") l.basis = LatticeBasis::bernstein;
        else if (b == "bspline") l.basis = LatticeBasis::bspline;
        else
            return make_error(where + ": unknown basis \"" + b.substr(0, 80) +
                              "\" (expected \"bernstein\" or \"bspline\")");
    }
    // The box first, before grids are built from it.
    l.rest = rest_grid(l.origin, l.axes, l.divisions);
    l.current = l.rest;
    if (Status s = validate_lattice(l, where); !s) return s.error();
    if (Status s = read_points(j, where, "rest_control_points", "rest", l.size(), l.rest); !s)
        return s.error();
    l.current = l.rest;
    if (Status s = read_points(j, where, "control_points", "current", l.size(), l.current); !s)
        return s.error();
    if (Status s = validate_lattice(l, where); !s) return s.error();
    return l;
}

json lattice_to_json(const Lattice& l) {
    json j;
    j["origin"] = array3(l.origin);
    j["axes"] = json::array({array3(l.axes[0]), array3(l.axes[1]), array3(l.axes[2])});
    j["divisions"] = json::array({l.divisions.x, l.divisions.y, l.divisions.z});
    j["basis"] = l.basis == LatticeBasis::bspline ? "bspline" : "bernstein";
    j["control_points"] = point_list(l.current);
    // Compared bit for bit (not to a tolerance, and -0.0 differs from 0.0): what is left out is rebuilt
    // by rest_grid() on reading, exactly.
    const auto grid = rest_grid(l.origin, l.axes, l.divisions);
    if (grid.size() != l.rest.size() ||
        (!grid.empty() && std::memcmp(grid.data(), l.rest.data(), grid.size() * sizeof(glm::dvec3)) != 0))
        j["rest_control_points"] = point_list(l.rest);
    return j;
}

}  // namespace sffd
