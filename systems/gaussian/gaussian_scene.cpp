#include "systems/gaussian/gaussian_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/surface/gltf_model.h"
#include "runtime/assets/formats/surface/gltf_point_columns.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/scene.h"
#include "runtime/core/file_io.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_subset.h"
#include "systems/gaussian/capture_up.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

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

// Strict JSON readers: errors say where.
glm::dvec3 vec3_at(const json& j, const char* key, glm::dvec3 fallback, const std::string& where) {
    if (!j.contains(key)) return fallback;
    const json& v = j[key];
    if (!v.is_array() || v.size() != 3) throw std::runtime_error(where + ": '" + key + "' must be [x, y, z]");
    glm::dvec3 out;
    for (int i = 0; i < 3; ++i) {
        const json& e = v[std::size_t(i)];
        if (!e.is_number() || !std::isfinite(e.get<double>()))
            throw std::runtime_error(where + ": '" + key + "' has a non-finite or non-numeric entry");
        out[i] = e.get<double>();
        // Bounded like the cloud itself (gaussian_io.h): a scale of 1e30 would overflow every projection.
        if (std::abs(out[i]) > kMaxCoordinate)
            throw std::runtime_error(where + ": '" + key + "' entry beyond the +-1e10 bound");
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
        if (!r.is_array() || r.size() != 4)
            throw std::runtime_error(where + " transform: 'rotation' must be [x, y, z, w]");
        double q[4];
        for (int i = 0; i < 4; ++i) {
            if (!r[std::size_t(i)].is_number() || !std::isfinite(r[std::size_t(i)].get<double>()))
                throw std::runtime_error(where +
                                         " transform: 'rotation' has a non-finite or non-numeric entry");
            q[i] = r[std::size_t(i)].get<double>();
        }
        const glm::dquat rot(q[3], q[0], q[1], q[2]);
        if (!(glm::length(rot) > 1e-12))
            throw std::runtime_error(where + " transform: 'rotation' is a zero quaternion");
        t.rotation = glm::normalize(rot);
    }
    return t;
}

json transform_json(const Transform& t) {
    return {{"translation", {t.translation.x, t.translation.y, t.translation.z}},
            {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}},
            {"scale", {t.scale.x, t.scale.y, t.scale.z}}};
}

// Embedded cloud `entry` (clouds[entry] with "embedded": true): node "<name>" (TRS = the entity's
// Transform, extras {"sffd_gaussians": entry}) with one child "<name>.origin" (translation = origin) whose
// mesh is one KHR_gaussian_splatting POINTS primitive.
// The cloud's optional columns, written as `_FLAGS` / `_WEIGHT` on the same primitive
// (gltf_point_columns.h); null: none.
struct EmbeddedColumns {
    std::shared_ptr<const PointFlags> flags;
    std::shared_ptr<const PointWeights> weights;
};

assets::GltfAppend embed(std::shared_ptr<const GaussianCloud> cloud, std::string name, Transform t, int entry,
                         EmbeddedColumns columns = {}) {
    return [cloud = std::move(cloud), name = std::move(name), t, entry, columns](json& doc,
                                                                                 std::string& bin) -> Status {
        json prim;
        if (Status s = append_primitive(doc, bin, *cloud, prim, "Gaussian cloud '" + name + "'"); !s)
            return s;
        if (columns.flags || columns.weights) {
            if (!doc.contains("accessors")) doc["accessors"] = json::array();
            if (!doc.contains("bufferViews")) doc["bufferViews"] = json::array();
            if (Status s = assets::append_point_columns(
                    doc["accessors"], doc["bufferViews"], bin, prim["attributes"], cloud->size(),
                    columns.flags.get(), columns.weights.get(), "Gaussian cloud '" + name + "'");
                !s)
                return s;
        }
        if (!doc.contains("meshes")) doc["meshes"] = json::array();
        if (!doc.contains("nodes")) doc["nodes"] = json::array();
        doc["meshes"].push_back({{"name", name}, {"primitives", {prim}}});
        const std::size_t parent = doc["nodes"].size();
        const glm::dvec3& o = cloud->origin;
        doc["nodes"].push_back({{"name", name},
                                {"translation", {t.translation.x, t.translation.y, t.translation.z}},
                                {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}},
                                {"scale", {t.scale.x, t.scale.y, t.scale.z}},
                                {"children", {parent + 1}},
                                {"extras", {{"sffd_gaussians", entry}}}});
        doc["nodes"].push_back({{"name", name + ".origin"},
                                {"translation", {o.x, o.y, o.z}},
                                {"mesh", doc["meshes"].size() - 1}});
        doc["scenes"][0]["nodes"].push_back(parent);
        return {};
    };
}

