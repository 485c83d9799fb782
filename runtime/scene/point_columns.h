// Point columns: every per-point fact of a cloud, of either kind, as a named, typed column with a strided
// view (Magnum's Trade::MeshData attributes are the model).
//
// Two sorts of column:
//   - authored columns live in the cloud component (SplatCloud, GaussianCloud in components.h) as one
//     contiguous std::vector each; importers and packers fill those and know nothing else;
//   - optional columns are their own plain components on the cloud's entity (below). Absent, or empty,
//     means the default for every point, so adding one touches no importer, exporter or packer: a
//     consumer that honours it looks it up, one that does not is unchanged.
// Both sorts are paged the same way (point_pages.h): page i is the index range [i*P, (i+1)*P) of every
// column at once, and each column group has its own change stamp per page.
//
// Every column of both kinds is named in one table below (kSurfaceColumns, kGaussianColumns,
// kOptionalColumns: name, value type, stamp group), and point_column<T>(cloud or entity, name) gives its
// strided view (empty when absent, of another size, or when T is not its type). `splatffd info` lists them.
// Saving keeps the optional columns (content/README.md: `_FLAGS`, `_WEIGHT`); point_subset.h drops the
// gone points for saving and export.
//
// Selections, hidden and deleted flags refer to points by index, never by position, so they survive
// deformation and animation (the deformed outputs keep the authored order).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_pages.h"

namespace sffd {

// `count` values of T, `stride` bytes apart. Non-owning; T may be const.
template <class T>
class StridedView {
    using Byte = std::conditional_t<std::is_const_v<T>, const std::byte, std::byte>;

public:
    StridedView() = default;
    StridedView(T* data, std::size_t count, std::ptrdiff_t stride = sizeof(T))
        : data_(data), count_(count), stride_(stride) {}
    template <class U>
    requires std::is_convertible_v<U (*)[], T (*)[]> StridedView(std::span<U> values)
        : StridedView(values.data(), values.size()) {}
    template <class U>
    requires std::is_convertible_v<U (*)[], T (*)[]> StridedView(std::vector<U>& values)
        : StridedView(values.data(), values.size()) {}
    template <class U>
    requires std::is_convertible_v<const U (*)[], T (*)[]> StridedView(const std::vector<U>& values)
        : StridedView(values.data(), values.size()) {}

    std::size_t size() const { return count_; }
    bool empty() const { return count_ == 0; }
    std::ptrdiff_t stride() const { return stride_; }
    T* data() const { return data_; }
    bool contiguous() const { return stride_ == std::ptrdiff_t(sizeof(T)); }

