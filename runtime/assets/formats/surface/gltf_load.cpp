// The guarded tinygltf load behind every glTF reader (gltf_io.h: load_gltf_model) and a node's matrix;
// the checked accessor readers over the loaded model are gltf_accessor.cpp. Hostile files are refused
// here with "file: problem".
#include "runtime/assets/formats/surface/gltf_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>
#include <tiny_gltf.h>

#include "runtime/assets/formats/surface/gltf_detail.h"
#include "runtime/assets/formats/surface/gltf_model.h"
#include "runtime/assets/formats/archive/mapped_file.h"
#include "runtime/core/file_io.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace gltf_detail;

namespace {

// Every file tinygltf opens besides the glTF itself (buffer and image URIs) goes through these callbacks:
// resolve_resource() keeps it inside the glTF's folder (no `..`, absolute paths, symlinks out, and no
// current-directory fallback: tinygltf tries "<basedir>/uri" and then "./uri"; only the first is
// answered), read_file() opens regular files only. The first refusal is kept and reported as the error.
// Images are not decoded in tinygltf's callback: it records each image's declared size (stb header) and
// keeps the encoded bytes; read_gltf() checks the total against kDecodedImageBudget and decodes after.
constexpr std::uint64_t kMaxImagePixels = 8192ull * 8192ull;           // one image: 256 MB as RGBA8
constexpr std::uint64_t kDecodedImageBudget = std::uint64_t(1) << 30;  // all images of one file, RGBA8
constexpr std::uint64_t kMaxGltfBytes = std::uint64_t(2) << 30;        // the .gltf / .glb itself

struct LoadContext {
    fs::path owner;                                      // the glTF file, for messages and resolution
    std::string basedir;                                 // what tinygltf prefixes to URIs
    std::string error;                                   // first refusal
    std::unordered_map<std::string, fs::path> resolved;  // tinygltf's joined path -> checked path
    std::uint64_t declared_bytes = 0;                    // decoded RGBA8 size of all images so far
    // A well-formed GLB's resources in its mapping, under internal names (glb_json_for_ascii()): buffer 0
    // (kBinChunkUri) and the images stored in it. No real file is read for these names, whatever the
    // folder holds.
    std::unordered_map<std::string, std::string_view> internal;    // name -> bytes
    std::unordered_map<std::string, std::string> internal_joined;  // tinygltf's joined path -> name
};

// A GLB's buffer 0 is handed to tinygltf under this name; tinygltf gets a one-byte stand-in for it (the
// bytes stay in the mapping: gltf_model.h).
constexpr const char* kBinChunkUri = "glb-bin-chunk.sffd-internal";
std::string internal_image_uri(std::size_t image) {
    return "glb-image-" + std::to_string(image) + ".sffd-internal";
}

void refuse(LoadContext& ctx, const std::string& message) {
    if (ctx.error.empty()) ctx.error = message;
}

bool fs_exists(const std::string& joined, void* user) {
    auto& ctx = *static_cast<LoadContext*>(user);
    std::string uri;
    const std::string prefix =
        ctx.basedir.empty() ? std::string() : (ctx.basedir.back() == '/' ? ctx.basedir : ctx.basedir + "/");
    if (prefix.empty())
        uri = joined;  // the glTF is in the current folder: both candidates are relative to it
    else if (joined.rfind(prefix, 0) == 0) uri = joined.substr(prefix.size());
    else return false;  // tinygltf's current-directory fallback: never
    if (ctx.internal.count(uri)) {
        ctx.internal_joined[joined] = uri;
        return true;
    }
    auto r = resolve_resource(ctx.owner, uri);
    if (!r) {
        refuse(ctx, r.message());
        return false;
    }
    ctx.resolved[joined] = *r;
    return true;
}

std::string fs_expand(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion

bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& joined, void* user) {
    auto& ctx = *static_cast<LoadContext*>(user);
    if (auto in = ctx.internal_joined.find(joined); in != ctx.internal_joined.end()) {
        if (in->second == kBinChunkUri) out->assign(1, 0);  // the stand-in for buffer 0
        else {
            const std::string_view bytes = ctx.internal.at(in->second);
            out->assign(bytes.begin(), bytes.end());
        }
        return true;
    }
    auto it = ctx.resolved.find(joined);
    if (it == ctx.resolved.end()) {
        if (err) *err += "not a checked resource";
        return false;
    }
    auto bytes = read_file(it->second, kMaxResourceBytes);
    if (!bytes) {
        refuse(ctx, ctx.owner.string() + ": " + bytes.message());
        if (err) *err += bytes.message();
        return false;
    }
    out->assign(bytes->begin(), bytes->end());
    return true;
}

bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing is not allowed while loading";
    return false;
}

