// Reading glTF 2.0 / GLB files as splat clouds and geometry (gltf_io.h): our splat nodes exactly as stored,
// every other mesh or point primitive in world space. The guarded load itself is gltf_load.cpp.
#include "runtime/assets/formats/surface/gltf_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <unordered_map>
#include <unordered_set>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/formats/surface/gltf_detail.h"
#include "runtime/assets/formats/surface/gltf_model.h"
#include "runtime/assets/formats/surface/gltf_point_columns.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"
#include "runtime/scene/camera.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using namespace gltf_detail;

json to_json(const tinygltf::Value& v, int depth = 0) {
    if (depth > 64) return nullptr;
    if (v.IsBool()) return v.Get<bool>();
    if (v.IsInt()) return v.Get<int>();
    if (v.IsNumber()) return v.GetNumberAsDouble();
    if (v.IsString()) return v.Get<std::string>();
    if (v.IsArray()) {
        json a = json::array();
        for (std::size_t i = 0; i < v.ArrayLen(); ++i)
            a.push_back(to_json(v.Get(static_cast<int>(i)), depth + 1));
        return a;
    }
    if (v.IsObject()) {
        json o = json::object();
        for (const std::string& k : v.Keys()) o[k] = to_json(v.Get(k), depth + 1);
        return o;
    }
    return nullptr;
}

Transform node_trs(const tinygltf::Node& n) {
    Transform t;
    if (n.translation.size() == 3)
        t.translation = glm::dvec3(n.translation[0], n.translation[1], n.translation[2]);
    if (n.rotation.size() == 4)
        t.rotation = glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
    if (n.scale.size() == 3) t.scale = glm::dvec3(n.scale[0], n.scale[1], n.scale[2]);
    return t;
}

Result<Image> gltf_image(const tinygltf::Model& m, int texture, const std::string& src) {
    if (texture < 0 || static_cast<std::size_t>(texture) >= m.textures.size())
        return make_error(src + ": texture index out of range");
    const int source = m.textures[static_cast<std::size_t>(texture)].source;
    if (source < 0 || static_cast<std::size_t>(source) >= m.images.size())
        return make_error(src + ": texture has no image");
    const tinygltf::Image& im = m.images[static_cast<std::size_t>(source)];
    if (im.width <= 0 || im.height <= 0 || im.component < 1 || im.component > 4 || im.bits != 8 ||
        im.image.size() != static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) *
                               static_cast<std::size_t>(im.component))
        return make_error(src + ": image " + std::to_string(source) + " was not decoded to 8-bit pixels");
    Image out;
    out.width = im.width;
    out.height = im.height;
    const std::size_t n = static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height);
    out.rgba8.resize(n * 4);
    for (std::size_t i = 0; i < n; ++i) {
        const unsigned char* p = &im.image[i * static_cast<std::size_t>(im.component)];
        std::uint8_t px[4] = {p[0], p[0], p[0], 255};
        if (im.component >= 3) {
            px[1] = p[1];
            px[2] = p[2];
        }
        if (im.component == 2) px[3] = p[1];
        if (im.component == 4) px[3] = p[3];
        std::memcpy(&out.rgba8[i * 4], px, 4);
    }
    return out;
}

// An attribute's values: doubles for everything transformed to world space. Our splat nodes' attributes
// are decoded as stored, floats straight into the cloud's arrays (no copy of a 4.5M-splat cloud): then
// `direct` counts their floats and `d` stays empty.
struct Attr {
    std::vector<double> d;
    std::size_t direct = 0;
    std::size_t size() const { return direct ? direct : d.size(); }
    bool empty() const { return size() == 0; }
    double operator[](std::size_t i) const { return d[i]; }
};