    T& operator[](std::size_t i) const {
        return *reinterpret_cast<T*>(reinterpret_cast<Byte*>(data_) + std::ptrdiff_t(i) * stride_);
    }
    // Values [first, first + count): a page, a run.
    StridedView slice(std::size_t first, std::size_t count) const {
        return {&(*this)[first], count, stride_};
    }

private:
    T* data_ = nullptr;
    std::size_t count_ = 0;
    std::ptrdiff_t stride_ = sizeof(T);
};

// ---- Optional columns ---------------------------------------------------------------------------------

// Per-point state, one byte a point, of a SplatCloud or GaussianCloud entity (SuperSplat keeps the same
// byte per splat). `bits` is empty (every point visible, none selected) or holds one byte per point.
// The bits are separate facts with separate stamps (point_pages.h PointColumn::selection and
// PointColumn::visibility): a selection change re-uploads the highlight but never re-deforms or re-picks.
enum PointFlagBits : std::uint8_t {
    kPointSelected = 1u << 0,  // in the point selection (editor); drawn highlighted
    kPointHidden = 1u << 1,    // not drawn, not picked, not exported; kept, and unhidden by "unhide"
    kPointDeleted = 1u << 2,   // gone for every path; kept only so that undo can bring it back, and dropped
                               // by saving and export (a saved scene holds no deleted point)
};
inline constexpr std::uint8_t kPointGone = kPointHidden | kPointDeleted;  // not drawn, picked or exported

struct PointFlags {
    std::vector<std::uint8_t> bits;
};

// Per-point deformation weight in [0, 1], read by every deformer: P' = P + w (FFD(P) - P), and the
// Jacobian blended the same way, J_w = I + w (J - I). `values` is empty (weight 1 everywhere: today's
// behaviour) or holds one weight per point. A PLY vertex property `weight` is read into it.
struct PointWeights {
    std::vector<float> values;
};

// Bounded: an index past a column of the wrong size reads the default, never past the end.
inline bool point_gone(const PointFlags* flags, std::size_t i) {
    return flags && i < flags->bits.size() && (flags->bits[i] & kPointGone) != 0;
}
inline float point_weight(const PointWeights* weights, std::size_t i) {
    return weights && i < weights->values.size() ? weights->values[i] : 1.0f;
}

// ---- Named columns ------------------------------------------------------------------------------------

// The type of one value of a column. A point holds one value, or for `sh` 3 * sh_coeffs(sh_degree) floats.
enum class ColumnType : std::uint8_t { u8, rgba8, f32, vec2, vec3, vec4, quat };

template <class T>
struct column_type_of;  // the ColumnType of a C++ value type (no definition: not a column type)
template <>
struct column_type_of<std::uint8_t> {
    static constexpr ColumnType value = ColumnType::u8;
};
template <>
struct column_type_of<std::uint32_t> {  // RGBA8, sRGB-encoded, R in the low byte
    static constexpr ColumnType value = ColumnType::rgba8;
};
template <>
struct column_type_of<float> {
    static constexpr ColumnType value = ColumnType::f32;
};
template <>
struct column_type_of<glm::vec2> {
    static constexpr ColumnType value = ColumnType::vec2;
};
template <>
struct column_type_of<glm::vec3> {
    static constexpr ColumnType value = ColumnType::vec3;
};
template <>
struct column_type_of<glm::vec4> {
    static constexpr ColumnType value = ColumnType::vec4;
};
template <>
struct column_type_of<glm::quat> {
    static constexpr ColumnType value = ColumnType::quat;
};

std::string_view column_type_name(ColumnType type);  // "u8", "rgba8", "f32", "vec2", ...
std::size_t column_type_bytes(ColumnType type);      // bytes of one value

// One named column: its name, the type of its values and the stamp group (point_pages.h) whose page
// stamps say it changed. `flags` is one byte of two facts: selection and visibility, stamped apart.
struct PointColumnSpec {
    std::string_view name;
    ColumnType type;
    PointColumn stamp;
    PointColumn also_stamp;  // a second group (flags: visibility); equal to `stamp` for the others
    bool per_sh = false;     // sh: 3 * sh_coeffs(sh_degree) values a point, else one
};

// THE table: every column of both kinds, in one place. Authored columns are the cloud component's
// vectors (components.h); optional ones are components beside either kind (above). point_columns.cpp
// maps each entry to its member and checks the member's type against `type` at compile time.
inline constexpr PointColumnSpec kSurfaceColumns[] = {
    {"position", ColumnType::vec3, PointColumn::position, PointColumn::position},  // SplatCloud::positions
    {"normal", ColumnType::vec3, PointColumn::frame, PointColumn::frame},          // normals
    {"axis_u", ColumnType::vec3, PointColumn::frame, PointColumn::frame},          // axis_u
    {"axis_v", ColumnType::vec3, PointColumn::frame, PointColumn::frame},          // axis_v
    {"color", ColumnType::rgba8, PointColumn::colour, PointColumn::colour},        // colors
    {"uv", ColumnType::vec2, PointColumn::colour, PointColumn::colour},            // uvs
    {"uv_axes", ColumnType::vec4, PointColumn::colour, PointColumn::colour},       // uv_axes
};
inline constexpr PointColumnSpec kGaussianColumns[] = {
    {"position", ColumnType::vec3, PointColumn::position, PointColumn::position},  // GaussianCloud::positions
    {"scale", ColumnType::vec3, PointColumn::scale, PointColumn::scale},           // scales
    {"rotation", ColumnType::quat, PointColumn::rotation, PointColumn::rotation},  // rotations
    {"opacity", ColumnType::f32, PointColumn::opacity, PointColumn::opacity},      // opacities
    {"sh", ColumnType::f32, PointColumn::sh, PointColumn::sh, true},               // sh
};
inline constexpr PointColumnSpec kOptionalColumns[] = {
    {"flags", ColumnType::u8, PointColumn::selection, PointColumn::visibility},  // PointFlags::bits
    {"weight", ColumnType::f32, PointColumn::weight, PointColumn::weight},       // PointWeights::values
};

// A column of one cloud, untyped: `count` points, `stride` bytes apart, `values` values of spec->type
// each. Empty (data null, count 0) when the column is absent, empty, or not one entry per point (a
// column of the wrong size reads as absent: nothing indexes past its end).
struct ColumnRef {
    const PointColumnSpec* spec = nullptr;
    const std::byte* data = nullptr;
    std::size_t count = 0;
    std::ptrdiff_t stride = 0;
    std::size_t values = 1;

    bool present() const { return count > 0; }
    std::size_t bytes() const {
        return count * values * column_type_bytes(spec ? spec->type : ColumnType::u8);
    }
};

// Every column of the kind, in table order, present or not.
std::vector<ColumnRef> point_columns(const SplatCloud& cloud);
std::vector<ColumnRef> point_columns(const GaussianCloud& cloud);
// Entity e's: its cloud's columns, then the optional ones (PointFlags, PointWeights); none without a cloud.
std::vector<ColumnRef> point_columns(const ecs::Registry& registry, ecs::Entity e);

// One named column (spec null when the kind has no such name).
ColumnRef column_ref(const SplatCloud& cloud, std::string_view name);
ColumnRef column_ref(const GaussianCloud& cloud, std::string_view name);
ColumnRef column_ref(const ecs::Registry& registry, ecs::Entity e, std::string_view name);

// The typed view of a column: empty when it is absent or T is not its type. The `sh` column's view has
// one element per point, the point's first float (its DC red); the point's 3K floats follow it.
template <class T>
StridedView<T> typed_column(const ColumnRef& ref) {
    if (!ref.spec || !ref.present() || ref.spec->type != column_type_of<std::remove_const_t<T>>::value)
        return {};
    return {reinterpret_cast<T*>(const_cast<std::byte*>(ref.data)), ref.count, ref.stride};
}
template <class T>
StridedView<const T> point_column(const SplatCloud& cloud, std::string_view name) {
    return typed_column<const T>(column_ref(cloud, name));
}
template <class T>
StridedView<T> point_column(SplatCloud& cloud, std::string_view name) {  // the cloud is the caller's to write
    return typed_column<T>(column_ref(static_cast<const SplatCloud&>(cloud), name));
}
template <class T>
StridedView<const T> point_column(const GaussianCloud& cloud, std::string_view name) {
    return typed_column<const T>(column_ref(cloud, name));
}
template <class T>
StridedView<T> point_column(GaussianCloud& cloud, std::string_view name) {
    return typed_column<T>(column_ref(static_cast<const GaussianCloud&>(cloud), name));
}
// Read-only through the registry: an edit writes through registry.patch and marks what it changed.
template <class T>
StridedView<const T> point_column(const ecs::Registry& registry, ecs::Entity e, std::string_view name) {
    return typed_column<const T>(column_ref(registry, e, name));
}

}  // namespace sffd
