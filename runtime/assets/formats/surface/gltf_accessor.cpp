// The checked accessor readers (gltf_io.h: read_gltf_accessor and its variants) over a model that
// load_gltf_model (gltf_load.cpp) loaded: every offset checked against its buffer, values decoded in
// parallel, non-finite values refused, and bytes read from a mapping that changed meanwhile refused.
#include "runtime/assets/formats/surface/gltf_io.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/formats/surface/gltf_detail.h"
#include "runtime/assets/formats/surface/gltf_model.h"

namespace sffd::assets {
using namespace gltf_detail;
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

}  // namespace sffd::assets
