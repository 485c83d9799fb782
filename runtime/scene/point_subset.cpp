#include "runtime/scene/point_subset.h"

#include <limits>
#include <string>
#include <utility>

namespace sffd {

namespace {

// `width` values a point: out[k*width + j] = in[keep[k]*width + j]. Empty stays empty.
template <class T>
std::vector<T> gather(const std::vector<T>& in, std::span<const std::uint32_t> keep, std::size_t width = 1) {
    std::vector<T> out;
    if (in.empty()) return out;
    out.resize(keep.size() * width);
    T* o = out.data();
    for (const std::uint32_t i : keep) {
        const T* p = in.data() + std::size_t(i) * width;
        for (std::size_t j = 0; j < width; ++j) *o++ = p[j];
    }
    return out;
}

Status check_keep(std::span<const std::uint32_t> keep, std::size_t n) {
    if (n > std::numeric_limits<std::uint32_t>::max())
        return make_error("subset_points(): " + std::to_string(n) +
                          " points, more than 32-bit indices reach");
    for (std::size_t k = 0; k < keep.size(); ++k)
        if (keep[k] >= n)
            return make_error("subset_points(): index " + std::to_string(keep[k]) + " (entry " +
                              std::to_string(k) + ") is past the cloud's " + std::to_string(n) + " points");
    return {};
}

// Every column of the table (point_columns.h) that is not empty must be one entry per point.
Status check_columns(const std::vector<ColumnRef>& columns, std::size_t n, std::size_t sh_values,
                     const auto& sizes) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
        const std::size_t per = columns[c].spec->per_sh ? sh_values : 1;
        if (sizes[c] != 0 && sizes[c] != n * per)
            return make_error("subset_points(): column '" + std::string(columns[c].spec->name) + "' has " +
                              std::to_string(sizes[c]) + " values, the cloud's " + std::to_string(n) +
                              " points need " + std::to_string(n * per));
    }
    return {};
}

}  // namespace

std::vector<std::uint32_t> points_with(const PointFlags* flags, std::size_t points, std::uint8_t want,
                                       std::uint8_t drop) {
    std::vector<std::uint32_t> out;
    const bool have = flags && flags->bits.size() == points;
    if (!have && want != 0) return out;
    out.reserve(points);
    for (std::size_t i = 0; i < points; ++i) {
        const std::uint8_t b = have ? flags->bits[i] : 0;
        if ((b & want) == want && (b & drop) == 0) out.push_back(std::uint32_t(i));
    }
    return out;
}

std::vector<std::uint32_t> mask_indices(std::span<const std::uint8_t> keep) {
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < keep.size(); ++i)
        if (keep[i]) out.push_back(std::uint32_t(i));
    return out;
}

bool any_point_flagged(const PointFlags* flags, std::size_t points, std::uint8_t bits) {
    if (!flags || flags->bits.size() != points) return false;
    for (const std::uint8_t b : flags->bits)
        if (b & bits) return true;
    return false;
}

Result<SplatCloud> subset_points(const SplatCloud& c, std::span<const std::uint32_t> keep) {
    const std::size_t n = c.size();
    if (Status s = check_keep(keep, n); !s) return s.error();
    const std::size_t sizes[] = {c.positions.size(), c.normals.size(), c.axis_u.size(), c.axis_v.size(),
                                 c.colors.size(),    c.uvs.size(),     c.uv_axes.size()};
    if (Status s = check_columns(point_columns(c), n, 1, sizes); !s) return s.error();
    SplatCloud out;
    out.origin = c.origin;
    out.texture = c.texture;
    out.positions = gather(c.positions, keep);
    out.normals = gather(c.normals, keep);
    out.axis_u = gather(c.axis_u, keep);
    out.axis_v = gather(c.axis_v, keep);
    out.colors = gather(c.colors, keep);
    out.uvs = gather(c.uvs, keep);
    out.uv_axes = gather(c.uv_axes, keep);
    return out;
}

Result<GaussianCloud> subset_points(const GaussianCloud& g, std::span<const std::uint32_t> keep) {
    const std::size_t n = g.size();
    if (Status s = check_keep(keep, n); !s) return s.error();
    if (g.sh_degree < 0 || g.sh_degree > 3)
        return make_error("subset_points(): SH degree " + std::to_string(g.sh_degree) + " is not 0..3");
    const std::size_t sh = 3 * std::size_t(sh_coeffs(g.sh_degree));
    const std::size_t sizes[] = {g.positions.size(), g.scales.size(), g.rotations.size(), g.opacities.size(),
                                 g.sh.size()};
    if (Status s = check_columns(point_columns(g), n, sh, sizes); !s) return s.error();
    if (!g.sh_frames.empty() && g.sh_frames.size() != n)
        return make_error("subset_points(): 'sh_frames' has " + std::to_string(g.sh_frames.size()) +
                          " values for " + std::to_string(n) + " points");
    GaussianCloud out;
    out.origin = g.origin;
    out.sh_degree = g.sh_degree;
    out.positions = gather(g.positions, keep);
    out.scales = gather(g.scales, keep);
    out.rotations = gather(g.rotations, keep);
    out.opacities = gather(g.opacities, keep);
    out.sh = gather(g.sh, keep, sh);
    out.sh_frames = gather(g.sh_frames, keep);
    return out;
}