bool load_image_deferred(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                         const unsigned char* bytes, int size, void* user) {
    auto& ctx = *static_cast<LoadContext*>(user);
    int w = 0, h = 0, comp = 0;
    if (size <= 0 || !stbi_info_from_memory(bytes, size, &w, &h, &comp) || w <= 0 || h <= 0) {
        if (err) *err += "image " + std::to_string(index) + ": unknown or corrupt image format\n";
        refuse(ctx,
               ctx.owner.string() + ": image " + std::to_string(index) + ": unknown or corrupt image format");
        return false;
    }
    const std::uint64_t pixels = static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h);
    if (pixels > kMaxImagePixels) {
        refuse(ctx, ctx.owner.string() + ": image " + std::to_string(index) + " is " + std::to_string(w) +
                        "x" + std::to_string(h) + ", larger than 8192x8192");
        return false;
    }
    ctx.declared_bytes += pixels * 4;
    if (ctx.declared_bytes > kDecodedImageBudget) {
        refuse(ctx, ctx.owner.string() + ": images decode to more than " +
                        std::to_string(kDecodedImageBudget >> 20) + " MiB in total (image " +
                        std::to_string(index) + " is " + std::to_string(w) + "x" + std::to_string(h) +
                        "); the budget per file is " + std::to_string(kDecodedImageBudget >> 20) + " MiB");
        return false;
    }
    image->width = w;
    image->height = h;
    image->component = 0;  // 0 = still encoded (decode_images())
    image->bits = 0;
    image->image.assign(bytes, bytes + size);
    return true;
}

// Decodes the images load_image_deferred() kept, to RGBA8 (the budget was checked on the declared sizes).
Status decode_images(tinygltf::Model& m, const std::string& src) {
    for (std::size_t i = 0; i < m.images.size(); ++i) {
        tinygltf::Image& im = m.images[i];
        if (im.component != 0 || im.image.empty()) continue;
        int w = 0, h = 0, comp = 0;
        stbi_uc* data =
            stbi_load_from_memory(im.image.data(), static_cast<int>(im.image.size()), &w, &h, &comp, 4);
        if (!data)
            return make_error(src + ": image " + std::to_string(i) + ": cannot decode: " +
                              (stbi_failure_reason() ? stbi_failure_reason() : "unknown error"));
        im.width = w;
        im.height = h;
        im.component = 4;
        im.bits = 8;
        im.image.assign(data, data + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
        stbi_image_free(data);
    }
    return {};
}
}  // namespace

