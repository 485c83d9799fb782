#include "runtime/assets/scene.h"

#include <algorithm>
#include <cmath>
#include <list>
#include <map>
#include <tuple>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/import.h"
#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice_json.h"
#include "runtime/scene/point_subset.h"

namespace sffd {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kSceneVersion = 1;

json vec3(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }
json vec3f(const glm::vec3& v) { return json::array({v.x, v.y, v.z}); }

json transform_json(const Transform& t) {
    return {{"translation", vec3(t.translation)},
            {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}},
            {"scale", vec3(t.scale)}};
}

// Strict readers: every number must be present, numeric and finite (hostile files).
struct Reader {
    std::string where;
    double num(const json& j, const char* key) const {
        if (!j.is_object() || !j.contains(key) || !j[key].is_number())
            throw std::runtime_error(where + ": '" + key + "' must be a number");
        const double v = j[key].get<double>();
        if (!std::isfinite(v)) throw std::runtime_error(where + ": '" + key + "' is not finite");
        return v;
    }
    double num_or(const json& j, const char* key, double def) const {
        return j.is_object() && j.contains(key) ? num(j, key) : def;
    }
    glm::dvec3 v3(const json& j, const char* key) const {
        if (!j.is_object() || !j.contains(key) || !j[key].is_array() || j[key].size() != 3)
            throw std::runtime_error(where + ": '" + key + "' must be [x, y, z]");
        glm::dvec3 v;
        for (int i = 0; i < 3; ++i) {
            const json& e = j[key][static_cast<std::size_t>(i)];
            if (!e.is_number() || !std::isfinite(e.get<double>()))
                throw std::runtime_error(where + ": '" + key + "' has a non-finite or non-numeric entry");
            v[i] = e.get<double>();
        }
        return v;
    }
    glm::dvec3 v3_or(const json& j, const char* key, glm::dvec3 def) const {
        return j.is_object() && j.contains(key) ? v3(j, key) : def;
    }
    int integer(const json& j, const char* key) const {
        if (!j.is_object() || !j.contains(key) || !j[key].is_number_integer())
            throw std::runtime_error(where + ": '" + key + "' must be an integer");
        const auto v = j[key].get<long long>();
        if (v < -1 || v > 1'000'000'000) throw std::runtime_error(where + ": '" + key + "' out of range");
        return static_cast<int>(v);
    }
    std::string str_or(const json& j, const char* key, const std::string& def) const {
        if (!j.is_object() || !j.contains(key)) return def;
        if (!j[key].is_string()) throw std::runtime_error(where + ": '" + key + "' must be a string");
        return j[key].get<std::string>();
    }
    Transform transform(const json& j) const {
        Transform t;
        if (!j.is_object() || !j.contains("transform")) return t;
        const json& tj = j["transform"];
        if (!tj.is_object())
            throw std::runtime_error(where +
                                     ": 'transform' must be an object {translation, rotation, scale}");
        t.translation = v3_or(tj, "translation", glm::dvec3(0.0));
        t.scale = v3_or(tj, "scale", glm::dvec3(1.0));
        if (t.scale.x == 0.0 || t.scale.y == 0.0 || t.scale.z == 0.0)
            throw std::runtime_error(
                where + ": 'transform' 'scale' has a zero component (the transform would not be invertible)");
        if (tj.contains("rotation")) {
            const json& q = tj["rotation"];
            if (!q.is_array() || q.size() != 4)
                throw std::runtime_error(where + ": rotation must be [x, y, z, w]");
            double c[4];
            for (std::size_t i = 0; i < 4; ++i) {
                if (!q[i].is_number() || !std::isfinite(q[i].get<double>()))
                    throw std::runtime_error(where + ": rotation is not finite");
                c[i] = q[i].get<double>();
            }
            t.rotation = glm::dquat(c[3], c[0], c[1], c[2]);
            const double len = glm::length(t.rotation);
            if (!(len > 1e-12) || !std::isfinite(len))
                throw std::runtime_error(where + ": 'transform' 'rotation' is a zero quaternion");
        }
        return t;
    }
};

std::string name_of(const ecs::Registry& r, ecs::Entity e, const std::string& fallback) {
    const Name* n = r.try_get<Name>(e);
    return n && !n->value.empty() ? n->value : fallback;
}

Status load_scene_file(ecs::Registry& r, const fs::path& path) {
    auto contents = assets::read_gltf(path);
    if (!contents) return contents.error();
    const std::string src = path.string();
    std::unordered_map<int, ecs::Entity> by_id;
    std::vector<ecs::Entity> created;
    auto rollback = [&](Error e) -> Status {
        for (ecs::Entity x : created)
            if (r.valid(x)) r.destroy(x);
        return e;
    };
    bool have_camera = false;
    try {
        json scene =
            contents->sffd_scene_json.empty() ? json::object() : json::parse(contents->sffd_scene_json);
        if (!scene.is_object()) return make_error(src + ": SFFD_scene must be an object");
        if (scene.contains("version") &&
            (!scene["version"].is_number_integer() || scene["version"].get<int>() > kSceneVersion))
            return make_error(src + ": SFFD_scene version not supported (this build reads version " +
                              std::to_string(kSceneVersion) + ")");
        Reader rd{src + ": SFFD_scene"};
        auto remember = [&](int id, ecs::Entity e) {
            if (id >= 0 && !by_id.emplace(id, e).second)
                throw std::runtime_error(src + ": SFFD_scene: duplicate id " + std::to_string(id));
        };
        for (auto& c : contents->clouds) {
            const ecs::Entity e = r.create();
            created.push_back(e);
            r.emplace<Name>(e, Name{c.name});
            r.emplace<Transform>(e, c.transform);
            r.emplace<SplatCloud>(e, std::move(c.cloud));
            r.emplace<SplatMaterial>(e, c.material);
            if (!c.flags.bits.empty()) r.emplace<PointFlags>(e, std::move(c.flags));
            if (!c.weights.values.empty()) r.emplace<PointWeights>(e, std::move(c.weights));
            remember(c.id, e);
        }
        if (!contents->other.positions.empty()) {
            // Ordinary meshes or points in a glTF file become one more cloud.
            auto cloud = assets::make_splat_cloud(contents->other, {});
            if (!cloud) return rollback(cloud.error());
            const ecs::Entity e = r.create();
            created.push_back(e);
            r.emplace<Name>(e, Name{path.stem().string()});
            r.emplace<Transform>(e, Transform{});
            r.emplace<SplatCloud>(e, std::move(*cloud));
            r.emplace<SplatMaterial>(e, contents->other.splat_material);
        }
        if (scene.contains("lattices")) {
            if (!scene["lattices"].is_array())
                throw std::runtime_error(src + ": SFFD_scene: 'lattices' must be an array");
            for (json& lj : scene["lattices"]) {
                // The entry's own keys are read here and taken out; what is left is the lattice's JSON
                // form, read by the one lattice reader (lattice files use it too) with its rules.
                Reader lr{src + ": SFFD_scene lattice"};
                const std::string name = lr.str_or(lj, "name", "lattice");
                const Transform transform = lr.transform(lj);
                const int id = lr.integer(lj, "id");
                if (lj.is_object())
                    for (const char* key : {"id", "name", "transform"}) lj.erase(key);
                auto l = lattice_from_json(lj, lr.where);
                if (!l) throw std::runtime_error(l.message());
                const ecs::Entity e = r.create();
                created.push_back(e);
                r.emplace<Name>(e, Name{name});
                r.emplace<Transform>(e, transform);
                r.emplace<Lattice>(e, std::move(*l));
                remember(id, e);
            }
        }
        if (scene.contains("deformers")) {
            if (!scene["deformers"].is_array())
                throw std::runtime_error(src + ": SFFD_scene: 'deformers' must be an array");
            for (const json& dj : scene["deformers"]) {
                const int cid = rd.integer(dj, "cloud");
                auto it = by_id.find(cid);
                if (it == by_id.end() || !r.has<SplatCloud>(it->second))
                    throw std::runtime_error(src + ": SFFD_scene: deformer refers to missing cloud " +
                                             std::to_string(cid));
                if (!dj.contains("lattices") || !dj["lattices"].is_array())
                    throw std::runtime_error(src + ": SFFD_scene: deformer needs a 'lattices' array");
                Deformers d;
                for (const json& lid : dj["lattices"]) {
                    if (!lid.is_number_integer())
                        throw std::runtime_error(src + ": SFFD_scene: lattice ids must be integers");
                    auto lt = by_id.find(lid.get<int>());
                    if (lt == by_id.end() || !r.has<Lattice>(lt->second))
                        throw std::runtime_error(src + ": SFFD_scene: deformer refers to missing lattice " +
                                                 lid.dump());
                    d.lattices.push_back(lt->second);
                }
                r.emplace<Deformers>(it->second, std::move(d));
            }
        }
        if (scene.contains("cameras")) {
            if (!scene["cameras"].is_array())
                throw std::runtime_error(src + ": SFFD_scene: 'cameras' must be an array");
            for (const json& cj : scene["cameras"]) {
                Reader cr{src + ": SFFD_scene camera"};
                Camera c;
                c.eye = cr.v3(cj, "eye");
                c.target = cr.v3(cj, "target");
                c.up = cr.v3_or(cj, "up", c.up);
                c.fov_y_degrees = static_cast<float>(cr.num_or(cj, "fov_y_degrees", c.fov_y_degrees));
                c.near_plane = static_cast<float>(cr.num_or(cj, "near", c.near_plane));
                c.far_plane = static_cast<float>(cr.num_or(cj, "far", c.far_plane));
                if (!(c.fov_y_degrees > 0.0f && c.fov_y_degrees < 180.0f) || !(c.near_plane > 0.0f) ||
                    !(c.far_plane > c.near_plane))
                    throw std::runtime_error(cr.where + ": fov must be in (0, 180) and 0 < near < far");
                // eye = target has no view direction; an up vector along it (or zero) has no roll.
                const glm::dvec3 view = c.target - c.eye;
                if (!(glm::length(view) > 0.0))
                    throw std::runtime_error(cr.where + ": 'eye' equals 'target' (no view direction)");
                if (!(glm::length(glm::cross(glm::normalize(view), glm::dvec3(c.up))) > 1e-9))
                    throw std::runtime_error(cr.where + ": 'up' is zero or parallel to the view direction");
                const ecs::Entity e = r.create();
                created.push_back(e);
                r.emplace<Name>(e, Name{cr.str_or(cj, "name", "camera")});
                r.emplace<Camera>(e, c);
                have_camera = true;
                if (cj.contains("id")) remember(cr.integer(cj, "id"), e);
            }
        }
        if (scene.contains("directional_lights")) {
            if (!scene["directional_lights"].is_array())
                throw std::runtime_error(src + ": SFFD_scene: 'directional_lights' must be an array");
            for (const json& lj : scene["directional_lights"]) {
                Reader lr{src + ": SFFD_scene directional light"};
                DirectionalLight d;
                d.direction = glm::vec3(lr.v3(lj, "direction"));
                d.color = glm::vec3(lr.v3_or(lj, "color", glm::dvec3(d.color)));
                d.intensity =
                    static_cast<float>(lr.num_or(lj, "intensity", static_cast<double>(d.intensity)));
                const ecs::Entity e = r.create();
                created.push_back(e);
                r.emplace<Name>(e, Name{lr.str_or(lj, "name", "light")});
                r.emplace<DirectionalLight>(e, d);
                if (lj.contains("id")) remember(lr.integer(lj, "id"), e);
            }
        }
        if (scene.contains("ambient_lights")) {
            if (!scene["ambient_lights"].is_array())
                throw std::runtime_error(src + ": SFFD_scene: 'ambient_lights' must be an array");
            for (const json& lj : scene["ambient_lights"]) {
                Reader lr{src + ": SFFD_scene ambient light"};
                AmbientLight a;
                a.color = glm::vec3(lr.v3_or(lj, "color", glm::dvec3(a.color)));
                a.intensity =
                    static_cast<float>(lr.num_or(lj, "intensity", static_cast<double>(a.intensity)));
                const ecs::Entity e = r.create();
                created.push_back(e);
                r.emplace<Name>(e, Name{lr.str_or(lj, "name", "ambient")});
                r.emplace<AmbientLight>(e, a);
                if (lj.contains("id")) remember(lr.integer(lj, "id"), e);
            }
        }
        if (scene.contains("extensions")) {
            if (!scene["extensions"].is_object())
                throw std::runtime_error(src + ": SFFD_scene: 'extensions' must be an object");
            for (const auto& [key, value] : scene["extensions"].items()) {
                const SceneHooks* own = SceneHooks::of(r);  // a copy below: a loader may change it
                const auto extensions = own ? own->extensions : SceneHooks{}.extensions;
                auto it = extensions.find(key);
                if (it == extensions.end() || !it->second.load) {
                    log::debug(src, ": scene extension '", key, "' has no registered loader; skipped");
                    continue;
                }
                const SceneEntityOf entity_of = [&](int id) {
                    auto f = by_id.find(id);
                    return f == by_id.end() ? ecs::null_entity : f->second;
                };
                if (auto s = it->second.load(r, value.dump(), entity_of, path, *contents->model); !s)
                    return rollback(make_error(src + ": scene extension '" + key + "': " + s.message()));
            }
        }
    } catch (const std::exception& e) {
        std::string what = e.what();
        if (what.rfind(src, 0) != 0) what = src + ": SFFD_scene: " + what;
        return rollback(make_error(what));
    }
    if (!have_camera && r.count<Camera>() == 0) {
        // A file without a camera still opens framed.
        glm::dvec3 lo(1e300), hi(-1e300);
        for (ecs::Entity e : created)
            if (const SplatCloud* c = r.try_get<SplatCloud>(e))
                for (const auto& p : c->positions) {
                    lo = glm::min(lo, c->origin + glm::dvec3(p));
                    hi = glm::max(hi, c->origin + glm::dvec3(p));
                }
        if (lo.x <= hi.x) assets::add_default_view(r, lo, hi, glm::dvec3(0.3, 0.3, 1.0));
    }
    return {};
}

}  // namespace