// Appends one primitive's data to `g` (world transform `world`); for our splat nodes `exact` receives
// the stored arrays untouched instead.
Status read_primitive(const GltfModel& model, const tinygltf::Primitive& prim, const glm::dmat4& world,
                      const std::string& src, Geometry& g, std::unordered_map<int, int>& material_map,
                      SplatCloud* exact, SplatMaterial* exact_material) {
    const tinygltf::Model& m = model.gltf;
    if (prim.mode != TINYGLTF_MODE_POINTS && prim.mode != TINYGLTF_MODE_TRIANGLES &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP && prim.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        log::warn(src, ": skipping a primitive with mode ", prim.mode, " (lines)");
        return {};
    }
    auto attr = [&](const char* name) {
        auto it = prim.attributes.find(name);
        return it == prim.attributes.end() ? -1 : it->second;
    };
    const int ip = attr("POSITION");
    if (ip < 0) return make_error(src + ": primitive without POSITION");
    if (exact) {  // what the primitive lacks stays empty
        SplatCloud& c = *exact;
        c.positions.clear(), c.normals.clear(), c.axis_u.clear(), c.axis_v.clear(), c.uvs.clear();
        c.uv_axes.clear();
    }
    // `into`: the exact cloud's array for this attribute (decoded there, the first-open cost of a large GLB
    // being mostly fresh memory); unused for other nodes.
    auto read = [&](int index, int comps, const char* name, auto* into) -> Result<Attr> {
        Attr a;
        if (exact) {
            if (Status st = read_gltf_accessor_into(model, index, src, name, *into); !st) return st.error();
            a.direct = into->size() * static_cast<std::size_t>(comps);
        } else {
            auto r = read_gltf_accessor(model, index, comps, src, name);
            if (!r) return r.error();
            a.d = std::move(*r);
        }
        return a;
    };
    SplatCloud* const x = exact;
    auto pos = read(ip, 3, "POSITION", x ? &x->positions : nullptr);
    if (!pos) return pos.error();
    const std::size_t n = pos->size() / 3;
    const std::size_t base = g.positions.size();
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(world)));
    const glm::dmat3 linear(world);

    Attr nrm, uv, au, av, uvf;
    std::vector<double> col;
    int col_components = 0;
    if (int i = attr("NORMAL"); i >= 0) {
        auto r = read(i, 3, "NORMAL", x ? &x->normals : nullptr);
        if (!r) return r.error();
        nrm = std::move(*r);
    }
    bool colours_read = false;  // into exact->colors
    if (int i = attr("COLOR_0"); i >= 0) {
        const int comps = m.accessors.size() > static_cast<std::size_t>(i) &&
                                  m.accessors[static_cast<std::size_t>(i)].type == TINYGLTF_TYPE_VEC3
                              ? 3
                              : 4;
        if (exact) {
            if (Status st = read_gltf_colors_into(model, i, comps, src, "COLOR_0", exact->colors); !st)
                return st;
            colours_read = true;
        } else {
            auto r = read_gltf_accessor(model, i, comps, src, "COLOR_0");
            if (!r) return r.error();
            col = std::move(*r);
            col_components = comps;
        }
    }
    if (int i = attr("TEXCOORD_0"); i >= 0) {
        auto r = read(i, 2, "TEXCOORD_0", x ? &x->uvs : nullptr);
        if (!r) return r.error();
        uv = std::move(*r);
    }
    if (int iu = attr("_AXIS_U"), iv = attr("_AXIS_V"); iu >= 0 && iv >= 0) {
        auto ru = read(iu, 3, "_AXIS_U", x ? &x->axis_u : nullptr);
        if (!ru) return ru.error();
        auto rv = read(iv, 3, "_AXIS_V", x ? &x->axis_v : nullptr);
        if (!rv) return rv.error();
        au = std::move(*ru);
        av = std::move(*rv);
        // The uv frame along those axes (SplatCloud::uv_axes): du/ds, dv/ds, du/dt, dv/dt.
        if (int i = attr("_UV_AXES"); i >= 0) {
            auto r = read(i, 4, "_UV_AXES", x ? &x->uv_axes : nullptr);
            if (!r) return r.error();
            uvf = std::move(*r);
            if (!uvf.direct)  // a direct decode refuses non-finite values itself
                for (std::size_t k = 0; k < uvf.size(); ++k)
                    if (!std::isfinite(uvf[k])) return make_error(src + ": _UV_AXES has a non-finite value");
            if (uvf.size() / 4 != n) return make_error(src + ": attribute counts differ from POSITION");
        }
    }
    for (const auto* a : {&nrm, &uv, &au, &av})
        if (!a->empty() && a->size() / (a == &uv ? 2 : 3) != n)
            return make_error(src + ": attribute counts differ from POSITION");
    if (!col.empty() && col.size() / static_cast<std::size_t>(col_components) != n)
        return make_error(src + ": COLOR_0 count differs from POSITION");
    if (colours_read && !exact->colors.empty() && exact->colors.size() != n)
        return make_error(src + ": COLOR_0 count differs from POSITION");

    auto colour = [&](std::size_t i) {
        const std::size_t k = i * static_cast<std::size_t>(col_components);
        const std::uint32_t a =
            col_components == 4
                ? static_cast<std::uint32_t>(std::lround(std::clamp(col[k + 3], 0.0, 1.0) * 255.0))
                : 255u;
        return linear_to_srgb8(col[k]) | (linear_to_srgb8(col[k + 1]) << 8) |
               (linear_to_srgb8(col[k + 2]) << 16) | (a << 24);
    };

    if (exact) {
        SplatCloud& c = *exact;
        SplatMaterial& cm = *exact_material;
        if (!colours_read) c.colors.clear();
        if (prim.material >= 0 && static_cast<std::size_t>(prim.material) < m.materials.size()) {
            const tinygltf::Material& mat = m.materials[static_cast<std::size_t>(prim.material)];
            const auto& f = mat.pbrMetallicRoughness.baseColorFactor;
            if (f.size() == 4)
                cm.base_color = glm::vec4(static_cast<float>(f[0]), static_cast<float>(f[1]),
                                          static_cast<float>(f[2]), static_cast<float>(f[3]));
            const json extras = to_json(mat.extras);
            if (extras.is_object()) {
                if (extras.contains("sffd_specular") && extras["sffd_specular"].is_number())
                    cm.specular = extras["sffd_specular"].get<float>();
                if (extras.contains("sffd_shininess") && extras["sffd_shininess"].is_number())
                    cm.shininess = extras["sffd_shininess"].get<float>();
                if (extras.contains("sffd_texture_path") && extras["sffd_texture_path"].is_string())
                    c.texture.path = extras["sffd_texture_path"].get<std::string>();
            }
            if (mat.pbrMetallicRoughness.baseColorTexture.index >= 0) {
                auto img = gltf_image(m, mat.pbrMetallicRoughness.baseColorTexture.index, src);
                if (!img) return img.error();
                c.texture.width = img->width;
                c.texture.height = img->height;
                c.texture.rgba8 = std::move(img->rgba8);
            }
        }
        return {};
    }

    for (std::size_t i = 0; i < n; ++i)
        g.positions.push_back(
            glm::dvec3(world * glm::dvec4((*pos)[3 * i], (*pos)[3 * i + 1], (*pos)[3 * i + 2], 1.0)));
    // Per-point attributes must cover every point of the Geometry: fill gaps with defaults once any
    // primitive has the attribute.
    auto pad = [&](auto& arr, auto value) {
        if (arr.size() < base) arr.resize(base, value);
    };
    if (!nrm.empty() || !g.normals.empty()) {
        pad(g.normals, glm::vec3(0.0f));
        for (std::size_t i = 0; i < n; ++i) {
            glm::dvec3 v = nrm.empty()
                               ? glm::dvec3(0.0)
                               : normal_matrix * glm::dvec3(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]);
            if (glm::length(v) > 0.0) v = glm::normalize(v);
            g.normals.emplace_back(v);
        }
    }
    if (!col.empty() || !g.colors.empty()) {
        pad(g.colors, 0xffffffffu);
        for (std::size_t i = 0; i < n; ++i) g.colors.push_back(col.empty() ? 0xffffffffu : colour(i));
    }
    if (!uv.empty() || !g.uvs.empty()) {
        pad(g.uvs, glm::vec2(0.0f));
        for (std::size_t i = 0; i < n; ++i)
            g.uvs.emplace_back(
                uv.empty() ? glm::vec2(0.0f)
                           : glm::vec2(static_cast<float>(uv[2 * i]), static_cast<float>(uv[2 * i + 1])));
    }
    if (!au.empty()) {
        pad(g.axis_u, glm::vec3(0.0f));
        pad(g.axis_v, glm::vec3(0.0f));
        for (std::size_t i = 0; i < n; ++i) {
            g.axis_u.emplace_back(linear * glm::dvec3(au[3 * i], au[3 * i + 1], au[3 * i + 2]));
            g.axis_v.emplace_back(linear * glm::dvec3(av[3 * i], av[3 * i + 1], av[3 * i + 2]));
        }
    }
    // Per axis, so a node transform (which maps the axes) leaves the uv frame as it is.
    if (!uvf.empty() || !g.uv_axes.empty()) {
        pad(g.uv_axes, glm::vec4(0.0f));
        for (std::size_t i = 0; i < n; ++i)
            g.uv_axes.push_back(uvf.empty() ? glm::vec4(0.0f)
                                            : glm::vec4(float(uvf[4 * i]), float(uvf[4 * i + 1]),
                                                        float(uvf[4 * i + 2]), float(uvf[4 * i + 3])));
    }

    // Material: base colour factor and texture, shared by all triangles of this primitive.
    int material = -1;
    if (prim.material >= 0 && static_cast<std::size_t>(prim.material) < m.materials.size()) {
        auto it = material_map.find(prim.material);
        if (it != material_map.end()) {
            material = it->second;
        } else {
            const tinygltf::Material& mat = m.materials[static_cast<std::size_t>(prim.material)];
            MeshMaterial mm;
            const auto& f = mat.pbrMetallicRoughness.baseColorFactor;
            if (f.size() == 4)
                mm.base_color = glm::vec4(static_cast<float>(f[0]), static_cast<float>(f[1]),
                                          static_cast<float>(f[2]), static_cast<float>(f[3]));
            if (mat.pbrMetallicRoughness.baseColorTexture.index >= 0) {
                auto img = gltf_image(m, mat.pbrMetallicRoughness.baseColorTexture.index, src);
                if (img) {
                    mm.texture = static_cast<int>(g.textures.size());
                    g.textures.push_back(std::move(*img));
                } else {
                    log::warn(img.message());
                }
            }
            material = static_cast<int>(g.materials.size());
            g.materials.push_back(mm);
            material_map[prim.material] = material;
        }
    }

    if (prim.mode == TINYGLTF_MODE_POINTS) {
        if (!g.triangles.empty())
            log::warn(src,
                      ": file mixes points and triangles; points are sampled with the surface only if they "
                      "have faces");
        return {};
    }
    std::vector<std::uint32_t> idx;
    if (prim.indices >= 0) {
        auto r = read_gltf_accessor(model, prim.indices, 1, src, "indices");
        if (!r) return r.error();
        idx.reserve(r->size());
        for (double d : *r) {
            if (d < 0 || d >= static_cast<double>(n))
                return make_error(src + ": index " + std::to_string(static_cast<long long>(d)) +
                                  " out of range (" + std::to_string(n) + " vertices)");
            idx.push_back(static_cast<std::uint32_t>(d));
        }
    } else {
        idx.resize(n);
        for (std::size_t i = 0; i < n; ++i) idx[i] = static_cast<std::uint32_t>(i);
    }
    auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        g.triangles.push_back(static_cast<std::uint32_t>(base) + a);
        g.triangles.push_back(static_cast<std::uint32_t>(base) + b);
        g.triangles.push_back(static_cast<std::uint32_t>(base) + c);
        g.triangle_material.push_back(material);
    };
    // A mirroring transform flips the winding; keep faces pointing the same way.
    const bool flip = glm::determinant(linear) < 0.0;
    auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        flip ? tri(a, c, b) : tri(a, b, c);
    };
    if (prim.mode == TINYGLTF_MODE_TRIANGLES) {
        for (std::size_t i = 0; i + 2 < idx.size() + 0 && i + 2 < idx.size(); i += 3)
            emit(idx[i], idx[i + 1], idx[i + 2]);
    } else if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (std::size_t i = 0; i + 2 < idx.size(); ++i)
            i % 2 ? emit(idx[i + 1], idx[i], idx[i + 2]) : emit(idx[i], idx[i + 1], idx[i + 2]);
    } else {
        for (std::size_t i = 1; i + 1 < idx.size(); ++i) emit(idx[0], idx[i], idx[i + 1]);
    }
    return {};
}

}  // namespace

