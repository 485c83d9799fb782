// The guarded tinygltf load behind every glTF reader (gltf_io.h: load_gltf_model), and the checked
// accessor reader (read_gltf_accessor). Hostile files are refused here with "file: problem".
#include "runtime/assets/gltf_io.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include <nlohmann/json.hpp>
#include <stb/stb_image.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include "runtime/assets/fresh_array.h"
#include "runtime/assets/gltf_detail.h"
#include "runtime/assets/mapped_file.h"
#include "runtime/core/file_io.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace gltf_detail;

namespace {

std::size_t component_size(int type) {
    switch (type) {
        case kByte:
        case kUByte: return 1;
        case kShort:
        case kUShort: return 2;
        case kUInt:
        case kFloat: return 4;
        default: return 0;
    }
}

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
    std::string_view bin;                                // a GLB's BIN chunk (fast path), in the mapping
    std::size_t bin_bytes = 0;                           // buffer 0's byteLength
    std::string bin_joined;                              // the path tinygltf asks for buffer 0's bytes
};

// A GLB's buffer 0 is handed to tinygltf under this name (see glb_json_for_ascii()); no real URI is read
// for it, whatever the folder holds.
constexpr const char* kBinChunkUri = "glb-bin-chunk.sffd-internal";

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
    if (!ctx.bin.empty() && uri == kBinChunkUri) {
        ctx.bin_joined = joined;
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
    if (!ctx.bin.empty() && joined == ctx.bin_joined) {
        // Parallel copy into prefaulted memory: one thread copying ~250 MB into fresh pages was the
        // largest cost of reading a large GLB.
        out->clear();
        resize_for_overwrite(*out, ctx.bin_bytes);
        constexpr std::size_t kBlock = std::size_t(1) << 22;
        tbb::parallel_for(std::size_t(0), (ctx.bin_bytes + kBlock - 1) / kBlock, [&](std::size_t b) {
            const std::size_t begin = b * kBlock;
            std::memcpy(out->data() + begin, ctx.bin.data() + begin, std::min(kBlock, ctx.bin_bytes - begin));
        });
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

// One component as a double: the same value for either output type (a float output then rounds it).
inline double component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
        case kFloat: {
            float f;
            std::memcpy(&f, p, 4);
            return static_cast<double>(f);
        }
        case kUByte: return normalized ? *p / 255.0 : double(*p);
        case kByte: {
            std::int8_t x;
            std::memcpy(&x, p, 1);
            return normalized ? std::max(x / 127.0, -1.0) : double(x);
        }
        case kUShort: {
            std::uint16_t x;
            std::memcpy(&x, p, 2);
            return normalized ? x / 65535.0 : double(x);
        }
        case kShort: {
            std::int16_t x;
            std::memcpy(&x, p, 2);
            return normalized ? std::max(x / 32767.0, -1.0) : double(x);
        }
        case kUInt: {
            std::uint32_t x;
            std::memcpy(&x, p, 4);
            return double(x);
        }
        default: return 0.0;
    }
}

// The checks and the decode behind read_gltf_accessor() and read_gltf_accessor_into(). Elements are decoded
// in parallel into the memory `storage(values)` gives for `values` Ts (called once, only when there are
// elements); each range stops at its first non-finite element, and the first in order is reported.
template <class T, class Storage>
Status decode_accessor_to(const tinygltf::Model& m, int index, int components, const std::string& src,
                          const std::string& what, Storage&& storage) {
    auto fail = [&](const std::string& why) { return make_error(src + ": " + what + ": " + why); };
    if (index < 0 || static_cast<std::size_t>(index) >= m.accessors.size())
        return fail("accessor index out of range");
    const tinygltf::Accessor& a = m.accessors[static_cast<std::size_t>(index)];
    if (a.sparse.isSparse) return fail("sparse accessors are not supported");
    if (tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type)) != components)
        return fail("expected " + std::to_string(components) + " components per element");
    const std::size_t csize = component_size(a.componentType);
    if (csize == 0) return fail("unsupported component type " + std::to_string(a.componentType));
    const std::size_t elem = csize * static_cast<std::size_t>(components);
    if (a.count == 0) return {};
    if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= m.bufferViews.size())
        return fail("accessor has no valid bufferView");
    const tinygltf::BufferView& bv = m.bufferViews[static_cast<std::size_t>(a.bufferView)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= m.buffers.size())
        return fail("bufferView has no valid buffer");
    const std::vector<unsigned char>& data = m.buffers[static_cast<std::size_t>(bv.buffer)].data;
    const std::size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem) return fail("byteStride smaller than an element");
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
        return fail("bufferView exceeds its buffer");
    if (a.byteOffset > bv.byteLength) return fail("accessor offset exceeds its bufferView");
    const std::size_t avail = bv.byteLength - a.byteOffset;
    if (a.count > avail / stride + 1 || (a.count - 1) * stride + elem > avail)
        return fail("accessor exceeds its bufferView");
    const std::size_t comps = static_cast<std::size_t>(components);
    T* const out = storage(a.count * comps);
    const unsigned char* base = data.data() + bv.byteOffset + a.byteOffset;
    const int type = a.componentType;
    const bool normalized = a.normalized;
    std::atomic<std::size_t> first_bad{a.count};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.count, 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              const unsigned char* p = base + i * stride;
                              bool finite = true;
                              for (std::size_t c = 0; c < comps; ++c, p += csize) {
                                  const double v = component(p, type, normalized);
                                  finite &= std::isfinite(v);
                                  out[i * comps + c] = static_cast<T>(v);
                              }
                              if (!finite) {
                                  std::size_t seen = first_bad.load();
                                  while (i < seen && !first_bad.compare_exchange_weak(seen, i)) {
                                  }
                                  return;
                              }
                          }
                      });
    if (const std::size_t i = first_bad.load(); i < a.count)
        return fail("non-finite value at element " + std::to_string(i));
    return {};
}

