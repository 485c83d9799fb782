// The guarded tinygltf load behind every glTF reader (gltf_io.h: load_gltf_model), and the checked
// accessor reader (read_gltf_accessor). Hostile files are refused here with "file: problem".
#include "runtime/assets/gltf_io.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include "runtime/assets/fresh_array.h"
#include "runtime/assets/gltf_detail.h"
#include "runtime/assets/gltf_model.h"
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

// An accessor's element layout, for the per-element decoders below.
struct ElementFormat {
    int type = 0;           // component type
    std::size_t csize = 0;  // bytes per component
    std::size_t comps = 0;  // components per element
    bool normalized = false;
};

// An accessor's checked place: `count` elements of layout `f`, `stride` bytes apart from `base`.
struct AccessorSpan {
    const unsigned char* base = nullptr;
    std::size_t count = 0, stride = 0;
    ElementFormat f;
};

// The checks behind every accessor reader: every offset against its buffer (hostile files point
// accessors past the end).
Result<AccessorSpan> locate_accessor(const GltfModel& model, int index, int components,
                                     const std::string& src, const std::string& what) {
    const tinygltf::Model& m = model.gltf;
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
    AccessorSpan out;
    out.f = ElementFormat{a.componentType, csize, static_cast<std::size_t>(components), a.normalized};
    if (a.count == 0) return out;
    if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= m.bufferViews.size())
        return fail("accessor has no valid bufferView");
    const tinygltf::BufferView& bv = m.bufferViews[static_cast<std::size_t>(a.bufferView)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= m.buffers.size())
        return fail("bufferView has no valid buffer");
    const std::span<const unsigned char> data = gltf_buffer(model, static_cast<std::size_t>(bv.buffer));
    const std::size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem) return fail("byteStride smaller than an element");
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
        return fail("bufferView exceeds its buffer");
    if (a.byteOffset > bv.byteLength) return fail("accessor offset exceeds its bufferView");
    const std::size_t avail = bv.byteLength - a.byteOffset;
    if (a.count > avail / stride + 1 || (a.count - 1) * stride + elem > avail)
        return fail("accessor exceeds its bufferView");
    out.base = data.data() + bv.byteOffset + a.byteOffset;
    out.count = a.count;
    out.stride = stride;
    return out;
}

// The first i in [0, count) for which `ok(i)` is false (count when none), tested in parallel: each range
// stops at its first failure.
template <class Ok>
std::size_t first_failing(std::size_t count, Ok&& ok) {
    std::atomic<std::size_t> first_bad{count};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              if (ok(i)) continue;
                              std::size_t seen = first_bad.load();
                              while (i < seen && !first_bad.compare_exchange_weak(seen, i)) {
                              }
                              return;
                          }
                      });
    return first_bad.load();
}

// What a decode of `at` reports once done, `bad` being its first non-finite element.
Status decode_status(const GltfModel& model, const AccessorSpan& at, std::size_t bad, const std::string& src,
                     const std::string& what) {
    // Bytes read from the mapping are only the file's if it was not shortened meanwhile.
    if (gltf_changed(model)) return make_error(src + ": " + kChangedWhileRead);
    if (bad < at.count)
        return make_error(src + ": " + what + ": non-finite value at element " + std::to_string(bad));
    return {};
}

// The checks and the decode behind most accessor readers. `storage(count)` gives the memory for `count`
// elements (called once, only when there are elements); `element(out, i, p, f)` decodes element i from its
// bytes `p` into `out` and says whether it was finite. The first non-finite element in order is reported.
template <class Out, class Storage, class Element>
Status decode_accessor_to(const GltfModel& model, int index, int components, const std::string& src,
                          const std::string& what, Storage&& storage, Element&& element) {
    auto at = locate_accessor(model, index, components, src, what);
    if (!at) return at.error();
    if (at->count == 0) return {};
    Out* const out = storage(at->count);
    const std::size_t bad = first_failing(
        at->count, [&](std::size_t i) { return element(out, i, at->base + i * at->stride, at->f); });
    return decode_status(model, *at, bad, src, what);
}