Result<PointFlags> subset_points(const PointFlags& f, std::size_t points,
                                 std::span<const std::uint32_t> keep) {
    if (Status s = check_keep(keep, points); !s) return s.error();
    if (!f.bits.empty() && f.bits.size() != points)
        return make_error("subset_points(): 'flags' has " + std::to_string(f.bits.size()) + " values for " +
                          std::to_string(points) + " points");
    return PointFlags{gather(f.bits, keep)};
}

Result<PointWeights> subset_points(const PointWeights& w, std::size_t points,
                                   std::span<const std::uint32_t> keep) {
    if (Status s = check_keep(keep, points); !s) return s.error();
    if (!w.values.empty() && w.values.size() != points)
        return make_error("subset_points(): 'weight' has " + std::to_string(w.values.size()) +
                          " values for " + std::to_string(points) + " points");
    return PointWeights{gather(w.values, keep)};
}

namespace {

// Every part subset first, then all written: a failure changes nothing.
template <class Cloud>
Result<std::size_t> keep_in(ecs::Registry& reg, ecs::Entity e, std::span<const std::uint32_t> keep) {
    const ecs::Registry& r = reg;
    const Cloud& cloud = r.get<Cloud>(e);
    const std::size_t n = cloud.size();
    const PointFlags* f = r.try_get<PointFlags>(e);
    const PointWeights* w = r.try_get<PointWeights>(e);
    auto c = subset_points(cloud, keep);
    if (!c) return c.error();
    Result<PointFlags> nf = f ? subset_points(*f, n, keep) : Result<PointFlags>(PointFlags{});
    if (!nf) return nf.error();
    Result<PointWeights> nw = w ? subset_points(*w, n, keep) : Result<PointWeights>(PointWeights{});
    if (!nw) return nw.error();
    const std::size_t dropped = n >= keep.size() ? n - keep.size() : 0;
    if (keep.size() == n) {  // the same points in the same order: nothing to change
        bool same = true;
        for (std::size_t k = 0; k < n && same; ++k) same = keep[k] == k;
        if (same) return std::size_t(0);
    }
    reg.patch<Cloud>(e) = std::move(*c);
    if (f) reg.patch<PointFlags>(e) = std::move(*nf);
    if (w) reg.patch<PointWeights>(e) = std::move(*nw);
    mark_cloud_replaced(reg, e);
    return dropped;
}

std::size_t cloud_size(const ecs::Registry& r, ecs::Entity e) {
    if (const SplatCloud* c = r.try_get<SplatCloud>(e)) return c->size();
    return r.get<GaussianCloud>(e).size();
}

bool has_cloud(const ecs::Registry& r, ecs::Entity e) {
    return r.valid(e) && (r.has<SplatCloud>(e) || r.has<GaussianCloud>(e));
}

}  // namespace

Result<std::size_t> keep_points(ecs::Registry& reg, ecs::Entity e, std::span<const std::uint32_t> keep) {
    if (!has_cloud(reg, e)) return make_error("keep_points(): the entity has no point cloud");
    return static_cast<const ecs::Registry&>(reg).has<SplatCloud>(e) ? keep_in<SplatCloud>(reg, e, keep)
                                                                     : keep_in<GaussianCloud>(reg, e, keep);
}

Result<std::size_t> drop_gone_points(ecs::Registry& reg, ecs::Entity e, PointDrop drop) {
    if (!has_cloud(reg, e)) return make_error("drop_gone_points(): the entity has no point cloud");
    const ecs::Registry& r = reg;
    const std::size_t n = cloud_size(r, e);
    const PointFlags* f = r.try_get<PointFlags>(e);
    if (!any_point_flagged(f, n, std::uint8_t(drop))) return std::size_t(0);
    return keep_points(reg, e, points_with(f, n, 0, std::uint8_t(drop)));
}

Result<std::size_t> extract_points(ecs::Registry& reg, ecs::Entity e) {
    if (!has_cloud(reg, e)) return make_error("extract_points(): the entity has no point cloud");
    const ecs::Registry& r = reg;
    const std::size_t n = cloud_size(r, e);
    return keep_points(reg, e, points_with(r.try_get<PointFlags>(e), n, kPointSelected, kPointGone));
}

}  // namespace sffd
