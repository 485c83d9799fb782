#include "systems/gaussian/gaussian_scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/ply.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_io.h"

namespace sffd::gaussian {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kKey = "gaussians";

std::string lower_ext(const fs::path& p) {
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

// The first `bytes` of a file (a glTF's JSON, or a GLB's JSON chunk, comes first).
std::string head(const fs::path& path, std::size_t bytes) {
    std::ifstream in(path, std::ios::binary);
    std::string s(bytes, '\0');
    in.read(s.data(), std::streamsize(bytes));
    s.resize(std::size_t(std::max<std::streamsize>(in.gcount(), 0)));
    return s;
}

// Strict JSON readers: errors say where.
glm::dvec3 vec3_at(const json& j, const char* key, glm::dvec3 fallback, const std::string& where) {
    if (!j.contains(key)) return fallback;
    const json& v = j[key];
    if (!v.is_array() || v.size() != 3) throw std::runtime_error(where + ": '" + key + "' must be [x, y, z]");
    glm::dvec3 out;
    for (int i = 0; i < 3; ++i) {
        const json& e = v[std::size_t(i)];
        if (!e.is_number() || !std::isfinite(e.get<double>())) throw std::runtime_error(where + ": '" + key + "' has a non-finite or non-numeric entry");
        out[i] = e.get<double>();
    }
    return out;
}

Transform transform_from(const json& j, const std::string& where) {
    Transform t;
    if (!j.is_object()) throw std::runtime_error(where + ": 'transform' must be an object");
    t.translation = vec3_at(j, "translation", t.translation, where + " transform");
    t.scale = vec3_at(j, "scale", t.scale, where + " transform");
    if (j.contains("rotation")) {
        const json& r = j["rotation"];
        if (!r.is_array() || r.size() != 4) throw std::runtime_error(where + " transform: 'rotation' must be [x, y, z, w]");
        double q[4];
        for (int i = 0; i < 4; ++i) {
            if (!r[std::size_t(i)].is_number() || !std::isfinite(r[std::size_t(i)].get<double>()))
                throw std::runtime_error(where + " transform: 'rotation' has a non-finite or non-numeric entry");
            q[i] = r[std::size_t(i)].get<double>();
        }
        const glm::dquat rot(q[3], q[0], q[1], q[2]);
        if (!(glm::length(rot) > 1e-12)) throw std::runtime_error(where + " transform: 'rotation' is a zero quaternion");
        t.rotation = glm::normalize(rot);
    }
    return t;
}

json transform_json(const Transform& t) {
    return {{"translation", {t.translation.x, t.translation.y, t.translation.z}},
            {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}},
            {"scale", {t.scale.x, t.scale.y, t.scale.z}}};
}

}  // namespace

bool is_gaussian_scene_file(const fs::path& path) {
    const std::string e = lower_ext(path);
    if (e == ".splat" || e == ".spz") return true;
    if (e == ".ply") {
        auto r = ply::Reader::open(path);
        if (!r) return false;
        const int v = r->header().find("vertex");
        return v >= 0 && is_gaussian_element(r->header().elements[std::size_t(v)]);
    }
    if (e == ".glb" || e == ".gltf") {
        const std::string h = head(path, std::size_t(4) << 20);
        return h.find("KHR_gaussian_splatting") != std::string::npos && h.find("SFFD_scene") == std::string::npos;
    }
    return false;
}

Result<ecs::Entity> load_gaussian_entity(ecs::Registry& registry, const fs::path& path) {
    auto cloud = read_gaussians(path);
    if (!cloud) return cloud.error();
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    if (ec) absolute = path;
    const ecs::Entity e = registry.create();
    registry.emplace<Name>(e, Name{path.stem().string()});
    registry.emplace<Transform>(e, Transform{});
    registry.emplace<GaussianSource>(e, GaussianSource{absolute.lexically_normal()});
    registry.emplace<GaussianCloud>(e, std::move(*cloud));
    return e;
}