// The cloud embedded for clouds[entry], with every check read_gltf makes on a KHR_gaussian_splatting file.
GaussianCloud read_embedded(const assets::GltfModel& model, int entry, const std::string& where,
                            PointFlags& flags, PointWeights& weights) {
    const tinygltf::Model& m = model.gltf;
    int found = -1;
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
        const tinygltf::Value& x = m.nodes[i].extras;
        if (x.IsObject() && x.Has("sffd_gaussians") && x.Get("sffd_gaussians").IsInt() &&
            x.Get("sffd_gaussians").GetNumberAsInt() == entry) {
            if (found >= 0)
                throw std::runtime_error(where + ": nodes " + std::to_string(found) + " and " +
                                         std::to_string(i) + " both claim this entry");
            found = int(i);
        }
    }
    if (found < 0)
        throw std::runtime_error(
            where + ": 'embedded' but no node has extras.sffd_gaussians = " + std::to_string(entry));
    const std::string at = where + " (embedded, node " + std::to_string(found) + ")";
    const tinygltf::Node& parent = m.nodes[std::size_t(found)];
    if (parent.children.size() != 1 || parent.children[0] < 0 ||
        std::size_t(parent.children[0]) >= m.nodes.size())
        throw std::runtime_error(at + ": must have exactly one child node (the cloud's origin)");
    const tinygltf::Node& child = m.nodes[std::size_t(parent.children[0])];
    if (child.mesh < 0 || std::size_t(child.mesh) >= m.meshes.size())
        throw std::runtime_error(at + ": the child node has no valid mesh");
    const auto& prims = m.meshes[std::size_t(child.mesh)].primitives;
    if (prims.size() != 1 || prims[0].mode != TINYGLTF_MODE_POINTS ||
        !prims[0].extensions.count("KHR_gaussian_splatting"))
        throw std::runtime_error(at + ": mesh " + std::to_string(child.mesh) +
                                 " must hold one KHR_gaussian_splatting POINTS primitive");
    auto g = read_primitive(model, prims[0], at + " mesh " + std::to_string(child.mesh));
    if (!g) throw std::runtime_error(g.message());
    if (child.translation.size() == 3)
        g->origin = glm::dvec3(child.translation[0], child.translation[1], child.translation[2]);
    if (!std::isfinite(g->origin.x + g->origin.y + g->origin.z))
        throw std::runtime_error(at + ": the origin node's translation is not finite");
    if (Status s = validate(*g, at); !s) throw std::runtime_error(s.message());
    if (Status s = assets::read_point_columns(model, prims[0].attributes, g->size(),
                                              at + " mesh " + std::to_string(child.mesh), flags, weights);
        !s)
        throw std::runtime_error(s.message());
    return std::move(*g);
}

}  // namespace

namespace {
// A SOG folder is opened through its meta.json (what read_gaussians reads); other paths as they are.
fs::path gaussian_file_of(const fs::path& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec) && fs::is_regular_file(path / "meta.json", ec)) return path / "meta.json";
    return path;
}
}  // namespace