std::vector<std::string> builtin_scene_names() { return {"sphere", "face"}; }

void SceneHooks::add_extension(const std::string& key, SceneSaveFn save_fn, SceneLoadFn load_fn) {
    Extension e;
    if (save_fn)
        e.save = [f = std::move(save_fn)](const ecs::Registry& r, const SceneIdOf& id_of, const fs::path&,
                                          std::vector<assets::GltfAppend>&) { return f(r, id_of); };
    if (load_fn)
        e.load = [f = std::move(load_fn)](ecs::Registry& r, std::string_view text,
                                          const SceneEntityOf& entity_of, const fs::path&,
                                          const assets::GltfModel&) { return f(r, text, entity_of); };
    extensions[key] = std::move(e);
}

void SceneHooks::add_gltf_extension(const std::string& key, SceneGltfSaveFn save_fn,
                                    SceneGltfLoadFn load_fn) {
    extensions[key] = Extension{std::move(save_fn), std::move(load_fn)};
}

void SceneHooks::add_file_loader(const std::string& key, SceneFileClaim claims, SceneFileLoader load,
                                 std::string types) {
    file_loaders[key] = FileLoader{std::move(claims), std::move(load), std::move(types)};
}

void SceneHooks::add_builtin_hook(const std::string& key, BuiltinSceneHook hook) {
    builtin_hooks[key] = std::move(hook);
}

