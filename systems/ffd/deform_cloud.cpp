#include "systems/ffd/deform_cloud.h"

#include <tbb/parallel_for.h>

#include "runtime/core/log.h"
#include "systems/ffd/deform.h"

namespace sffd::ffd {

namespace {

// Each lattice in turn deforms out's arrays (n points): the first one that runs reads `first` (the
// authored arrays, so they are not copied first) when given, the later ones deform out's arrays in place.
// When no lattice ran, out's arrays get `first` as they are.
void deform_arrays(const glm::dvec3& origin, std::span<const Lattice* const> lattices, DeformedSplats& out,
                   std::size_t n, const SplatCloud* first, const char* who) {
    out.inverted = 0;
    auto ptr = [n](std::vector<glm::vec3>& v) { return v.size() == n ? v.data() : nullptr; };
    auto src = [n](const std::vector<glm::vec3>& v) { return v.size() == n ? v.data() : nullptr; };
    if (first) {  // outputs sized as their inputs (an output without its input is not written)
        auto fit = [n](std::vector<glm::vec3>& to, const std::vector<glm::vec3>& from) {
            if (from.size() == n) to.resize(n);
            else to.clear();
        };
        fit(out.positions, first->positions), fit(out.normals, first->normals);
        fit(out.axis_u, first->axis_u), fit(out.axis_v, first->axis_v);
    }
    bool read_first = first != nullptr;
    for (const Lattice* lattice : lattices) {
        if (!lattice) continue;
        // In place after the first: each lattice deforms the previous one's output (allowed by ffd::deform).
        const PointsIn in =
            read_first
                ? PointsIn{first->positions.data(),
                           src(first->normals),
                           src(first->axis_u),
                           src(first->axis_v),
                           n,
                           origin}
                : PointsIn{
                      out.positions.data(), ptr(out.normals), ptr(out.axis_u), ptr(out.axis_v), n, origin};
        const PointsOut o{out.positions.data(), ptr(out.normals), ptr(out.axis_u), ptr(out.axis_v)};
        const auto stats = deform(*lattice, in, o);
        if (!stats) {
            log::warn(who, ": ", stats.message(), " (lattice skipped)");
            continue;
        }
        read_first = false;
        out.inverted += stats->inverted;
    }
    if (read_first) {
        out.positions = first->positions, out.normals = first->normals;
        out.axis_u = first->axis_u, out.axis_v = first->axis_v;
    }
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

}  // namespace

void deform_cloud(const SplatCloud& cloud, std::span<const Lattice* const> lattices, DeformedSplats& out,
                  const char* who) {
    out.origin = cloud.origin;
    deform_arrays(cloud.origin, lattices, out, cloud.size(), &cloud, who);
    out.cpu_valid = true;
}

void deform_cloud_subset(const SplatCloud& cloud, std::span<const Lattice* const> lattices,
                         std::span<const std::uint32_t> indices, DeformedSplats& out, const char* who) {
    const std::size_t n = cloud.size();
    out.origin = cloud.origin;
    gather(cloud.positions, indices, n, out.positions);
    gather(cloud.normals, indices, n, out.normals);
    gather(cloud.axis_u, indices, n, out.axis_u);
    gather(cloud.axis_v, indices, n, out.axis_v);
    deform_arrays(cloud.origin, lattices, out, indices.size(), nullptr, who);
    out.cpu_valid = false;
}

}  // namespace sffd::ffd