namespace {

// Attribute arrays are filled lazily (only once some primitive has them): complete every present one to
// the point count with its neutral value (zero normal/uv/axes, opaque white colour).
void pad_attributes(Geometry& g) {
    const std::size_t n = g.positions.size();
    if (!g.normals.empty()) g.normals.resize(n, glm::vec3(0.0f));
    if (!g.colors.empty()) g.colors.resize(n, 0xffffffffu);
    if (!g.uvs.empty()) g.uvs.resize(n, glm::vec2(0.0f));
    if (!g.axis_u.empty()) {
        g.axis_u.resize(n, glm::vec3(0.0f));
        g.axis_v.resize(n, glm::vec3(0.0f));
    }
    if (!g.uv_axes.empty()) g.uv_axes.resize(n, glm::vec4(0.0f));
}

}  // namespace

Result<GltfContents> read_gltf(const fs::path& path) {
    const std::string src = path.string();
    auto model = std::make_shared<GltfModel>();
    if (Status s = load_gltf_model(path, *model); !s) return s.error();
    const tinygltf::Model& m = model->gltf;
    GltfContents out;
    out.model = model;
    out.other.source = src;
    const bool scene_file = m.extensions.find("SFFD_scene") != m.extensions.end();
    if (scene_file) out.sffd_scene_json = to_json(m.extensions.find("SFFD_scene")->second).dump();

    std::unordered_map<int, int> material_map;
    std::unordered_set<int> visiting;
    std::vector<int> roots;
    if (!m.scenes.empty()) {
        const int s = m.defaultScene >= 0 && static_cast<std::size_t>(m.defaultScene) < m.scenes.size()
                          ? m.defaultScene
                          : 0;
        roots = m.scenes[static_cast<std::size_t>(s)].nodes;
    } else {
        // No scene: every node that is nobody's child is a root.
        std::vector<char> is_child(m.nodes.size(), 0);
        for (const auto& n : m.nodes)
            for (int c : n.children)
                if (c >= 0 && static_cast<std::size_t>(c) < m.nodes.size())
                    is_child[static_cast<std::size_t>(c)] = 1;
        for (std::size_t i = 0; i < m.nodes.size(); ++i)
            if (!is_child[i]) roots.push_back(static_cast<int>(i));
    }

    std::function<Status(int, const glm::dmat4&, int)> visit = [&](int index, const glm::dmat4& parent,
                                                                   int depth) -> Status {
        if (index < 0 || static_cast<std::size_t>(index) >= m.nodes.size())
            return make_error(src + ": node index " + std::to_string(index) + " out of range");
        if (depth > 256 || !visiting.insert(index).second)
            return make_error(src + ": node hierarchy has a cycle");
        const tinygltf::Node& node = m.nodes[static_cast<std::size_t>(index)];
        const glm::dmat4 world = parent * gltf_node_matrix(node);
        const json extras = to_json(node.extras);
        if (extras.is_object() && extras.contains("sffd_cloud") && node.children.size() == 1) {
            // One of our splat nodes: keep the arrays exactly as stored, Transform and origin apart.
            const int child = node.children[0];
            if (child < 0 || static_cast<std::size_t>(child) >= m.nodes.size())
                return make_error(src + ": bad child of splat node");
            const tinygltf::Node& cn = m.nodes[static_cast<std::size_t>(child)];
            GltfCloudIn cloud;
            cloud.name = node.name;
            cloud.id = extras["sffd_cloud"].is_number_integer() ? extras["sffd_cloud"].get<int>() : -1;
            cloud.transform = node_trs(node);
            // A zero quaternion has no rotation to normalise to, a zero scale flattens the cloud: refused
            // (others are kept exactly as stored, for round trips).
            const glm::dquat& q = cloud.transform.rotation;
            if (!(glm::length(q) > 1e-12) || !std::isfinite(glm::length(q)))
                return make_error(src + ": splat node '" + node.name +
                                  "': rotation is a zero or non-finite quaternion");
            const glm::dvec3& sc = cloud.transform.scale;
            if (sc.x == 0.0 || sc.y == 0.0 || sc.z == 0.0 || !std::isfinite(sc.x + sc.y + sc.z))
                return make_error(src + ": splat node '" + node.name +
                                  "': scale has a zero or non-finite component");
            for (int a = 0; a < 3; ++a)
                if (!std::isfinite(cloud.transform.translation[a]))
                    return make_error(src + ": splat node '" + node.name + "': translation is not finite");
            if (cn.translation.size() == 3)
                cloud.cloud.origin = glm::dvec3(cn.translation[0], cn.translation[1], cn.translation[2]);
            if (cn.mesh >= 0 && static_cast<std::size_t>(cn.mesh) >= m.meshes.size())
                return make_error(src + ": splat node '" + node.name + "': mesh index " +
                                  std::to_string(cn.mesh) + " out of range (" +
                                  std::to_string(m.meshes.size()) + " meshes)");
            if (cn.mesh >= 0) {
                const auto& prims = m.meshes[static_cast<std::size_t>(cn.mesh)].primitives;
                if (prims.size() != 1 || prims[0].mode != TINYGLTF_MODE_POINTS)
                    return make_error(src + ": splat node '" + node.name +
                                      "' must hold one POINTS primitive");
                Geometry unused;
                if (auto s = read_primitive(*model, prims[0], glm::dmat4(1.0), src, unused, material_map,
                                            &cloud.cloud, &cloud.material);
                    !s)
                    return s;
                if (auto s = read_point_columns(*model, prims[0].attributes, cloud.cloud.size(),
                                                src + ": splat node '" + node.name + "'", cloud.flags,
                                                cloud.weights);
                    !s)
                    return s;
            }
            const std::size_t n = cloud.cloud.size();
            for (const auto& p : cloud.cloud.positions)
                if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                    return make_error(src + ": splat node '" + node.name + "' has a non-finite position");
            if ((!cloud.cloud.axis_u.empty() && cloud.cloud.axis_u.size() != n) ||
                (!cloud.cloud.normals.empty() && cloud.cloud.normals.size() != n) ||
                (!cloud.cloud.uv_axes.empty() && cloud.cloud.uv_axes.size() != n))
                return make_error(src + ": splat node '" + node.name +
                                  "' has attribute arrays of the wrong length");
            out.clouds.push_back(std::move(cloud));
        } else {
            if (node.mesh >= 0) {
                if (static_cast<std::size_t>(node.mesh) >= m.meshes.size())
                    return make_error(src + ": node '" + node.name + "': mesh index " +
                                      std::to_string(node.mesh) + " out of range (" +
                                      std::to_string(m.meshes.size()) + " meshes)");
                for (const auto& prim : m.meshes[static_cast<std::size_t>(node.mesh)].primitives) {
                    if (scene_file && prim.extensions.count("KHR_gaussian_splatting"))
                        continue;  // systems/gaussian's
                    if (auto s = read_primitive(*model, prim, world, src, out.other, material_map, nullptr,
                                                nullptr);
                        !s)
                        return s;
                }
            }
            for (int c : node.children)
                if (auto s = visit(c, world, depth + 1); !s) return s;
        }
        visiting.erase(index);
        return {};
    };
    for (int r : roots)
        if (auto s = visit(r, glm::dmat4(1.0), 0); !s) return s.error();
    // Attribute arrays padded lazily: complete them to the point count.
    Geometry& g = out.other;
    pad_attributes(g);
    for (const auto& p : g.positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return make_error(src + ": a node transform or position is not finite");
    g.attributes = {"POSITION"};
    if (!g.normals.empty()) g.attributes.push_back("NORMAL");
    if (!g.colors.empty()) g.attributes.push_back("COLOR_0");
    if (!g.uvs.empty()) g.attributes.push_back("TEXCOORD_0");
    if (!g.axis_u.empty()) g.attributes.push_back("_AXIS_U/_AXIS_V");
    if (!g.uv_axes.empty()) g.attributes.push_back("_UV_AXES");
    return out;
}

Result<Geometry> read_gltf_geometry(const fs::path& path) {
    auto contents = read_gltf(path);
    if (!contents) return contents.error();
    Geometry g = std::move(contents->other);
    // Our splat nodes join the rest in world space (positions, normals and axes transformed).
    bool single = contents->clouds.size() == 1 && g.positions.empty();
    for (GltfCloudIn& c : contents->clouds) {
        const Transform& t = c.transform;
        const glm::dmat4 world = model_matrix(&t);
        const glm::dmat3 linear(world);
        const glm::dmat3 nm = glm::transpose(glm::inverse(linear));
        const std::size_t base = g.positions.size();
        const std::size_t n = c.cloud.size();
        for (const auto& p : c.cloud.positions)
            g.positions.push_back(glm::dvec3(world * glm::dvec4(c.cloud.origin + glm::dvec3(p), 1.0)));
        auto extend = [&](auto& dst, const auto& src_arr, auto fn, auto def) {
            if (src_arr.empty() && dst.empty()) return;
            dst.resize(base, def);
            for (std::size_t i = 0; i < n; ++i) dst.push_back(src_arr.empty() ? def : fn(src_arr[i]));
        };
        extend(
            g.normals, c.cloud.normals,
            [&](const glm::vec3& v) { return glm::vec3(glm::normalize(nm * glm::dvec3(v))); },
            glm::vec3(0.0f));
        extend(
            g.axis_u, c.cloud.axis_u, [&](const glm::vec3& v) { return glm::vec3(linear * glm::dvec3(v)); },
            glm::vec3(0.0f));
        extend(
            g.axis_v, c.cloud.axis_v, [&](const glm::vec3& v) { return glm::vec3(linear * glm::dvec3(v)); },
            glm::vec3(0.0f));
        extend(
            g.colors, c.cloud.colors, [](std::uint32_t v) { return v; }, 0xffffffffu);
        extend(
            g.uvs, c.cloud.uvs, [](const glm::vec2& v) { return v; }, glm::vec2(0.0f));
        extend(
            g.uv_axes, c.cloud.uv_axes, [](const glm::vec4& v) { return v; }, glm::vec4(0.0f));
        if (single) {
            g.splat_texture = c.cloud.texture;
            g.splat_material = c.material;
            const bool identity = t.translation == glm::dvec3(0.0) && t.rotation == glm::dquat(1, 0, 0, 0) &&
                                  t.scale == glm::dvec3(1.0);
            if (identity) {
                g.has_origin = true;
                g.origin = c.cloud.origin;
            }
        }
    }
    pad_attributes(g);
    if (g.positions.empty()) return make_error(path.string() + ": no points or triangles in the glTF scene");
    return g;
}

}  // namespace sffd::assets
