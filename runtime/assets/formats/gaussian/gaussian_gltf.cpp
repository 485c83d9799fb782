#include "runtime/assets/formats/gaussian/gaussian_gltf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/formats/surface/gltf_model.h"
#include "runtime/core/file_io.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

constexpr int kFloat = 5126, kUByte = 5121, kUInt = 5125;
const std::string kExt = "KHR_gaussian_splatting";

// The attributes KHR_gaussian_splatting allows: float or normalised (unsigned) byte / short, never
// unsigned int (which the shared reader also accepts, for indices).
Result<std::vector<double>> read_accessor(const assets::GltfModel& model, int index, int components,
                                          const std::string& where, const std::string& name) {
    const tinygltf::Model& m = model.gltf;
    if (index >= 0 && std::size_t(index) < m.accessors.size() &&
        m.accessors[std::size_t(index)].componentType == kUInt)
        return make_error(where + ": " + name + ": unsupported component type " + std::to_string(kUInt));
    return assets::read_gltf_accessor(model, index, components, where, name);
}

std::string sh_name(int l, int n) {
    return kExt + ":SH_DEGREE_" + std::to_string(l) + "_COEF_" + std::to_string(n);
}

}  // namespace

Result<GaussianCloud> read_primitive(const assets::GltfModel& model, const tinygltf::Primitive& prim,
                                     const std::string& where) {
    const tinygltf::Model& m = model.gltf;
    auto attr = [&](const std::string& name) {
        auto it = prim.attributes.find(name);
        return it == prim.attributes.end() ? -1 : it->second;
    };
    for (const char* name : {"POSITION", "KHR_gaussian_splatting:ROTATION", "KHR_gaussian_splatting:SCALE",
                             "KHR_gaussian_splatting:OPACITY"})
        if (attr(name) < 0) return make_error(where + ": missing attribute " + name);
    if (const int a = attr("POSITION");
        std::size_t(a) < m.accessors.size() && m.accessors[std::size_t(a)].count > kMaxGaussians)
        return make_error(where + ": POSITION declares " + std::to_string(m.accessors[std::size_t(a)].count) +
                          " Gaussians, more than the " + std::to_string(kMaxGaussians) + "-Gaussian limit");
    // Positions and SH coefficients (most of a file) are decoded as floats straight into the cloud; the
    // values are those of the doubles the rest is read as, rounded to float as the cloud stores them.
    GaussianCloud g;
    auto no_uint = [&](int index, const std::string& name) -> Status {
        if (index >= 0 && std::size_t(index) < m.accessors.size() &&
            m.accessors[std::size_t(index)].componentType == kUInt)
            return make_error(where + ": " + name + ": unsupported component type " + std::to_string(kUInt));
        return {};
    };
    if (Status s = no_uint(attr("POSITION"), "POSITION"); !s) return s.error();
    if (Status s = assets::read_gltf_accessor_into(model, attr("POSITION"), where, "POSITION", g.positions);
        !s)
        return s.error();
    const std::size_t n = g.positions.size();
    auto get = [&](const std::string& name, int comps) -> Result<std::vector<double>> {
        auto v = read_accessor(model, attr(name), comps, where, name);
        if (v && v->size() != n * std::size_t(comps))
            return make_error(where + ": " + name + " has " + std::to_string(v->size() / std::size_t(comps)) +
                              " elements, POSITION " + std::to_string(n));
        return v;
    };
    auto rot = get(kExt + ":ROTATION", 4);
    if (!rot) return rot.error();
    auto scale = get(kExt + ":SCALE", 3);
    if (!scale) return scale.error();
    auto opacity = get(kExt + ":OPACITY", 1);
    if (!opacity) return opacity.error();
    int degree = 0;
    for (int l = 1; l <= 3; ++l) {
        int present = 0;
        for (int c = 0; c <= 2 * l; ++c) present += attr(sh_name(l, c)) >= 0;
        if (present == 0) continue;
        if (present != 2 * l + 1)
            return make_error(where + ": SH degree " + std::to_string(l) + " is partial (" +
                              std::to_string(present) + " of " + std::to_string(2 * l + 1) +
                              " coefficients)");
        // Degree l needs every band below it; silently dropping the higher bands would lose data.
        if (degree != l - 1)
            return make_error(where + ": SH degree " + std::to_string(l) + " coefficients without degree " +
                              std::to_string(degree + 1));
        degree = l;
    }
    g.sh_degree = degree;
    const int K = sh_coeffs(degree);
    // Every coefficient is written below (the DC term from SH or COLOR_0, every band up to the degree).
    assets::resize_for_overwrite(g.sh, n * std::size_t(K) * 3);
    // Coefficient k of every Gaussian, into its place in the interleaved array.
    auto coefficient = [&](const std::string& name, std::size_t k) -> Status {
        const int a = attr(name);
        if (Status s = no_uint(a, name); !s) return s;
        if (a >= 0 && std::size_t(a) < m.accessors.size() && m.accessors[std::size_t(a)].count != n)
            return make_error(where + ": " + name + " has " +
                              std::to_string(m.accessors[std::size_t(a)].count) + " elements, POSITION " +
                              std::to_string(n));
        return assets::read_gltf_accessor_strided(model, a, 3, where, name, g.sh.data() + k * 3,
                                                  std::size_t(K) * 3, n);
    };
    if (attr(sh_name(0, 0)) >= 0) {
        if (Status s = coefficient(sh_name(0, 0), 0); !s) return s.error();
    } else if (attr("COLOR_0") >= 0) {
        const std::size_t ci = std::size_t(attr("COLOR_0"));
        const int comps = ci < m.accessors.size() && m.accessors[ci].type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
        auto col = get("COLOR_0", comps);
        if (!col) return col.error();
        for (std::size_t i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c)
                g.sh[i * std::size_t(K) * 3 + std::size_t(c)] =
                    float(((*col)[i * std::size_t(comps) + std::size_t(c)] - 0.5) / kShDc);
    } else {
        return make_error(where + ": missing attribute " + sh_name(0, 0) + " (and no COLOR_0)");
    }
    for (int l = 1; l <= degree; ++l)
        for (int c = 0; c <= 2 * l; ++c)
            if (Status s = coefficient(sh_name(l, c), std::size_t(l * l + c)); !s) return s.error();
    g.scales.reserve(n);
    g.opacities.reserve(n);
    g.rotations.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto fail = [&](const char* why) {
            return make_error(where + ": Gaussian " + std::to_string(i) + ": " + why);
        };
        const glm::dvec3 s((*scale)[i * 3], (*scale)[i * 3 + 1], (*scale)[i * 3 + 2]);
        if (s.x < 0 || s.y < 0 || s.z < 0)
            return fail(
                "negative scale (KHR_gaussian_splatting scales are linear; log-space data from the review "
                "draft?)");
        g.scales.push_back(glm::vec3(s));
        const double o = (*opacity)[i];
        if (o < 0.0 || o > 1.0) return fail("opacity outside [0, 1]");
        g.opacities.push_back(float(o));
        glm::quat q;  // the file stores x y z w
        if (!normalize_quaternion((*rot)[i * 4 + 3], (*rot)[i * 4], (*rot)[i * 4 + 1], (*rot)[i * 4 + 2], q))
            return fail("zero-length rotation quaternion");
        g.rotations.push_back(q);
    }
    return g;
}

