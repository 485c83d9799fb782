// Writing splat clouds as glTF 2.0 / GLB (gltf_io.h): the JSON is built with nlohmann::json so the layout
// is exactly what content/README.md documents; one binary buffer, embedded PNG textures, atomic save.
#include "runtime/assets/formats/surface/gltf_io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include <nlohmann/json.hpp>
#include <stb/stb_image_write.h>

#include "runtime/assets/formats/surface/gltf_detail.h"
#include "runtime/assets/formats/surface/gltf_point_columns.h"
#include "runtime/core/atomic_file.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace gltf_detail;

namespace {

std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((in.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const std::uint32_t v = (std::uint32_t(std::uint8_t(in[i])) << 16) |
                                (std::uint32_t(std::uint8_t(in[i + 1])) << 8) | std::uint8_t(in[i + 2]);
        out += t[v >> 18];
        out += t[(v >> 12) & 63];
        out += t[(v >> 6) & 63];
        out += t[v & 63];
    }
    if (i < in.size()) {
        std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16;
        if (i + 1 < in.size()) v |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
        out += t[v >> 18];
        out += t[(v >> 12) & 63];
        out += i + 1 < in.size() ? t[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

struct BinBuilder {
    std::string bin;
    json views = json::array();
    json accessors = json::array();

    int view(const void* data, std::size_t bytes, int target) {
        while (bin.size() % 4) bin.push_back('\0');
        json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
        if (target) v["target"] = target;
        bin.append(static_cast<const char*>(data), bytes);
        views.push_back(v);
        return static_cast<int>(views.size()) - 1;
    }
    template <class T>
    int accessor(const std::vector<T>& data, int component_type, const char* type, std::size_t components,
                 bool normalized = false) {
        const int v = view(data.data(), data.size() * sizeof(T), 34962);
        json a = {
            {"bufferView", v}, {"componentType", component_type}, {"count", data.size()}, {"type", type}};
        if (normalized) a["normalized"] = true;
        (void)components;
        accessors.push_back(a);
        return static_cast<int>(accessors.size()) - 1;
    }
};

json vec(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

void png_append(void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data),
                                               static_cast<std::size_t>(size));
}

}  // namespace

Status write_gltf(const fs::path& path, const std::vector<GltfCloudOut>& clouds,
                  const std::string& sffd_scene_json, const std::vector<GltfAppend>& append) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool binary = ext == ".glb";
    if (!binary && ext != ".gltf") return make_error(path.string() + ": expected a .gltf or .glb file name");

    BinBuilder b;
    // The buffer grows once for the clouds' attributes (each doubling copied all before it).
    std::size_t attribute_bytes = 0;
    for (const GltfCloudOut& out : clouds) {
        const SplatCloud& c = *out.cloud;
        attribute_bytes += c.positions.size() * 12 + c.normals.size() * 12 + c.colors.size() * 8 +
                           c.uvs.size() * 8 + (c.axis_u.size() + c.axis_v.size()) * 12 +
                           c.uv_axes.size() * 16 + 8 * 4;  // alignment
    }
    b.bin.reserve(attribute_bytes);
    json nodes = json::array(), meshes = json::array(), materials = json::array(), textures = json::array(),
         images = json::array();
    json roots = json::array();
    for (const GltfCloudOut& out : clouds) {
        const SplatCloud& c = *out.cloud;
        const SplatMaterial cm = out.material ? *out.material : SplatMaterial{};
        const std::size_t n = c.size();
        auto sized = [&](std::size_t s) { return s == 0 || s == n; };
        if (!sized(c.normals.size()) || !sized(c.colors.size()) || !sized(c.uvs.size()) ||
            !sized(c.axis_u.size()) || c.axis_u.size() != c.axis_v.size() || !sized(c.uv_axes.size()))
            return make_error(path.string() + ": cloud '" + out.name +
                              "' has attribute arrays of the wrong length");
        json attributes = json::object();
        if (n > 0) {
            const int ip = b.accessor(c.positions, kFloat, "VEC3", 3);
            glm::vec3 lo(c.positions[0]), hi(c.positions[0]);
            for (const auto& p : c.positions) {
                lo = glm::min(lo, p);
                hi = glm::max(hi, p);
            }
            b.accessors[ip]["min"] = {lo.x, lo.y, lo.z};
            b.accessors[ip]["max"] = {hi.x, hi.y, hi.z};
            attributes["POSITION"] = ip;
            if (!c.normals.empty()) attributes["NORMAL"] = b.accessor(c.normals, kFloat, "VEC3", 3);
            if (!c.colors.empty()) {
                std::vector<std::uint16_t> lin(n * 4);
                for (std::size_t i = 0; i < n; ++i) {
                    const std::uint32_t col = c.colors[i];
                    lin[4 * i] = srgb8_to_linear16(col & 255u);
                    lin[4 * i + 1] = srgb8_to_linear16((col >> 8) & 255u);
                    lin[4 * i + 2] = srgb8_to_linear16((col >> 16) & 255u);
                    lin[4 * i + 3] =
                        static_cast<std::uint16_t>((col >> 24) * 257u);  // alpha is linear already
                }
                const int v = b.view(lin.data(), lin.size() * 2, 34962);
                b.accessors.push_back({{"bufferView", v},
                                       {"componentType", kUShort},
                                       {"count", n},
                                       {"type", "VEC4"},
                                       {"normalized", true}});
                attributes["COLOR_0"] = static_cast<int>(b.accessors.size()) - 1;
            }
            if (!c.uvs.empty()) attributes["TEXCOORD_0"] = b.accessor(c.uvs, kFloat, "VEC2", 2);
            if (!c.axis_u.empty()) {
                attributes["_AXIS_U"] = b.accessor(c.axis_u, kFloat, "VEC3", 3);
                attributes["_AXIS_V"] = b.accessor(c.axis_v, kFloat, "VEC3", 3);
                if (!c.uv_axes.empty()) attributes["_UV_AXES"] = b.accessor(c.uv_axes, kFloat, "VEC4", 4);
            }
            if (Status s = append_point_columns(b.accessors, b.views, b.bin, attributes, n, out.flags,
                                                out.weights, path.string() + ": cloud '" + out.name + "'");
                !s)
                return s;
        }
        json material = {
            {"name", out.name + ".material"},
            {"pbrMetallicRoughness",
             {{"baseColorFactor", {cm.base_color.x, cm.base_color.y, cm.base_color.z, cm.base_color.w}},
              {"metallicFactor", 0.0},
              {"roughnessFactor", 1.0}}},
            {"extras", {{"sffd_specular", cm.specular}, {"sffd_shininess", cm.shininess}}}};
        if (!c.texture.path.empty()) material["extras"]["sffd_texture_path"] = c.texture.path;
        if (!c.texture.rgba8.empty()) {
            const int w = c.texture.width, h = c.texture.height;
            if (w <= 0 || h <= 0 ||
                c.texture.rgba8.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4)
                return make_error(path.string() + ": cloud '" + out.name +
                                  "' has a texture of the wrong size");
            std::string png;
            if (!stbi_write_png_to_func(png_append, &png, w, h, 4, c.texture.rgba8.data(), w * 4))
                return make_error(path.string() + ": cannot encode the texture as PNG");
            const int v = b.view(png.data(), png.size(), 0);
            images.push_back({{"bufferView", v}, {"mimeType", "image/png"}});
            textures.push_back({{"source", images.size() - 1}, {"sampler", 0}});
            material["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", textures.size() - 1}};
        }
        materials.push_back(material);
        json prim = {{"mode", 0}, {"attributes", attributes}, {"material", materials.size() - 1}};
        meshes.push_back({{"name", out.name}, {"primitives", json::array({prim})}});

        const Transform t = out.transform ? *out.transform : Transform{};
        json parent = {{"name", out.name},
                       {"translation", vec(t.translation)},
                       {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}},
                       {"scale", vec(t.scale)},
                       {"children", {nodes.size() + 1}},
                       {"extras", {{"sffd_cloud", out.id}}}};
        json child = {
            {"name", out.name + ".origin"}, {"translation", vec(c.origin)}, {"mesh", meshes.size() - 1}};
        roots.push_back(nodes.size());
        nodes.push_back(parent);
        nodes.push_back(child);
    }

    json doc = {{"asset", {{"version", "2.0"}, {"generator", "SplatFFD " SFFD_VERSION}}},
                {"scene", 0},
                {"scenes", {{{"name", "scene"}, {"nodes", roots}}}},
                {"nodes", nodes}};
    if (!meshes.empty()) doc["meshes"] = meshes;
    if (!materials.empty()) doc["materials"] = materials;
    if (!textures.empty()) {
        doc["textures"] = textures;
        doc["images"] = images;
        doc["samplers"] = {{{"magFilter", 9729}, {"minFilter", 9729}, {"wrapS", 10497}, {"wrapT", 10497}}};
    }
    if (!sffd_scene_json.empty()) {
        json ext_json = json::parse(sffd_scene_json, nullptr, false);
        if (ext_json.is_discarded())
            return make_error(path.string() + ": write_gltf(): scene extension is not valid JSON");
        doc["extensionsUsed"] = {"SFFD_scene"};
        doc["extensions"] = {{"SFFD_scene", ext_json}};
    }
    if (!b.accessors.empty()) doc["accessors"] = b.accessors;
    if (!b.views.empty()) doc["bufferViews"] = b.views;
    for (const GltfAppend& fn : append)
        if (Status s = fn(doc, b.bin); !s) return make_error(path.string() + ": " + s.message());
    while (b.bin.size() % 4) b.bin.push_back('\0');
    if (!b.bin.empty()) {
        json buffer = {{"byteLength", b.bin.size()}};
        if (!binary) buffer["uri"] = "data:application/octet-stream;base64," + base64(b.bin);
        doc["buffers"] = {buffer};
    }
    std::string text = doc.dump(binary ? -1 : 1, ' ', false, json::error_handler_t::replace);
    if (!binary) return write_file_atomic(path, text + "\n");

    const auto write_bin = [&](std::FILE* f) {
        return std::fwrite(b.bin.data(), 1, b.bin.size(), f) == b.bin.size();
    };
    return write_glb_file(path, std::move(text), b.bin.size(),
                          b.bin.empty() ? std::function<bool(std::FILE*)>() : write_bin, "scene");
}

