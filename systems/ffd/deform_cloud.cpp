#include "systems/ffd/deform_cloud.h"

#include <algorithm>

#include <tbb/parallel_for.h>

#include "runtime/core/log.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

namespace {

// Each lattice in turn deforms points [first, first + count) of out's arrays: the first one that runs reads
// `authored` (so its arrays are not copied first) when given, the later ones deform out's arrays in place.
// When no lattice ran, out's arrays get `authored`'s points as they are. Returns the inverted count.
// `lattices` hold valid lattices only (checked once by the caller), so nothing is reported per range.
std::size_t deform_range(const glm::dvec3& origin, std::span<const Lattice* const> lattices,
                         DeformedSplats& out, std::size_t n, std::size_t first, std::size_t count,
                         const SplatCloud* authored, const float* weights) {
    std::size_t inverted = 0;
    auto ptr = [n, first](std::vector<glm::vec3>& v) { return v.size() == n ? v.data() + first : nullptr; };
    auto src = [n, first](const std::vector<glm::vec3>& v) {
        return v.size() == n ? v.data() + first : nullptr;
    };
    bool read_authored = authored != nullptr;
    for (const Lattice* lattice : lattices) {
        // In place after the first: each lattice deforms the previous one's output (allowed by ffd::deform).
        const PointsIn in = read_authored ? PointsIn{authored->positions.data() + first,
                                                     src(authored->normals),
                                                     src(authored->axis_u),
                                                     src(authored->axis_v),
                                                     count,
                                                     origin}
                                          : PointsIn{out.positions.data() + first,
                                                     ptr(out.normals),
                                                     ptr(out.axis_u),
                                                     ptr(out.axis_v),
                                                     count,
                                                     origin};
        PointsIn weighted = in;
        weighted.weights = weights ? weights + first : nullptr;  // the same weight for every lattice's step
        const PointsOut o{out.positions.data() + first, ptr(out.normals), ptr(out.axis_u), ptr(out.axis_v)};
        const auto stats = deform(*lattice, weighted, o);
        if (!stats) continue;  // validated by the caller: not reached
        read_authored = false;
        inverted += stats->inverted;
    }
    if (read_authored) {
        auto copy = [&](const std::vector<glm::vec3>& from, std::vector<glm::vec3>& to) {
            if (from.size() == n && to.size() == n)
                std::copy_n(from.begin() + std::ptrdiff_t(first), count, to.begin() + std::ptrdiff_t(first));
        };
        copy(authored->positions, out.positions), copy(authored->normals, out.normals);
        copy(authored->axis_u, out.axis_u), copy(authored->axis_v, out.axis_v);
    }
    return inverted;
}

// The lattices that pass validation; the others are reported once and skipped.
std::vector<const Lattice*> valid_lattices(std::span<const Lattice* const> lattices, const char* who) {
    std::vector<const Lattice*> ok;
    for (const Lattice* l : lattices) {
        if (!l) continue;
        if (Status s = validate(*l); !s) {
            log::warn(who, ": ", s.message(), " (lattice skipped)");
            continue;
        }
        ok.push_back(l);
    }
    return ok;
}

template <class T>
void gather(const std::vector<T>& from, std::span<const std::uint32_t> indices, std::size_t n,
            std::vector<T>& to) {
    if (from.size() != n) {
        to.clear();
        return;
    }
    to.resize(indices.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, indices.size(), 1 << 14), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) to[i] = from[indices[i]];
    });
}

// The weights of a cloud of n points, or null (absent, empty, or not one per point: weight 1).
const float* weight_column(const PointWeights* weights, std::size_t n) {
    return weights && weights->values.size() == n && n > 0 ? weights->values.data() : nullptr;
}

}  // namespace

void deform_cloud(const SplatCloud& cloud, std::span<const Lattice* const> lattices, DeformedSplats& out,
                  const char* who, const PointWeights* weights) {
    const std::size_t n = cloud.size();
    // Outputs sized as their inputs (an output without its input is not written).
    auto fit = [n](std::vector<glm::vec3>& to, const std::vector<glm::vec3>& from) {
        if (from.size() == n) to.resize(n);
        else to.clear();
    };
    fit(out.positions, cloud.positions), fit(out.normals, cloud.normals);
    fit(out.axis_u, cloud.axis_u), fit(out.axis_v, cloud.axis_v);
    std::vector<std::uint32_t> all(page_count(n));
    for (std::size_t p = 0; p < all.size(); ++p) all[p] = std::uint32_t(p);
    out.paged.counts.assign(all.size(), {0, 0, 0});
    deform_cloud_pages(cloud, lattices, all, out, who, weights);
}

void deform_cloud_pages(const SplatCloud& cloud, std::span<const Lattice* const> lattices,
                        std::span<const std::uint32_t> pages, DeformedSplats& out, const char* who,
                        const PointWeights* weights) {
    const std::size_t n = cloud.size();
    out.origin = cloud.origin;
    const std::vector<const Lattice*> ok = valid_lattices(lattices, who);
    const float* w = weight_column(weights, n);
    out.paged.counts.resize(page_count(n), {0, 0, 0});
    for (std::uint32_t p : pages) {
        const PageRange r = page_range(p, n);
        out.paged.counts[p][0] =
            std::uint32_t(deform_range(cloud.origin, ok, out, n, r.first, r.count, &cloud, w));
    }
    out.inverted = 0;
    for (const auto& c : out.paged.counts) out.inverted += c[0];
    out.cpu_valid = true;
}

void deform_cloud_subset(const SplatCloud& cloud, std::span<const Lattice* const> lattices,
                         std::span<const std::uint32_t> indices, DeformedSplats& out, const char* who,
                         const PointWeights* weights) {
    const std::size_t n = cloud.size();
    out.origin = cloud.origin;
    gather(cloud.positions, indices, n, out.positions);
    gather(cloud.normals, indices, n, out.normals);
    gather(cloud.axis_u, indices, n, out.axis_u);
    gather(cloud.axis_v, indices, n, out.axis_v);
    std::vector<float> kept_weights;
    if (const float* w = weight_column(weights, n)) {
        kept_weights.resize(indices.size());
        for (std::size_t i = 0; i < indices.size(); ++i) kept_weights[i] = w[indices[i]];
    }
    const std::vector<const Lattice*> ok = valid_lattices(lattices, who);
    out.inverted = deform_range(cloud.origin, ok, out, indices.size(), 0, indices.size(), nullptr,
                                kept_weights.empty() ? nullptr : kept_weights.data());
    out.cpu_valid = false;
}

}  // namespace sffd::ffd