template <class T>
Result<std::vector<T>> decode_accessor(const tinygltf::Model& m, int index, int components,
                                       const std::string& src, const std::string& what) {
    std::vector<T> out;
    const Status st = decode_accessor_to<T>(m, index, components, src, what, [&](std::size_t values) {
        resize_for_overwrite(out, values);
        return out.data();
    });
    if (!st) return st.error();
    return out;
}

// Into glm vectors of float components (tightly packed: the layout fill_vectors relied on too).
template <class V>
Status decode_accessor_vectors(const tinygltf::Model& m, int index, const std::string& src,
                               const std::string& what, std::vector<V>& dst) {
    static_assert(sizeof(V) == V::length() * sizeof(float));
    dst.clear();
    return decode_accessor_to<float>(m, index, V::length(), src, what, [&](std::size_t values) {
        resize_for_overwrite(dst, values / std::size_t(V::length()));
        return reinterpret_cast<float*>(dst.data());
    });
}

}  // namespace

Result<std::vector<double>> read_gltf_accessor(const tinygltf::Model& m, int index, int components,
                                               const std::string& src, const std::string& what) {
    return decode_accessor<double>(m, index, components, src, what);
}

Status read_gltf_accessor_into(const tinygltf::Model& m, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec2>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}
Status read_gltf_accessor_into(const tinygltf::Model& m, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec3>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}
Status read_gltf_accessor_into(const tinygltf::Model& m, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec4>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}

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

// The fast path for a well-formed GLB: tinygltf's binary loader copies the whole BIN chunk on one thread
// into freshly faulted memory. When the container is valid (magic, version 2, lengths within the file, a
// JSON chunk padded to 4 bytes followed by a BIN chunk) and buffer 0 is the BIN chunk, the JSON is handed
// to tinygltf's text loader with buffer 0 renamed to kBinChunkUri, whose bytes fs_read() copies in
// parallel. Returns "" for anything else: such files take tinygltf's binary loader, with its messages.
std::string glb_json_for_ascii(std::string_view all, std::string_view& bin, std::size_t& bin_bytes) {
    auto u32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        std::memcpy(&v, all.data() + at, 4);
        return v;
    };
    if (all.size() < 28 || all.compare(0, 4, "glTF") != 0 || u32(4) != 2) return {};
    const std::size_t total = u32(8);
    const std::size_t json_len = u32(12);
    if (total > all.size() || u32(16) != 0x4E4F534Au || json_len == 0 || json_len % 4 != 0) return {};
    if (json_len > total - 28) return {};  // room for the JSON chunk and a BIN chunk header
    const std::size_t bin_at = 20 + json_len;
    const std::size_t bin_len = u32(bin_at);
    if (u32(bin_at + 4) != 0x004E4942u || bin_len == 0 || bin_len > total - bin_at - 8) return {};
    try {
        json doc = json::parse(all.substr(20, json_len), nullptr, false);
        if (doc.is_discarded() || !doc.is_object()) return {};
        auto buffers = doc.find("buffers");
        if (buffers == doc.end() || !buffers->is_array() || buffers->empty()) return {};
        json& b0 = (*buffers)[0];
        if (!b0.is_object() || b0.contains("uri")) return {};
        // tinygltf's binary loader binds every buffer without a uri to the BIN chunk, not only buffer 0.
        for (std::size_t i = 1; i < buffers->size(); ++i)
            if (!(*buffers)[i].is_object() || !(*buffers)[i].contains("uri")) return {};
        auto length = b0.find("byteLength");
        if (length == b0.end() || !length->is_number_unsigned()) return {};
        const std::uint64_t n = length->get<std::uint64_t>();
        if (n == 0 || n > bin_len) return {};
        b0["uri"] = kBinChunkUri;
        bin = all.substr(bin_at + 8, bin_len);
        bin_bytes = static_cast<std::size_t>(n);
        return doc.dump();
    } catch (const std::exception&) {  // e.g. invalid UTF-8 in a string: tinygltf's loader reports it
        return {};
    }
}

Status refuse_gltf1(const std::string& src, const std::string& version) {
    return make_error(src + ": glTF 1.0 is not supported (asset.version \"" + version +
                      "\"); convert it to glTF 2.0");
}

}  // namespace

Status load_gltf_model(const fs::path& path, tinygltf::Model& m) {
    const std::string src = path.string();
    // Mapped, not copied: a GLB's BIN chunk is copied once, into buffer 0 (fs_read()).
    auto file = MappedFile::open(path, kMaxGltfBytes);
    if (!file) return file.error();
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
    try {
        const auto* data = reinterpret_cast<const unsigned char*>(bytes->data());
        const std::string glb_json = binary ? glb_json_for_ascii(all, ctx.bin, ctx.bin_bytes) : std::string();
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
    // Everything tinygltf keeps was copied out of the mapping by now (buffers, images' bytes).
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
    return decode_images(m, src);
}

}  // namespace sffd::assets