bool is_gaussian_scene_file(const fs::path& given) {
    const fs::path path = gaussian_file_of(given);
    const std::string e = lower_ext(path);
    if (e == ".splat" || e == ".spz" || e == ".ksplat" || e == ".sog") return true;
    if (path.filename() == "meta.json") return true;      // a SOG folder's
    if (path.filename() == "lod-meta.json") return true;  // a streamed SOG, read at full detail
    if (e == ".ply") {
        auto r = ply::Reader::open(path);
        if (!r) return false;
        const int v = r->header().find("vertex");
        return v >= 0 &&
               (is_gaussian_element(r->header().elements[std::size_t(v)]) || is_compressed_ply(r->header()));
    }
    if (e == ".glb" || e == ".gltf") {
        const GltfDeclaration d = gltf_declaration(path);
        return d.gaussian_splatting && !d.sffd_scene;
    }
    return false;
}

Result<ecs::Entity> load_gaussian_entity(ecs::Registry& registry, const fs::path& given) {
    const fs::path path = gaussian_file_of(given);
    auto cloud = read_gaussians(path);
    if (!cloud) return cloud.error();
    auto weights = assets::cloud_weights_of_file(path, cloud->size());  // a 3DGS PLY's `weight` column
    if (!weights) return weights.error();
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    if (ec) absolute = path;
    const ecs::Entity e = registry.create();
    // A SOG folder is named after the folder, not "meta".
    const fs::path named =
        path.filename() == "meta.json" || path.filename() == "lod-meta.json" ? path.parent_path() : path;
    registry.emplace<Name>(e, Name{named.stem().string()});
    // Shown upright: the capture's up (y down unless --up says otherwise) turned onto the world's +y.
    registry.emplace<Transform>(e, capture_transform());
    registry.emplace<GaussianSource>(e, GaussianSource{absolute.lexically_normal()});
    registry.emplace<GaussianCloud>(e, std::move(*cloud));
    if (!weights->values.empty()) registry.emplace<PointWeights>(e, std::move(*weights));
    return e;
}