// Element i as `f.comps` values of T at out[i * comps].
template <class T>
bool decode_values(T* out, std::size_t i, const unsigned char* p, const ElementFormat& f) {
    bool finite = true;
    for (std::size_t c = 0; c < f.comps; ++c, p += f.csize) {
        const double v = component(p, f.type, f.normalized);
        finite &= std::isfinite(v);
        out[i * f.comps + c] = static_cast<T>(v);
    }
    return finite;
}

template <class T>
Result<std::vector<T>> decode_accessor(const GltfModel& m, int index, int components, const std::string& src,
                                       const std::string& what) {
    std::vector<T> out;
    const Status st = decode_accessor_to<T>(
        m, index, components, src, what,
        [&](std::size_t count) {
            resize_for_overwrite(out, count * static_cast<std::size_t>(components));
            return out.data();
        },
        decode_values<T>);
    if (!st) return st.error();
    return out;
}

// Into glm vectors of float components (tightly packed: the layout fill_vectors relied on too).
template <class V>
Status decode_accessor_vectors(const GltfModel& m, int index, const std::string& src, const std::string& what,
                               std::vector<V>& dst) {
    static_assert(sizeof(V) == V::length() * sizeof(float));
    constexpr std::size_t N = V::length();
    dst.clear();
    auto at = locate_accessor(m, index, int(N), src, what);
    if (!at) return at.error();
    if (at->count == 0) return {};
    std::size_t bad = 0;
    if (at->f.type == kFloat && at->stride == sizeof(V) &&
        reinterpret_cast<std::uintptr_t>(at->base) % alignof(V) == 0) {
        // Packed floats, what the writer writes: copied into the array in one pass (resizing first would
        // write the whole array twice), then checked: finite when no exponent is all ones.
        dst.reserve(at->count);
        prefault_for_write(dst.data(), at->count * sizeof(V));
        const V* first = reinterpret_cast<const V*>(at->base);
        dst.assign(first, first + at->count);
        bad = first_failing(at->count, [&](std::size_t i) {
            std::uint32_t inf = 0;
            for (std::size_t c = 0; c < N; ++c)
                inf |= (std::bit_cast<std::uint32_t>(dst[i][int(c)]) & 0x7f800000u) == 0x7f800000u;
            return inf == 0;
        });
    } else {
        resize_for_overwrite(dst, at->count);
        float* out = reinterpret_cast<float*>(dst.data());
        bad = first_failing(at->count, [&](std::size_t i) {
            return decode_values<float>(out, i, at->base + i * at->stride, at->f);
        });
    }
    return decode_status(m, *at, bad, src, what);
}

// linear_to_srgb8() of every normalised unsigned short (x / 65535): what the writer stores colours as,
// so decoding them is a table lookup instead of three pow() calls per splat.
const std::array<std::uint8_t, 65536>& srgb8_of_linear16() {
    static const auto table = [] {
        std::array<std::uint8_t, 65536> t{};
        for (std::size_t x = 0; x < t.size(); ++x)
            t[x] = static_cast<std::uint8_t>(linear_to_srgb8(static_cast<double>(x) / 65535.0));
        return t;
    }();
    return table;
}

std::uint32_t alpha8(double a) {
    return static_cast<std::uint32_t>(std::lround(std::clamp(a, 0.0, 1.0) * 255.0));
}

}  // namespace

Result<std::vector<double>> read_gltf_accessor(const GltfModel& m, int index, int components,
                                               const std::string& src, const std::string& what) {
    return decode_accessor<double>(m, index, components, src, what);
}

Status read_gltf_accessor_into(const GltfModel& m, int index, const std::string& src, const std::string& what,
                               std::vector<glm::vec2>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}
Status read_gltf_accessor_into(const GltfModel& m, int index, const std::string& src, const std::string& what,
                               std::vector<glm::vec3>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}
Status read_gltf_accessor_into(const GltfModel& m, int index, const std::string& src, const std::string& what,
                               std::vector<glm::vec4>& dst) {
    return decode_accessor_vectors(m, index, src, what, dst);
}