namespace {

void append(GaussianCloud& a, const GaussianCloud& b, int degree) {
    const int ka = sh_coeffs(a.sh_degree), kb = sh_coeffs(b.sh_degree), k = sh_coeffs(degree);
    std::vector<float> sh;
    sh.reserve((a.size() + b.size()) * std::size_t(k) * 3);
    for (std::size_t i = 0; i < a.size(); ++i)
        sh.insert(sh.end(), a.sh.begin() + std::ptrdiff_t(i * std::size_t(ka) * 3),
                  a.sh.begin() + std::ptrdiff_t((i * std::size_t(ka) + std::size_t(k)) * 3));
    for (std::size_t i = 0; i < b.size(); ++i)
        sh.insert(sh.end(), b.sh.begin() + std::ptrdiff_t(i * std::size_t(kb) * 3),
                  b.sh.begin() + std::ptrdiff_t((i * std::size_t(kb) + std::size_t(k)) * 3));
    a.sh = std::move(sh);
    a.sh_degree = degree;
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    a.scales.insert(a.scales.end(), b.scales.begin(), b.scales.end());
    a.rotations.insert(a.rotations.end(), b.rotations.begin(), b.rotations.end());
    a.opacities.insert(a.opacities.end(), b.opacities.begin(), b.opacities.end());
}

}  // namespace