Result<std::string> save_gaussian_extension(const ecs::Registry& registry, const std::function<int(ecs::Entity)>& id_of,
                                            const fs::path& scene_dir) {
    json clouds = json::array();
    std::vector<ecs::Entity> entities;
    registry.each_entity([&](ecs::Entity e) {
        if (registry.has<GaussianCloud>(e)) entities.push_back(e);
    });
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const ecs::Entity e = entities[i];
        const Name* name = registry.try_get<Name>(e);
        const std::string label = name && !name->value.empty() ? name->value : "gaussians" + std::to_string(i);
        fs::path file;
        if (const GaussianSource* src = registry.try_get<GaussianSource>(e); src && !src->path.empty()) {
            file = src->path;
        } else {  // made in memory: written beside the scene
            file = scene_dir / (label + ".gaussians.ply");
            GaussianCloud baked = registry.get<GaussianCloud>(e);
            bake_sh_frames(baked);
            if (Status s = write_ply(file, baked); !s) return s.error();
        }
        std::error_code ec;
        const fs::path base = scene_dir.empty() ? fs::current_path(ec) : fs::absolute(scene_dir, ec);
        fs::path rel = ec ? fs::path() : fs::absolute(file, ec).lexically_relative(base);
        if (ec || rel.empty()) rel = file;
        json c = {{"name", label}, {"file", rel.generic_string()}};
        if (const Transform* t = registry.try_get<Transform>(e)) c["transform"] = transform_json(*t);
        json lattices = json::array();
        if (const Deformers* d = registry.try_get<Deformers>(e))
            for (ecs::Entity l : d->lattices)
                if (const int id = id_of(l); id >= 0 && registry.has<Lattice>(l)) lattices.push_back(id);
        c["lattices"] = lattices;
        clouds.push_back(std::move(c));
    }
    if (clouds.empty()) return std::string();
    return json{{"version", 1}, {"clouds", clouds}}.dump();
}

Status load_gaussian_extension(ecs::Registry& registry, std::string_view text, const std::function<ecs::Entity(int)>& entity_of,
                               const fs::path& scene_dir) {
    const json j = json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) return make_error("not a JSON object");
    if (!j.contains("version") || !j["version"].is_number_integer() || j["version"].get<int>() != 1)
        return make_error("'version' must be 1");
    if (!j.contains("clouds") || !j["clouds"].is_array()) return make_error("'clouds' must be an array");
    std::vector<ecs::Entity> created;
    auto undo = [&](Error e) -> Status {
        for (ecs::Entity c : created)
            if (registry.valid(c)) registry.destroy(c);
        return e;
    };
    try {
        for (std::size_t i = 0; i < j["clouds"].size(); ++i) {
            const json& c = j["clouds"][i];
            const std::string where = "clouds[" + std::to_string(i) + "]";
            if (!c.is_object()) throw std::runtime_error(where + ": must be an object");
            if (!c.contains("file") || !c["file"].is_string() || c["file"].get<std::string>().empty())
                throw std::runtime_error(where + ": 'file' must be a non-empty string (a Gaussian file)");
            fs::path file = c["file"].get<std::string>();
            if (file.is_relative()) file = scene_dir / file;
            std::vector<ecs::Entity> lattices;
            if (c.contains("lattices")) {
                if (!c["lattices"].is_array()) throw std::runtime_error(where + ": 'lattices' must be an array of lattice ids");
                for (const json& id : c["lattices"]) {
                    if (!id.is_number_integer()) throw std::runtime_error(where + ": 'lattices' must be an array of lattice ids");
                    const ecs::Entity l = entity_of(id.get<int>());
                    if (l == ecs::null_entity || !registry.has<Lattice>(l))
                        throw std::runtime_error(where + ": 'lattices' names " + std::to_string(id.get<int>()) + ", which is not a lattice of this scene");
                    lattices.push_back(l);
                }
            }
            const Transform t = c.contains("transform") ? transform_from(c["transform"], where) : Transform{};
            if (!fs::exists(file)) throw std::runtime_error(where + ": " + file.string() + ": no such Gaussian file");
            auto e = load_gaussian_entity(registry, file);
            if (!e) throw std::runtime_error(where + ": " + e.message());
            created.push_back(*e);
            registry.get<Transform>(*e) = t;
            if (c.contains("name")) {
                if (!c["name"].is_string()) throw std::runtime_error(where + ": 'name' must be a string");
                registry.get<Name>(*e).value = c["name"].get<std::string>();
            }
            if (!lattices.empty()) registry.emplace<Deformers>(*e, Deformers{lattices});
        }
    } catch (const std::exception& ex) {
        return undo(make_error(ex.what()));
    }
    return {};
}

void register_gaussian_scene_hooks() {
    register_scene_file_extension(kKey, save_gaussian_extension, load_gaussian_extension);
    register_scene_file_loader(
        kKey, [](const fs::path& p) { return is_gaussian_scene_file(p); },
        [](ecs::Registry& registry, const fs::path& p) -> Status {
            auto e = load_gaussian_entity(registry, p);
            if (!e) return e.error();
            if (registry.count<Camera>() == 0) {
                const GaussianCloud& g = registry.get<GaussianCloud>(*e);
                glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
                for (const glm::vec3& q : g.positions) {
                    lo = glm::min(lo, g.origin + glm::dvec3(q));
                    hi = glm::max(hi, g.origin + glm::dvec3(q));
                }
                if (lo.x <= hi.x) assets::add_default_view(registry, lo, hi, glm::dvec3(0.3, 0.3, 1.0));
            }
            return {};
        });
}

void unregister_gaussian_scene_hooks() {
    unregister_scene_extension(kKey);
    unregister_scene_file_loader(kKey);
}

}  // namespace sffd::gaussian