void SceneHooks::remove(const std::string& key) {
    extensions.erase(key);
    file_loaders.erase(key);
    builtin_hooks.erase(key);
}

std::string SceneHooks::file_types() const {
    std::string all = ".ply, .obj, .off, .gltf, .glb";
    for (const auto& [key, loader] : file_loaders)
        if (!loader.types.empty()) all += ", " + loader.types;
    return all;
}

const SceneHooks* SceneHooks::of(const ecs::Registry& registry) {
    return registry.try_resource<SceneHooks>();
}

SceneHooks& SceneHooks::in(ecs::Registry& registry) {
    if (SceneHooks* own = registry.try_resource<SceneHooks>()) return *own;
    return registry.set_resource<SceneHooks>();
}

void SceneHooks::copy_to(const ecs::Registry& from, ecs::Registry& to) {
    if (const SceneHooks* hooks = of(from)) to.set_resource<SceneHooks>(*hooks);
}

std::string scene_file_types(const ecs::Registry& registry) {
    const SceneHooks* hooks = SceneHooks::of(registry);
    return hooks ? hooks->file_types() : SceneHooks{}.file_types();
}

namespace {
Status load_builtin_with_hooks(ecs::Registry& r, const std::string& name) {
    std::vector<ecs::Entity> before;
    r.each_entity([&](ecs::Entity e) { before.push_back(e); });
    if (Status s = assets::load_builtin_scene(r, name); !s) return s;
    std::vector<ecs::Entity> created;
    r.each_entity([&](ecs::Entity e) {
        if (std::find(before.begin(), before.end(), e) == before.end()) created.push_back(e);
    });
    // A copy: a hook may replace the registry's SceneHooks.
    const auto builtin = SceneHooks::of(r)->builtin_hooks;
    for (const auto& [key, hook] : builtin)
        if (hook) hook(r, name, created);
    return {};
}
}  // namespace