Result<std::string> save_gaussian_extension(const ecs::Registry& registry,
                                            const std::function<int(ecs::Entity)>& id_of,
                                            const fs::path& scene_path,
                                            std::vector<assets::GltfAppend>& append) {
    const fs::path scene_dir = scene_path.parent_path();
    json clouds = json::array();
    std::vector<ecs::Entity> entities;
    registry.each_entity([&](ecs::Entity e) {
        if (registry.has<GaussianCloud>(e)) entities.push_back(e);
    });
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const ecs::Entity e = entities[i];
        const Name* name = registry.try_get<Name>(e);
        const std::string label =
            name && !name->value.empty() ? name->value : "gaussians" + std::to_string(i);
        json c = {{"name", label}};
        const Transform* t = registry.try_get<Transform>(e);
        // The optional columns live only in the scene file: a cloud with flags or weights is embedded with
        // them, without its deleted points (a referenced file would bring those back).
        const PointFlags* flags = registry.try_get<PointFlags>(e);
        const PointWeights* weights = registry.try_get<PointWeights>(e);
        const std::size_t n = registry.get<GaussianCloud>(e).size();
        if (flags && !flags->bits.empty() && flags->bits.size() != n)
            return make_error("Gaussian cloud '" + label + "': flags hold " +
                              std::to_string(flags->bits.size()) + " values for " + std::to_string(n) +
                              " points");
        const bool columns =
            any_point_flagged(flags, n, kPointSelected | kPointGone) || (weights && !weights->values.empty());
        if (const GaussianSource* src = registry.try_get<GaussianSource>(e);
            src && !src->path.empty() && !columns) {
            std::error_code ec;
            const fs::path base = scene_dir.empty() ? fs::current_path(ec) : fs::absolute(scene_dir, ec);
            fs::path rel = ec ? fs::path() : fs::absolute(src->path, ec).lexically_relative(base);
            if (ec || rel.empty()) rel = src->path;
            c["file"] = rel.generic_string();
        } else {  // made in memory: embedded in the scene file as a KHR_gaussian_splatting primitive
            // The append functions run inside save_scene, while the registry's cloud exists: no copy
            // unless SH frames must be baked first.
            const GaussianCloud& own = registry.get<GaussianCloud>(e);
            std::shared_ptr<const GaussianCloud> cloud(&own, [](const GaussianCloud*) {});
            if (!own.sh_frames.empty()) {
                auto baked = std::make_shared<GaussianCloud>(own);
                bake_sh_frames(*baked);
                cloud = std::move(baked);
            }
            EmbeddedColumns kept;
            if (flags) kept.flags = std::shared_ptr<const PointFlags>(flags, [](const PointFlags*) {});
            if (weights)
                kept.weights = std::shared_ptr<const PointWeights>(weights, [](const PointWeights*) {});
            if (any_point_flagged(flags, n, kPointDeleted)) {
                const auto keep = points_with(flags, n, 0, kPointDeleted);
                auto sub = subset_points(*cloud, keep);
                auto sf = subset_points(*flags, n, keep);
                auto sw = weights ? subset_points(*weights, n, keep) : Result<PointWeights>(PointWeights{});
                if (!sub || !sf || !sw)
                    return make_error("Gaussian cloud '" + label + "': " +
                                      (!sub  ? sub.message()
                                       : !sf ? sf.message()
                                             : sw.message()));
                cloud = std::make_shared<GaussianCloud>(std::move(*sub));
                kept.flags = std::make_shared<PointFlags>(std::move(*sf));
                kept.weights = weights ? std::make_shared<PointWeights>(std::move(*sw)) : nullptr;
            }
            append.push_back(embed(std::move(cloud), label, t ? *t : Transform{}, int(i), std::move(kept)));
            c["embedded"] = true;
        }
        if (t) c["transform"] = transform_json(*t);
        json lattices = json::array();
        if (const Deformers* d = registry.try_get<Deformers>(e))
            for (ecs::Entity l : d->lattices)
                if (const int id = id_of(l); id >= 0 && registry.has<Lattice>(l)) lattices.push_back(id);
        c["lattices"] = lattices;
        clouds.push_back(std::move(c));
    }
    if (clouds.empty()) return std::string();
    // Names and file names are any bytes: invalid UTF-8 becomes U+FFFD instead of an exception.
    return json{{"version", 1}, {"clouds", clouds}}.dump(-1, ' ', false, json::error_handler_t::replace);
}