Status write_glb_file(const fs::path& path, std::string text, std::uint64_t bin_bytes,
                      const std::function<bool(std::FILE*)>& write_bin, const std::string& what) {
    while (text.size() % 4) text.push_back(' ');
    const std::uint64_t total = 12 + 8 + text.size() + (write_bin ? 8 + bin_bytes : 0);
    if (total > 0xffffffffu)
        return make_error(path.string() + ": " + what + " too large for a GLB file (4 GiB)");
    const std::uint32_t header[5] = {0x46546C67u /* glTF */, 2, std::uint32_t(total),
                                     std::uint32_t(text.size()), 0x4E4F534Au /* JSON */};
    const std::uint32_t bin_header[2] = {std::uint32_t(bin_bytes), 0x004E4942u /* BIN\0 */};
    return write_file_atomic(path, [&](std::FILE* f) -> Status {
        bool ok = std::fwrite(header, sizeof header, 1, f) == 1 &&
                  std::fwrite(text.data(), 1, text.size(), f) == text.size();
        if (ok && write_bin) ok = std::fwrite(bin_header, sizeof bin_header, 1, f) == 1 && write_bin(f);
        if (!ok) return make_error(path.string() + ": write failed: " + std::strerror(errno));
        return {};
    });
}

}  // namespace sffd::assets