Result<GaussianCloud> read_gltf(const fs::path& path, NodePlacement place) {
    const std::string src = path.string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return make_error(src + ": no such file");
    assets::GltfModel model;
    if (Status s = assets::load_gltf_model(path, model); !s) return s.error();
    const tinygltf::Model& m = model.gltf;
    std::vector<GaussianCloud> parts;
    // glTF node graphs are forests: a node listed as a child twice (two parents, or twice by one) would
    // be visited once per path, exponentially often in a DAG. Refused up front; each node is then
    // visited at most once.
    std::vector<int> parent_of(m.nodes.size(), -1);
    for (std::size_t i = 0; i < m.nodes.size(); ++i)
        for (int c : m.nodes[i].children) {
            if (c < 0 || std::size_t(c) >= m.nodes.size())
                return make_error(src + ": node " + std::to_string(i) + ": child index " + std::to_string(c) +
                                  " out of range");
            if (parent_of[std::size_t(c)] >= 0)
                return make_error(src + ": node " + std::to_string(c) + " is listed as a child of node " +
                                  std::to_string(parent_of[std::size_t(c)]) + " and of node " +
                                  std::to_string(i) + " (a glTF node has at most one parent)");
            parent_of[std::size_t(c)] = int(i);
        }
    std::vector<char> visited(m.nodes.size(), 0);
    std::size_t depth = 0;
    std::function<Status(int, const glm::dmat4&)> visit = [&](int index, const glm::dmat4& parent) -> Status {
        if (index < 0 || std::size_t(index) >= m.nodes.size())
            return make_error(src + ": node index " + std::to_string(index) + " out of range");
        if (visited[std::size_t(index)])
            return make_error(src + ": node " + std::to_string(index) +
                              " is reached twice (a cycle, or a root that is also a child)");
        if (depth >= 256) return make_error(src + ": node hierarchy deeper than 256 levels");
        visited[std::size_t(index)] = 1;
        ++depth;
        const tinygltf::Node& node = m.nodes[std::size_t(index)];
        const glm::dmat4 world = parent * assets::gltf_node_matrix(node);
        if (node.mesh >= 0 && std::size_t(node.mesh) < m.meshes.size()) {
            const auto& prims = m.meshes[std::size_t(node.mesh)].primitives;
            for (std::size_t p = 0; p < prims.size(); ++p) {
                if (prims[p].extensions.find(kExt) == prims[p].extensions.end()) continue;
                const std::string where =
                    src + ": mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p);
                if (prims[p].mode != TINYGLTF_MODE_POINTS)
                    return make_error(where + ": KHR_gaussian_splatting needs mode POINTS");
                auto g = read_primitive(model, prims[p], where);
                if (!g) return g.error();
                if (world != glm::dmat4(1.0)) place(*g, glm::dmat3(world), glm::dvec3(world[3]));
                parts.push_back(std::move(*g));
            }
        }
        for (int c : node.children)
            if (Status s = visit(c, world); !s) return s;
        --depth;
        return {};
    };
    std::vector<int> roots;
    if (!m.scenes.empty()) {
        const std::size_t s = m.defaultScene >= 0 && std::size_t(m.defaultScene) < m.scenes.size()
                                  ? std::size_t(m.defaultScene)
                                  : 0;
        roots = m.scenes[s].nodes;
    } else {  // no scene: the roots are the nodes that are nobody's child
        for (std::size_t i = 0; i < m.nodes.size(); ++i)
            if (parent_of[i] < 0) roots.push_back(int(i));
    }
    for (int r : roots)
        if (Status s = visit(r, glm::dmat4(1.0)); !s) return s.error();
    if (parts.empty()) return make_error(src + ": no KHR_gaussian_splatting primitive");
    int degree = 3;
    for (const GaussianCloud& p : parts) degree = std::min(degree, p.sh_degree);
    GaussianCloud out;
    out.sh_degree = degree;
    if (parts.size() == 1) out = std::move(parts.front());  // the usual file: nothing to merge or copy
    else
        for (const GaussianCloud& p : parts) append(out, p, degree);
    // glTF's frame (y up, +z the front, x left) is the 3DGS PLY frame turned 180 degrees about z
    // (gaussian_axes.h): the world-space cloud is turned into the internal frame.
    turn_axes(out, AxisTurn::z180);
    return out;
}