namespace {
// What decides which files and extensions a registry opens is set up with the registry, never found in
// the process: a registry without hooks is refused, not opened with whatever ran before.
std::string no_hooks_message(const std::string& what) {
    return what +
           ": no scene loaders registered in this registry (give it a SceneHooks resource: "
           "use_engine_scene_hooks(registry), or an empty SceneHooks for assets' own formats)";
}
}  // namespace

Status load_scene(ecs::Registry& r, const std::string& name_or_path) {
    if (!SceneHooks::of(r)) return make_error(no_hooks_message(name_or_path));
    if (assets::is_builtin_scene(name_or_path)) return load_builtin_with_hooks(r, name_or_path);
    const fs::path path(name_or_path);
    std::error_code ec;
    if (!fs::exists(path, ec))
        return make_error(name_or_path + ": no such file or built-in scene (built-ins: sphere, face)");
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const auto loaders = SceneHooks::of(r)->file_loaders;  // a copy: a loader may change the registry
    for (const auto& [key, loader] : loaders)
        if (loader.claims && loader.load && loader.claims(path)) return loader.load(r, path);
    if (ext == ".gltf" || ext == ".glb") return load_scene_file(r, path);
    // Refused here rather than by the importer, whose list knows only its own formats.
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && path.filename() != "metadata.json")
        return make_error(name_or_path + ": unknown file type '" + ext + "' (expected " +
                          scene_file_types(r) + ")");
    SplatMaterial material;
    auto cloud = assets::import_splat_cloud(path, {}, &material);
    if (!cloud) return cloud.error();
    auto weights = assets::cloud_weights_of_file(path, cloud->size());  // a PLY's `weight` column
    if (!weights) return weights.error();
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : cloud->positions) {
        lo = glm::min(lo, cloud->origin + glm::dvec3(p));
        hi = glm::max(hi, cloud->origin + glm::dvec3(p));
    }
    const ecs::Entity e = r.create();
    r.emplace<Name>(e, Name{path.stem().string()});
    r.emplace<Transform>(e, Transform{});
    r.emplace<SplatCloud>(e, std::move(*cloud));
    r.emplace<SplatMaterial>(e, material);
    if (!weights->values.empty()) r.emplace<PointWeights>(e, std::move(*weights));
    if (r.count<Camera>() == 0) assets::add_default_view(r, lo, hi, glm::dvec3(0.3, 0.3, 1.0));
    return {};
}

