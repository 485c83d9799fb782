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
// Selections, hidden and deleted flags refer to points by index, never by position, so they survive
// deformation and animation (the deformed outputs keep the authored order).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

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
        requires std::is_convertible_v<U (*)[], T (*)[]>
    StridedView(std::span<U> values) : StridedView(values.data(), values.size()) {}
    template <class U>
        requires std::is_convertible_v<U (*)[], T (*)[]>
    StridedView(std::vector<U>& values) : StridedView(values.data(), values.size()) {}
    template <class U>
        requires std::is_convertible_v<const U (*)[], T (*)[]>
    StridedView(const std::vector<U>& values) : StridedView(values.data(), values.size()) {}

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

inline bool point_gone(const PointFlags* flags, std::size_t i) {
    return flags && !flags->bits.empty() && (flags->bits[i] & kPointGone) != 0;
}
inline float point_weight(const PointWeights* weights, std::size_t i) {
    return weights && !weights->values.empty() ? weights->values[i] : 1.0f;
}

}  // namespace sffd