GltfDeclaration gltf_declaration(const fs::path& path) {
    GltfDeclaration d;
    std::string text;
    {
        std::ifstream in(path, std::ios::binary);
        char head[20] = {};
        in.read(head, sizeof head);
        if (in.gcount() >= 4 && std::memcmp(head, "glTF", 4) == 0) {
            if (in.gcount() < 20) return d;
            std::uint32_t len = 0, type = 0;
            std::memcpy(&len, head + 12, 4), std::memcpy(&type, head + 16, 4);
            if (type != 0x4E4F534Au || len > kMaxJsonFileBytes) return d;
            text.resize(len);
            in.read(text.data(), std::streamsize(len));
            text.resize(std::size_t(std::max<std::streamsize>(in.gcount(), 0)));
        } else {
            auto all = read_file(path, kMaxResourceBytes);  // a .gltf may carry base64 buffers
            if (!all) return d;
            text = std::move(*all);
        }
    }
    if (!check_json_depth(text, path.string())) return d;
    const nlohmann::json doc = nlohmann::json::parse(text, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return d;
    for (const char* key : {"extensionsUsed", "extensionsRequired"})
        if (auto it = doc.find(key); it != doc.end() && it->is_array())
            for (const auto& e : *it)
                d.gaussian_splatting =
                    d.gaussian_splatting || (e.is_string() && e.get<std::string>() == kExt);
    if (auto it = doc.find("extensions"); it != doc.end() && it->is_object())
        d.sffd_scene = it->contains("SFFD_scene");
    return d;
}

namespace {

// One attribute of a primitive: its accessor's description and a fill of its rows [first, first + count)
// (row_bytes each, a multiple of 4) into `out`, so the binary buffer is either assembled in memory
// (append_primitive) or streamed to the file a block of rows at a time (write_glb), turned on the way when
// the file's axes differ from the cloud's.
struct AttributeSource {
    std::string name;
    int component = kFloat;
    const char* type = "VEC3";
    bool normalized = false;
    nlohmann::json lo, hi;
    std::size_t row_bytes = 12;
    std::function<void(std::size_t first, std::size_t count, unsigned char* out)> fill;
};

std::vector<AttributeSource> attribute_sources(const GaussianCloud& g, const AxisTurnParts& t) {
    const std::size_t n = g.size();
    const std::size_t K = std::size_t(sh_coeffs(g.sh_degree));
    std::vector<AttributeSource> a;
    glm::vec3 lo(0.0f), hi(0.0f);
    if (n > 0) lo = hi = g.positions[0] * t.scale;
    for (const glm::vec3& p : g.positions) lo = glm::min(lo, p * t.scale), hi = glm::max(hi, p * t.scale);
    a.push_back({"POSITION",
                 kFloat,
                 "VEC3",
                 false,
                 {lo.x, lo.y, lo.z},
                 {hi.x, hi.y, hi.z},
                 12,
                 [&g, t](std::size_t first, std::size_t count, unsigned char* out) {
                     for (std::size_t i = 0; i < count; ++i) {
                         const glm::vec3 p = g.positions[first + i] * t.scale;
                         std::memcpy(out + i * 12, &p[0], 12);
                     }
                 }});
    a.push_back({"COLOR_0",
                 kUByte,
                 "VEC4",
                 true,
                 {},
                 {},
                 4,
                 [&g, K](std::size_t first, std::size_t count, unsigned char* out) {
                     for (std::size_t i = 0; i < count; ++i) {
                         const std::size_t j = first + i;
                         for (std::size_t c = 0; c < 3; ++c)
                             out[i * 4 + c] = static_cast<unsigned char>(std::lround(
                                 std::clamp(0.5 + kShDc * double(g.sh[j * K * 3 + c]), 0.0, 1.0) * 255.0));
                         out[i * 4 + 3] =
                             static_cast<unsigned char>(std::lround(double(g.opacities[j]) * 255.0));
                     }
                 }});
    a.push_back({kExt + ":ROTATION",
                 kFloat,
                 "VEC4",
                 false,
                 {},
                 {},
                 16,
                 [&g, t](std::size_t first, std::size_t count, unsigned char* out) {
                     for (std::size_t i = 0; i < count; ++i) {
                         const glm::quat q = t.rotation * g.rotations[first + i];
                         const float xyzw[4] = {q.x, q.y, q.z, q.w};
                         std::memcpy(out + i * 16, xyzw, 16);
                     }
                 }});
    a.push_back({kExt + ":SCALE",
                 kFloat,
                 "VEC3",
                 false,
                 {},
                 {},
                 12,
                 [&g](std::size_t first, std::size_t count, unsigned char* out) {
                     std::memcpy(out, &g.scales[first], count * 12);
                 }});
    a.push_back({kExt + ":OPACITY",
                 kFloat,
                 "SCALAR",
                 false,
                 {},
                 {},
                 4,
                 [&g](std::size_t first, std::size_t count, unsigned char* out) {
                     std::memcpy(out, &g.opacities[first], count * 4);
                 }});
    for (int l = 0; l <= g.sh_degree; ++l)
        for (int c = 0; c <= 2 * l; ++c) {
            const std::size_t k = std::size_t(l * l + c);
            a.push_back(
                {sh_name(l, c),
                 kFloat,
                 "VEC3",
                 false,
                 {},
                 {},
                 12,
                 [&g, K, k, sign = t.sh_sign[k]](std::size_t first, std::size_t count, unsigned char* out) {
                     for (std::size_t i = 0; i < count; ++i) {
                         const float* src = &g.sh[((first + i) * K + k) * 3];
                         const float v[3] = {src[0] * sign, src[1] * sign, src[2] * sign};
                         std::memcpy(out + i * 12, v, 12);
                     }
                 }});
        }
    return a;
}

// Adds the attributes' buffer views (from byte `offset` of buffer 0, back to back: every row size is a
// multiple of 4) and accessors to `doc`, and returns the POINTS primitive, `doc` listing the extension.
nlohmann::json add_primitive(nlohmann::json& doc, const std::vector<AttributeSource>& attributes,
                             std::size_t offset, std::size_t n) {
    if (!doc.contains("bufferViews")) doc["bufferViews"] = nlohmann::json::array();
    if (!doc.contains("accessors")) doc["accessors"] = nlohmann::json::array();
    nlohmann::json& views = doc["bufferViews"];
    nlohmann::json& accessors = doc["accessors"];
    nlohmann::json names = nlohmann::json::object();
    for (const AttributeSource& a : attributes) {
        const std::size_t bytes = a.row_bytes * n;
        views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", 34962}});
        offset += bytes;
        nlohmann::json acc = {
            {"bufferView", views.size() - 1}, {"componentType", a.component}, {"count", n}, {"type", a.type}};
        if (a.normalized) acc["normalized"] = true;
        if (!a.lo.is_null()) acc["min"] = a.lo, acc["max"] = a.hi;
        accessors.push_back(acc);
        names[a.name] = accessors.size() - 1;
    }
    if (!doc.contains("extensionsUsed")) doc["extensionsUsed"] = nlohmann::json::array();
    bool listed = false;
    for (const auto& e : doc["extensionsUsed"])
        listed = listed || (e.is_string() && e.get<std::string>() == kExt);
    if (!listed) doc["extensionsUsed"].push_back(kExt);
    return {{"attributes", names},
            {"mode", 0},
            {"extensions",
             {{kExt,
               {{"kernel", "ellipse"},
                {"colorSpace", "srgb_rec709_display"},
                {"sortingMethod", "cameraDistance"},
                {"projection", "perspective"}}}}}};
}

std::size_t primitive_bytes(const std::vector<AttributeSource>& attributes, std::size_t n) {
    std::size_t bytes = 0;
    for (const AttributeSource& a : attributes) bytes += a.row_bytes * n;
    return bytes;
}

}  // namespace

Status append_primitive(nlohmann::json& doc, std::string& bin, const GaussianCloud& g,
                        nlohmann::json& primitive, const std::string& where) {
    if (Status s = validate(g, where); !s) return s;
    const std::size_t n = g.size();
    const std::vector<AttributeSource> attributes = attribute_sources(g, AxisTurnParts{});
    while (bin.size() % 4) bin.push_back('\0');
    std::size_t offset = bin.size();
    primitive = add_primitive(doc, attributes, offset, n);
    // Grown once and filled in place: no per-attribute temporaries, no copies.
    bin.resize(offset + primitive_bytes(attributes, n));
    for (const AttributeSource& a : attributes) {
        a.fill(0, n, reinterpret_cast<unsigned char*>(bin.data()) + offset);
        offset += a.row_bytes * n;
    }
    return {};
}

Status write_glb(const fs::path& path, const GaussianCloud& g) {
    if (Status s = validate(g, path.string()); !s) return s;
    // Written in glTF's frame: the internal (3DGS PLY) frame turned 180 degrees about z, as read_gltf
    // turns it back. Each block of rows is turned as it is written: no turned copy of the cloud and no
    // binary chunk assembled in memory (writing 1M Gaussians of degree 3 spent most of its 4 s on those
    // two copies of 250 MB and the page faults of their fresh memory).
    const AxisTurnParts turn = axis_turn_parts(AxisTurn::z180);
    const std::vector<AttributeSource> attributes = attribute_sources(g, turn);
    const std::size_t n = g.size();
    nlohmann::json doc = nlohmann::json::object();
    const nlohmann::json prim = add_primitive(doc, attributes, 0, n);
    const std::uint64_t bin_bytes = primitive_bytes(attributes, n);
    nlohmann::json node = {{"mesh", 0}, {"name", "gaussians"}};
    const glm::dvec3 origin = g.origin * glm::dvec3(turn.scale);
    if (origin != glm::dvec3(0.0)) node["translation"] = {origin.x, origin.y, origin.z};
    doc["asset"] = {{"version", "2.0"}, {"generator", "splatffd"}};
    doc["scene"] = 0;
    doc["scenes"] = {{{"nodes", {0}}}};
    doc["nodes"] = {node};
    doc["meshes"] = {{{"primitives", {prim}}}};
    doc["buffers"] = {{{"byteLength", bin_bytes}}};
    const auto write_bin = [&](std::FILE* f) {
        constexpr std::size_t kRows = 1 << 16;
        std::vector<unsigned char> block;
        for (const AttributeSource& a : attributes)
            for (std::size_t first = 0; first < n; first += kRows) {
                const std::size_t rows = std::min(kRows, n - first);
                block.resize(rows * a.row_bytes);
                a.fill(first, rows, block.data());
                if (std::fwrite(block.data(), 1, block.size(), f) != block.size()) return false;
            }
        return true;
    };
    return assets::write_glb_file(path, doc.dump(), bin_bytes, write_bin, "a Gaussian cloud");
}

}  // namespace sffd::gaussian
