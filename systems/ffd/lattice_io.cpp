#include "systems/ffd/lattice_io.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include <nlohmann/json.hpp>

#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

using nlohmann::json;

namespace {

// Control points larger than this overflow when the basis sums them (1e308 passed as finite and deformed
// to inf); 1e30 leaves room for every product and sum in double and in the float paths' offsets.
constexpr double kMaxCoordinate = 1e30;

// Reads a [x,y,z] array of finite numbers; `what` names it in messages.
Result<glm::dvec3> vec3(const json& j, const std::string& name, const std::string& what) {
    if (!j.is_array() || j.size() != 3) return make_error(name + ": " + what + " must be an array of 3 numbers");
    glm::dvec3 v(0.0);
    for (int a = 0; a < 3; ++a) {
        if (!j[a].is_number()) return make_error(name + ": " + what + " must be an array of 3 numbers");
        v[a] = j[a].get<double>();
        if (!std::isfinite(v[a])) return make_error(name + ": " + what + " is not finite");
        if (std::abs(v[a]) > kMaxCoordinate) return make_error(name + ": " + what + " is larger than 1e30 in magnitude");
    }
    return v;
}

Result<std::vector<glm::dvec3>> points(const json& j, const std::string& name, const std::string& key, std::size_t want) {
    if (!j.is_array()) return make_error(name + ": \"" + key + "\" must be an array of [x,y,z]");
    if (j.size() != want)
        return make_error(name + ": expected " + std::to_string(want) + " " + key + " ((l+1)(m+1)(n+1)), got " +
                          std::to_string(j.size()));
    std::vector<glm::dvec3> out;
    out.reserve(want);
    for (std::size_t c = 0; c < j.size(); ++c) {
        auto v = vec3(j[c], name, key + "[" + std::to_string(c) + "]");
        if (!v) return v.error();
        out.push_back(*v);
    }
    return out;
}

}  // namespace

Result<Lattice> parse_lattice_json(std::string_view text, const std::string& name) {
    if (Status s = check_json_depth(text, name); !s) return s.error();
    json j;
    try {
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {  // parse errors, number overflow (1e999)
        return make_error(name + ": malformed JSON (" + std::string(e.what()) + ")");
    }
    if (!j.is_object()) return make_error(name + ": expected a JSON object");
    // A misspelt key ("controlpoints") would silently deform nothing: every key must be known.
    for (const auto& item : j.items()) {
        const std::string& key = item.key();
        static constexpr const char* kKeys[] = {"origin", "axes", "divisions", "basis", "rest_control_points", "control_points"};
        if (std::none_of(std::begin(kKeys), std::end(kKeys), [&](const char* k) { return key == k; }))
            return make_error(name + ": unknown key \"" + key.substr(0, 80) +
                              "\" (expected origin, axes, divisions, basis, rest_control_points, control_points)");
    }
    for (const char* key : {"origin", "axes", "divisions"})
        if (!j.contains(key)) return make_error(name + ": missing \"" + key + "\"");
    Lattice l;
    auto origin = vec3(j["origin"], name, "\"origin\"");
    if (!origin) return origin.error();
    l.origin = *origin;
    const json& axes = j["axes"];
    if (!axes.is_array() || axes.size() != 3) return make_error(name + ": \"axes\" must be 3 vectors [S, T, U]");
    for (int a = 0; a < 3; ++a) {
        auto v = vec3(axes[a], name, std::string("axis ") + "STU"[a]);
        if (!v) return v.error();
        l.axes[a] = *v;
    }
    const json& div = j["divisions"];
    if (!div.is_array() || div.size() != 3) return make_error(name + ": \"divisions\" must be [l, m, n]");
    for (int a = 0; a < 3; ++a) {
        if (!div[a].is_number_integer()) return make_error(name + ": \"divisions\" must be integers");
        const long long d = div[a].get<long long>();
        if (d < 1 || d > kMaxDivisions)
            return make_error(name + ": divisions must be between 1 and " + std::to_string(kMaxDivisions) + " (got " +
                              std::to_string(d) + ")");
        l.divisions[a] = int(d);
    }
    if (j.contains("basis")) {
        if (!j["basis"].is_string()) return make_error(name + ": \"basis\" must be \"bernstein\" or \"bspline\"");
        const std::string b = j["basis"].get<std::string>();
        if (b == "bernstein") l.basis = LatticeBasis::bernstein;
        else if (b == "bspline") l.basis = LatticeBasis::bspline;
        else return make_error(name + ": unknown basis \"" + b + "\" (expected \"bernstein\" or \"bspline\")");
    }
    // Check the box before building grids from it.
    {
        Lattice probe = l;
        probe.rest = probe.current = rest_grid(l.origin, l.axes, l.divisions);
        if (Status s = validate(probe, name); !s) return s.error();
    }
    l.rest = rest_grid(l.origin, l.axes, l.divisions);
    if (j.contains("rest_control_points")) {
        auto r = points(j["rest_control_points"], name, "rest_control_points", l.size());
        if (!r) return r.error();
        l.rest = std::move(*r);
    }
    l.current = l.rest;
    if (j.contains("control_points") && !j["control_points"].is_null()) {
        auto c = points(j["control_points"], name, "control_points", l.size());
        if (!c) return c.error();
        l.current = std::move(*c);
    }
    if (Status s = validate(l, name); !s) return s.error();
    return l;
}

Result<Lattice> load_lattice(const std::filesystem::path& path) {
    // Regular files only (--lattice /dev/zero or a FIFO would read forever), within the JSON budget.
    auto text = read_file(path, kMaxJsonFileBytes);
    if (!text) return text.error();
    return parse_lattice_json(*text, path.string());
}

std::string lattice_to_json(const Lattice& l) {
    auto arr = [](const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); };
    json j;
    j["origin"] = arr(l.origin);
    j["axes"] = json::array({arr(l.axes[0]), arr(l.axes[1]), arr(l.axes[2])});
    j["divisions"] = json::array({l.divisions.x, l.divisions.y, l.divisions.z});
    j["basis"] = l.basis == LatticeBasis::bspline ? "bspline" : "bernstein";
    json cp = json::array();
    for (const auto& p : l.current) cp.push_back(arr(p));
    j["control_points"] = std::move(cp);
    if (!rest_is_uniform(l)) {
        json rp = json::array();
        for (const auto& p : l.rest) rp.push_back(arr(p));
        j["rest_control_points"] = std::move(rp);
    }
    return j.dump(1) + "\n";
}

Status save_lattice(const std::filesystem::path& path, const Lattice& l) {
    if (Status s = validate(l, path.string()); !s) return s;
    return write_file_atomic(path, lattice_to_json(l));
}

}  // namespace sffd::ffd