namespace {

// glTF 1.0 (2015) is a different format (dictionaries instead of arrays, GLSL techniques, a version-1
// binary container) that tinygltf reads as broken 2.0 with a misleading message. Returns the version the
// file declares when it is 1.x ("1.0", "1.0.2"), "1.0 (no asset.version; top-level dictionaries)" for an
// undeclared 1.0 layout, or "" for anything else (left to tinygltf).
std::string gltf1_version(std::string_view json_text) {
    const json doc = json::parse(json_text.begin(), json_text.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return {};
    if (auto a = doc.find("asset"); a != doc.end() && a->is_object()) {
        if (auto v = a->find("version"); v != a->end()) {
            const std::string text = v->is_string() ? v->get<std::string>() : v->dump();
            return text.rfind('1', 0) == 0 ? text : std::string{};
        }
    }
    for (const char* key : {"meshes", "accessors", "nodes", "buffers"})
        if (auto it = doc.find(key); it != doc.end() && it->is_object() && !it->empty())
            return "1.0 (no asset.version; '" + std::string(key) + "' is a dictionary)";
    return {};
}

// tinygltf reads an image's bytes from its bufferView without checking that the view lies inside its
// buffer: a hostile offset made it read far past the end. Refuses the first image whose view does not;
// fields of the wrong type are left to tinygltf, which refuses them before it reads anything.
Status check_image_views(const json& doc, const std::string& src) {
    auto images = doc.find("images"), views = doc.find("bufferViews"), buffers = doc.find("buffers");
    if (images == doc.end() || !images->is_array()) return {};
    const bool have_views = views != doc.end() && views->is_array();
    const bool have_buffers = buffers != doc.end() && buffers->is_array();
    for (std::size_t i = 0; i < images->size(); ++i) {
        const json& image = (*images)[i];
        if (!image.is_object()) continue;
        auto v = image.find("bufferView");
        if (v == image.end() || !v->is_number_integer()) continue;
        const std::string what = src + ": image " + std::to_string(i) + ": bufferView " + v->dump();
        if (!have_views || v->get<std::int64_t>() < 0 || v->get<std::uint64_t>() >= views->size())
            return make_error(what + " does not exist");
        const json& view = (*views)[v->get<std::size_t>()];
        if (!view.is_object()) continue;
        auto b = view.find("buffer");
        auto length = view.find("byteLength");
        auto offset = view.find("byteOffset");
        if (b == view.end() || !b->is_number_integer() || length == view.end() ||
            !length->is_number_unsigned() || (offset != view.end() && !offset->is_number_unsigned()))
            continue;
        if (!have_buffers || b->get<std::int64_t>() < 0 || b->get<std::uint64_t>() >= buffers->size())
            return make_error(what + ": buffer " + b->dump() + " does not exist");
        const json& buffer = (*buffers)[b->get<std::size_t>()];
        auto size = buffer.is_object() ? buffer.find("byteLength") : buffer.end();
        if (!buffer.is_object() || size == buffer.end() || !size->is_number_unsigned()) continue;
        const std::uint64_t at = offset == view.end() ? 0 : offset->get<std::uint64_t>();
        const std::uint64_t n = length->get<std::uint64_t>(), total = size->get<std::uint64_t>();
        if (at > total || n > total - at)
            return make_error(what + " (" + std::to_string(n) + " bytes at " + std::to_string(at) +
                              ") lies outside buffer " + b->dump() + " (" + std::to_string(total) +
                              " bytes)");
    }
    return {};
}

// The fast path for a well-formed GLB: tinygltf's binary loader copies the whole BIN chunk on one thread
// into freshly faulted memory. When the container is valid (magic, version 2, lengths within the file, a
// JSON chunk padded to 4 bytes followed by a BIN chunk) and buffer 0 is the BIN chunk, the JSON is handed
// to tinygltf's text loader with buffer 0 renamed to kBinChunkUri (a one-byte stand-in: its bytes become
// `bin`, left in the mapping) and every image stored in buffer 0 renamed to an internal URI that fs_read()
// answers from the mapping. Returns "" for anything else (such files take tinygltf's binary loader, with
// its messages), or an error for an image view outside its buffer.
Result<std::string> glb_json_for_ascii(std::string_view all, const std::string& src, LoadContext& ctx,
                                       std::string_view& bin) {
    auto u32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        std::memcpy(&v, all.data() + at, 4);
        return v;
    };
    if (all.size() < 28 || all.compare(0, 4, "glTF") != 0 || u32(4) != 2) return std::string();
    const std::size_t total = u32(8);
    const std::size_t json_len = u32(12);
    if (total > all.size() || u32(16) != 0x4E4F534Au || json_len == 0 || json_len % 4 != 0)
        return std::string();
    // Room for the JSON chunk and a BIN chunk header (a declared total under 28 bytes has none).
    if (total < 28 || json_len > total - 28) return std::string();
    const std::size_t bin_at = 20 + json_len;
    const std::size_t bin_len = u32(bin_at);
    if (u32(bin_at + 4) != 0x004E4942u || bin_len == 0 || bin_len > total - bin_at - 8) return std::string();
    try {
        json doc = json::parse(all.substr(20, json_len), nullptr, false);
        if (doc.is_discarded() || !doc.is_object()) return std::string();
        auto buffers = doc.find("buffers");
        if (buffers == doc.end() || !buffers->is_array() || buffers->empty()) return std::string();
        json& b0 = (*buffers)[0];
        if (!b0.is_object() || b0.contains("uri")) return std::string();
        // tinygltf's binary loader binds every buffer without a uri to the BIN chunk, not only buffer 0.
        for (std::size_t i = 1; i < buffers->size(); ++i)
            if (!(*buffers)[i].is_object() || !(*buffers)[i].contains("uri")) return std::string();
        auto length = b0.find("byteLength");
        if (length == b0.end() || !length->is_number_unsigned()) return std::string();
        const std::uint64_t n = length->get<std::uint64_t>();
        if (n == 0 || n > bin_len) return std::string();
        if (Status s = check_image_views(doc, src); !s) return s.error();
        bin = all.substr(bin_at + 8, static_cast<std::size_t>(n));
        b0["uri"] = kBinChunkUri;
        b0["byteLength"] = 1;
        ctx.internal[kBinChunkUri] = bin;
        // Images in buffer 0 (their views were checked above) are read from the mapping by name.
        if (auto images = doc.find("images"); images != doc.end() && images->is_array()) {
            json& views = doc["bufferViews"];
            for (std::size_t i = 0; i < images->size(); ++i) {
                json& image = (*images)[i];
                if (!image.is_object() || !image.contains("bufferView") ||
                    !image["bufferView"].is_number_integer())
                    continue;
                const json& view = views[image["bufferView"].get<std::size_t>()];
                if (!view.is_object() || !view.contains("buffer") || view["buffer"] != 0 ||
                    !view.contains("byteLength") || !view["byteLength"].is_number_unsigned())
                    continue;
                const std::size_t at = view.value("byteOffset", std::size_t(0));
                const std::string uri = internal_image_uri(i);
                ctx.internal[uri] = bin.substr(at, view["byteLength"].get<std::size_t>());
                image.erase("bufferView");
                image["uri"] = uri;
            }
        }
        return doc.dump();
    } catch (const std::exception&) {  // e.g. invalid UTF-8 in a string: tinygltf's loader reports it
        ctx.internal.clear();
        bin = {};
        return std::string();
    }
}

// The other loads (text glTF, GLBs off the fast path) get the image view check from a parse of their JSON,
// when it has images at all. JSON that does not parse is left to tinygltf's messages.
Status check_image_views(std::string_view json_text, const std::string& src) {
    if (json_text.find("\"images\"") == std::string_view::npos) return {};
    const json doc = json::parse(json_text.begin(), json_text.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return {};
    return check_image_views(doc, src);
}

Status refuse_gltf1(const std::string& src, const std::string& version) {
    return make_error(src + ": glTF 1.0 is not supported (asset.version \"" + version +
                      "\"); convert it to glTF 2.0");
}

}  // namespace

Status load_gltf_model(const fs::path& path, GltfModel& model) {
    const std::string src = path.string();
    tinygltf::Model& m = model.gltf;
    // Mapped, not copied: a well-formed GLB's BIN chunk is read where it lies (gltf_model.h).
    auto opened = MappedFile::open(path, kMaxGltfBytes);
    if (!opened) return opened.error();
    const auto file = std::make_shared<const MappedFile>(std::move(*opened));
    const std::string_view all = file->bytes();
    const std::string_view* bytes = &all;
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool binary = ext == ".glb" || (bytes->size() >= 4 && bytes->compare(0, 4, "glTF") == 0);
    // The JSON chunk's nesting is checked before tinygltf's recursive parser sees it (stack overflow).
    std::string_view json_text = *bytes;
    if (binary && bytes->size() >= 20) {
        std::uint32_t len = 0;
        std::memcpy(&len, bytes->data() + 12, 4);
        json_text = all.substr(20, std::min<std::size_t>(len, bytes->size() - 20));
    }
    if (Status s = check_json_depth(json_text, src); !s) return s;
    if (binary &&
        bytes->size() >= 8) {  // the GLB header's container version: 1 is glTF 1.0's KHR_binary_glTF
        std::uint32_t container = 0;
        std::memcpy(&container, bytes->data() + 4, 4);
        if (container == 1) {
            const std::string v = gltf1_version(json_text);
            return refuse_gltf1(src, v.empty() ? "1.0" : v);
        }
        if (container != 2 && bytes->compare(0, 4, "glTF") == 0)  // tinygltf reads any other as 2
            return make_error(src + ": invalid glTF: GLB container version " + std::to_string(container) +
                              " is not supported (expected 2)");
    }

    LoadContext ctx;
    ctx.owner = path;
    ctx.basedir = path.parent_path().string();
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(load_image_deferred, &ctx);
    loader.SetFsCallbacks(tinygltf::FsCallbacks{fs_exists, fs_expand, fs_read, fs_write, &ctx});
    std::string err, warn;
    bool ok = false;
    std::string_view bin;
    try {
        const auto* data = reinterpret_cast<const unsigned char*>(bytes->data());
        auto fast = binary ? glb_json_for_ascii(all, src, ctx, bin) : Result<std::string>(std::string());
        if (!fast) return fast.error();
        const std::string& glb_json = *fast;
        if (glb_json.empty())
            if (Status s = check_image_views(json_text, src); !s) return s;
        if (!glb_json.empty())
            ok = loader.LoadASCIIFromString(&m, &err, &warn, glb_json.data(),
                                            static_cast<unsigned int>(glb_json.size()), ctx.basedir);
        else
            ok = binary ? loader.LoadBinaryFromMemory(&m, &err, &warn, data,
                                                      static_cast<unsigned int>(bytes->size()), ctx.basedir)
                        : loader.LoadASCIIFromString(&m, &err, &warn, bytes->data(),
                                                     static_cast<unsigned int>(bytes->size()), ctx.basedir);
    } catch (const std::bad_alloc&) {
        return make_error(src + ": out of memory while parsing the glTF");
    } catch (const std::exception& e) {  // tinygltf's JSON parser may throw on hostile input
        return make_error(src + ": invalid glTF: " + e.what());
    }
    // Everything tinygltf keeps was copied out of the mapping by now (buffers, images' bytes); what stayed
    // there (`bin`) is checked again by each accessor read.
    if (file->changed()) return make_error(src + ": " + kChangedWhileRead);
    if (!ok || m.asset.version.rfind('1', 0) == 0) {
        if (const std::string v = gltf1_version(json_text); !v.empty()) return refuse_gltf1(src, v);
    }
    if (!ctx.error.empty()) return make_error(ctx.error);  // a refused resource, whatever tinygltf made of it
    if (!ok) {
        while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
        return make_error(
            src + ": invalid glTF: " + (err.empty() ? std::string("unknown error") : err.substr(0, 500)));
    }
    if (!bin.empty()) {
        model.file = file;
        model.bin = bin;
    }
    return decode_images(m, src);
}

glm::dmat4 gltf_node_matrix(const tinygltf::Node& n) {
    if (n.matrix.size() == 16) return glm::make_mat4(n.matrix.data());
    glm::dmat4 m(1.0);
    if (n.translation.size() == 3)
        m = glm::translate(m, glm::dvec3(n.translation[0], n.translation[1], n.translation[2]));
    if (n.rotation.size() == 4)
        m = m * glm::mat4_cast(
                    glm::normalize(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2])));
    if (n.scale.size() == 3) m = glm::scale(m, glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
    return m;
}

}  // namespace sffd::assets
