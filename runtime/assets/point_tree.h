// The one k-d tree of the importers (nanoflann over a contiguous array of glm::vec3 or glm::dvec3):
// k nearest neighbours for normal and radius estimation (splat_estimation.cpp), radius search for
// weighted sample elimination (surface_sampling.cpp). Internal to sffd_assets: nanoflann stays out of
// the public headers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>

#include <nanoflann.hpp>

namespace sffd::assets::detail {

template <class Vec>
struct PointSpanAdaptor {
    std::span<const Vec> pts;
    std::size_t kdtree_get_point_count() const { return pts.size(); }
    typename Vec::value_type kdtree_get_pt(std::size_t i, std::size_t d) const {
        return pts[i][static_cast<int>(d)];
    }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const {
        return false;
    }
};

// Built on construction; `points` must outlive the tree. Leaf size 16 (what both users had).
// Not copyable or movable: nanoflann's index keeps a reference to the adaptor beside it.
template <class Vec>
class PointTree {
public:
    using Scalar = typename Vec::value_type;
    using Index =
        nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<Scalar, PointSpanAdaptor<Vec>>,
                                            PointSpanAdaptor<Vec>, 3, std::uint32_t>;

    explicit PointTree(std::span<const Vec> points)
        : m_adaptor{points}, m_index(3, m_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
        m_index.buildIndex();
    }
    PointTree(const PointTree&) = delete;
    PointTree& operator=(const PointTree&) = delete;

    // The k nearest (the query point itself included when it is in the set), nearest first.
    std::size_t knn(const Scalar* query, std::size_t k, std::uint32_t* index, Scalar* dist2) const {
        return m_index.knnSearch(query, k, index, dist2);
    }
    // Every point within sqrt(radius2); arguments as nanoflann's radiusSearch (matches, search params).
    template <class... Args>
    std::size_t radius(const Scalar* query, Scalar radius2, Args&&... args) const {
        return m_index.radiusSearch(query, radius2, std::forward<Args>(args)...);
    }

private:
    PointSpanAdaptor<Vec> m_adaptor;
    Index m_index;
};

}  // namespace sffd::assets::detail