Status load_gaussian_extension(ecs::Registry& registry, std::string_view text,
                               const std::function<ecs::Entity(int)>& entity_of, const fs::path& scene_path,
                               const assets::GltfModel& model) {
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
            if (c.contains("embedded") && !c["embedded"].is_boolean())
                throw std::runtime_error(where + ": 'embedded' must be true or false");
            const bool embedded = c.value("embedded", false);
            if (embedded && c.contains("file"))
                throw std::runtime_error(where + ": has both 'file' and 'embedded'");
            if (!embedded &&
                (!c.contains("file") || !c["file"].is_string() || c["file"].get<std::string>().empty()))
                throw std::runtime_error(
                    where + ": 'file' must be a non-empty string (a Gaussian file), or 'embedded' true");
            fs::path file;
            if (!embedded) {
                // The same confinement as every other resource a file names (runtime/core/file_io.h): inside
                // the scene file's folder unless --allow-outside-resources.
                auto resolved = resolve_resource(scene_path, c["file"].get<std::string>());
                if (!resolved) {
                    const std::string& m = resolved.message();
                    const bool missing = m.size() >= 10 && m.compare(m.size() - 10, 10, " not found") == 0;
                    throw std::runtime_error(where + ": " + m + (missing ? " (no such Gaussian file)" : ""));
                }
                file = std::move(*resolved);
            }
            std::vector<ecs::Entity> lattices;
            if (c.contains("lattices")) {
                if (!c["lattices"].is_array())
                    throw std::runtime_error(where + ": 'lattices' must be an array of lattice ids");
                for (const json& id : c["lattices"]) {
                    if (!id.is_number_integer())
                        throw std::runtime_error(where + ": 'lattices' must be an array of lattice ids");
                    const ecs::Entity l = entity_of(id.get<int>());
                    if (l == ecs::null_entity || !registry.has<Lattice>(l))
                        throw std::runtime_error(where + ": 'lattices' names " +
                                                 std::to_string(id.get<int>()) +
                                                 ", which is not a lattice of this scene");
                    lattices.push_back(l);
                }
            }
            const Transform t = c.contains("transform") ? transform_from(c["transform"], where) : Transform{};
            Result<ecs::Entity> e = ecs::null_entity;
            if (embedded) {
                PointFlags flags;
                PointWeights weights;
                GaussianCloud g = read_embedded(model, int(i), where, flags, weights);
                const ecs::Entity x = registry.create();
                registry.emplace<Name>(x, Name{"gaussians" + std::to_string(i)});
                registry.emplace<Transform>(x, Transform{});
                registry.emplace<GaussianCloud>(x, std::move(g));
                if (!flags.bits.empty()) registry.emplace<PointFlags>(x, std::move(flags));
                if (!weights.values.empty()) registry.emplace<PointWeights>(x, std::move(weights));
                e = x;
            } else {
                e = load_gaussian_entity(registry, file);
                if (!e) throw std::runtime_error(where + ": " + e.message());
            }
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
    // A scene saved without a camera (convert IN OUT.glb --lattice fit) opens with the camera IN opens with.
    if (!created.empty()) add_default_gaussian_view(registry);
    return {};
}

void add_default_gaussian_view(ecs::Registry& registry) {
    if (registry.count<Camera>() > 0) return;
    // World-space bounds (through each cloud's Transform: a capture's up turn, a scene's placement), so a
    // capture and the scene made from it frame the same box. They hold each Gaussian's 3-sigma extent, not
    // only its centre: the camera (and its near plane) then sits outside every Gaussian, also when the
    // centres coincide. Surface clouds of the same scene are framed with them.
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    auto add = [&](const glm::dmat4& m, const glm::dvec3& p, double reach) {
        const glm::dvec3 w = glm::dvec3(m * glm::dvec4(p, 1.0));
        lo = glm::min(lo, w - reach), hi = glm::max(hi, w + reach);
    };
    auto scale_of = [](const glm::dmat4& m) {
        return std::max(
            {glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
    };
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& g) {
        const glm::dmat4 m = model_matrix(registry.try_get<Transform>(e), g.origin);
        const double k = scale_of(m);
        for (std::size_t i = 0; i < g.size(); ++i) {
            const glm::dvec3 s = glm::dvec3(g.scales[i]);
            add(m, glm::dvec3(g.positions[i]), 3.0 * k * std::max({s.x, s.y, s.z}));
        }
    });
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) {
        const glm::dmat4 m = model_matrix(registry.try_get<Transform>(e), c.origin);
        for (const glm::vec3& p : c.positions) add(m, glm::dvec3(p), 0.0);
    });
    if (lo.x <= hi.x) assets::add_default_view(registry, lo, hi, glm::dvec3(0.3, 0.3, 1.0));
}

void register_gaussian_scene_hooks(SceneHooks& hooks) {
    hooks.add_gltf_extension(kKey, save_gaussian_extension, load_gaussian_extension);
    hooks.add_file_loader(
        kKey, [](const fs::path& p) { return is_gaussian_scene_file(p); },
        [](ecs::Registry& registry, const fs::path& p) -> Status {
            auto e = load_gaussian_entity(registry, p);
            if (!e) return e.error();
            add_default_gaussian_view(registry);
            return {};
        },
        ".spz, .splat, .ksplat, .sog, a SOG folder or its meta.json, a streamed SOG's lod-meta.json, a 3DGS "
        ".ply, a KHR_gaussian_splatting .glb/.gltf");
}

}  // namespace sffd::gaussian