Status save_scene(const ecs::Registry& r, const fs::path& path) {
    const SceneHooks* hooks = SceneHooks::of(r);
    if (!hooks) return make_error(no_hooks_message(path.string()));
    // Stable ids: clouds, then lattices, cameras, lights, in entity order.
    std::unordered_map<ecs::Entity, int> ids;
    std::vector<ecs::Entity> clouds, lattices, cameras, suns, ambients;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<SplatCloud>(e)) clouds.push_back(e);
        if (r.has<Lattice>(e)) lattices.push_back(e);
        if (r.has<Camera>(e)) cameras.push_back(e);
        if (r.has<DirectionalLight>(e)) suns.push_back(e);
        if (r.has<AmbientLight>(e)) ambients.push_back(e);
    });
    int next = 0;
    for (const auto* list : {&clouds, &lattices, &cameras, &suns, &ambients})
        for (ecs::Entity e : *list) ids.emplace(e, next++);
    const SceneIdOf id_of = [&](ecs::Entity e) {
        auto it = ids.find(e);
        return it == ids.end() ? -1 : it->second;
    };

    json scene = {{"version", kSceneVersion}};
    json lj = json::array();
    for (ecs::Entity e : lattices) {
        json j = lattice_to_json(r.get<Lattice>(e));
        j["id"] = ids[e];
        j["name"] = name_of(r, e, "lattice");
        if (const Transform* t = r.try_get<Transform>(e)) j["transform"] = transform_json(*t);
        lj.push_back(std::move(j));
    }
    scene["lattices"] = lj;
    json dj = json::array();
    for (ecs::Entity e : clouds)
        if (const Deformers* d = r.try_get<Deformers>(e)) {
            json list = json::array();
            for (ecs::Entity l : d->lattices)
                if (int id = id_of(l); id >= 0 && r.has<Lattice>(l)) list.push_back(id);
            dj.push_back({{"cloud", ids[e]}, {"lattices", list}});
        }
    scene["deformers"] = dj;
    json cj = json::array();
    for (ecs::Entity e : cameras) {
        const Camera& c = r.get<Camera>(e);
        cj.push_back({{"id", ids[e]},
                      {"name", name_of(r, e, "camera")},
                      {"eye", vec3(c.eye)},
                      {"target", vec3(c.target)},
                      {"up", vec3(c.up)},
                      {"fov_y_degrees", c.fov_y_degrees},
                      {"near", c.near_plane},
                      {"far", c.far_plane}});
    }
    scene["cameras"] = cj;
    json sj = json::array();
    for (ecs::Entity e : suns) {
        const DirectionalLight& d = r.get<DirectionalLight>(e);
        sj.push_back({{"id", ids[e]},
                      {"name", name_of(r, e, "light")},
                      {"direction", vec3f(d.direction)},
                      {"color", vec3f(d.color)},
                      {"intensity", d.intensity}});
    }
    scene["directional_lights"] = sj;
    json aj = json::array();
    for (ecs::Entity e : ambients) {
        const AmbientLight& a = r.get<AmbientLight>(e);
        aj.push_back({{"id", ids[e]},
                      {"name", name_of(r, e, "ambient")},
                      {"color", vec3f(a.color)},
                      {"intensity", a.intensity}});
    }
    scene["ambient_lights"] = aj;
    json ext = json::object();
    std::vector<assets::GltfAppend> append;
    for (const auto& [key, fns] : hooks->extensions) {
        if (!fns.save) continue;
        auto text = fns.save(r, id_of, path, append);
        if (!text) return make_error(path.string() + ": scene extension '" + key + "': " + text.message());
        if (text->empty()) continue;
        json v = json::parse(*text, nullptr, false);
        if (v.is_discarded())
            return make_error(path.string() + ": scene extension '" + key + "' returned invalid JSON");
        ext[key] = v;
    }
    if (!ext.empty()) scene["extensions"] = ext;

    std::vector<assets::GltfCloudOut> out;
    // A saved cloud holds no deleted point (point_subset.h): a cloud with some is written from a copy
    // without them, its flags and weights subset with it. Kept in a list so the pointers stay put.
    std::list<std::tuple<SplatCloud, PointFlags, PointWeights>> compacted;
    for (ecs::Entity e : clouds) {
        assets::GltfCloudOut c;
        c.name = name_of(r, e, "cloud" + std::to_string(ids[e]));
        c.id = ids[e];
        c.transform = r.try_get<Transform>(e);
        c.cloud = &r.get<SplatCloud>(e);
        c.material = r.try_get<SplatMaterial>(e);
        c.flags = r.try_get<PointFlags>(e);
        c.weights = r.try_get<PointWeights>(e);
        const std::size_t n = c.cloud->size();
        if (c.flags && !c.flags->bits.empty() && c.flags->bits.size() != n)
            return make_error(path.string() + ": cloud '" + c.name + "': flags hold " +
                              std::to_string(c.flags->bits.size()) + " values for " + std::to_string(n) +
                              " points");
        if (any_point_flagged(c.flags, n, kPointDeleted)) {
            const auto keep = points_with(c.flags, n, 0, kPointDeleted);
            auto cloud = subset_points(*c.cloud, keep);
            if (!cloud) return make_error(path.string() + ": cloud '" + c.name + "': " + cloud.message());
            auto flags = subset_points(*c.flags, n, keep);
            auto weights =
                c.weights ? subset_points(*c.weights, n, keep) : Result<PointWeights>(PointWeights{});
            if (!flags || !weights)
                return make_error(path.string() + ": cloud '" + c.name +
                                  "': " + (!flags ? flags.message() : weights.message()));
            auto& [sc, sf, sw] =
                compacted.emplace_back(std::move(*cloud), std::move(*flags), std::move(*weights));
            c.cloud = &sc, c.flags = &sf, c.weights = &sw;
        }
        out.push_back(c);
    }
    return assets::write_gltf(path, out, scene.dump(-1, ' ', false, json::error_handler_t::replace), append);
}

}  // namespace sffd