Status read_gltf_accessor_strided(const GltfModel& m, int index, int components, const std::string& src,
                                  const std::string& what, float* dst, std::size_t stride,
                                  std::size_t count) {
    if (components < 1 || components > 4)  // scalars and vectors only
        return make_error(src + ": " + what + ": " + std::to_string(components) + " components per element");
    auto at = locate_accessor(m, index, components, src, what);
    if (!at) return at.error();
    if (at->count != count)
        return make_error(src + ": " + what + ": " + std::to_string(at->count) + " elements, expected " +
                          std::to_string(count));
    if (count == 0) return {};
    if (stride < static_cast<std::size_t>(components))
        return make_error(src + ": " + what + ": stride " + std::to_string(stride) +
                          " is less than an element");
    // Floats as stored (finite when no exponent is all ones), with the element size known to the compiler
    // (a copy of a run-time size is a library call per element).
    auto floats = [&]<std::size_t N>() {
        return first_failing(count, [&](std::size_t i) {
            std::uint32_t bits[N];
            std::memcpy(bits, at->base + i * at->stride, sizeof bits);
            std::memcpy(dst + i * stride, bits, sizeof bits);
            std::uint32_t inf = 0;
            for (std::size_t c = 0; c < N; ++c) inf |= (bits[c] & 0x7f800000u) == 0x7f800000u;
            return inf == 0;
        });
    };
    std::size_t bad = count;
    if (at->f.type == kFloat && components == 3) bad = floats.template operator()<3>();
    else if (at->f.type == kFloat && components == 4) bad = floats.template operator()<4>();
    else
        bad = first_failing(count, [&](std::size_t i) {
            const unsigned char* p = at->base + i * at->stride;
            float* out = dst + i * stride;
            bool finite = true;
            for (std::size_t c = 0; c < at->f.comps; ++c, p += at->f.csize) {
                const double v = component(p, at->f.type, at->f.normalized);
                finite &= std::isfinite(v);
                out[c] = static_cast<float>(v);
            }
            return finite;
        });
    return decode_status(m, *at, bad, src, what);
}

Status read_gltf_colors_into(const GltfModel& m, int index, int components, const std::string& src,
                             const std::string& what, std::vector<std::uint32_t>& dst) {
    dst.clear();
    const std::array<std::uint8_t, 65536>* lut = nullptr;
    if (index >= 0 && static_cast<std::size_t>(index) < m.gltf.accessors.size()) {
        const tinygltf::Accessor& a = m.gltf.accessors[static_cast<std::size_t>(index)];
        if (a.componentType == kUShort && a.normalized && a.count > 0) lut = &srgb8_of_linear16();
    }
    return decode_accessor_to<std::uint32_t>(
        m, index, components, src, what,
        [&](std::size_t count) {
            resize_for_overwrite(dst, count);
            return dst.data();
        },
        [lut](std::uint32_t* out, std::size_t i, const unsigned char* p, const ElementFormat& f) {
            if (lut && f.type == kUShort && f.normalized) {
                std::uint16_t x[4] = {0, 0, 0, 65535};
                std::memcpy(x, p, 2 * f.comps);
                // Alpha is linear: round(x / 65535 * 255) = round(x / 257), never a tie.
                out[i] = std::uint32_t((*lut)[x[0]]) | (std::uint32_t((*lut)[x[1]]) << 8) |
                         (std::uint32_t((*lut)[x[2]]) << 16) | (((std::uint32_t(x[3]) + 128u) / 257u) << 24);
                return true;
            }
            double v[4] = {0.0, 0.0, 0.0, 1.0};
            bool finite = true;
            for (std::size_t c = 0; c < f.comps; ++c, p += f.csize) {
                v[c] = component(p, f.type, f.normalized);
                finite &= std::isfinite(v[c]);
            }
            if (!finite) return false;
            out[i] = linear_to_srgb8(v[0]) | (linear_to_srgb8(v[1]) << 8) | (linear_to_srgb8(v[2]) << 16) |
                     ((f.comps == 4 ? alpha8(v[3]) : 255u) << 24);
            return true;
        });
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
