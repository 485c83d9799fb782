// The screen tools: regions (rectangle, brush circle, lasso and polygon), the click, and the depth buffer
// that decides what is visible. One pass over the blocks whose projected bounds can meet the query's
// screen box (parallel over blocks), in float, with the projection rows composed once in double.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/scene/camera.h"
#include "systems/point_select/point_select.h"
#include "systems/point_select/shown_points.h"

namespace sffd::point_select {
namespace {

using detail::Block;
using detail::kBlockPoints;
using detail::Shown;

glm::dvec4 row(const glm::dmat4& m, int r) { return {m[0][r], m[1][r], m[2][r], m[3][r]}; }

// Cloud frame -> (pixel x, pixel y, eye depth): x = dot(rx, p) / w, y = dot(ry, p) / w, w = dot(rw, p).
struct Projector {
    glm::dvec4 rx, ry, rw;
    glm::vec4 fx, fy, fw;
    float px_per_unit = 1.0f;  // pixels per world unit at eye depth 1
    float scale = 1.0f;        // the model's largest axis scale: cloud-frame radius -> world radius
    double width = 1.0, height = 1.0;

    Projector(const picking::ScreenView& view, const Shown& s) {
        const glm::dmat4 pvm =
            projection_matrix(view.camera, view.viewport) * view_matrix(view.camera) * s.model;
        width = view.viewport.width, height = view.viewport.height;
        rw = row(pvm, 3);
        rx = 0.5 * width * (row(pvm, 0) + rw);
        ry = 0.5 * height * (rw - row(pvm, 1));
        fx = glm::vec4(rx), fy = glm::vec4(ry), fw = glm::vec4(rw);
        px_per_unit = float(height / (2.0 * std::tan(glm::radians(double(view.camera.fov_y_degrees)) * 0.5)));
        scale = float(s.scale);
        const glm::dmat3 vm(view_matrix(view.camera) * s.model);
        to_eye_normal = glm::mat3(glm::transpose(glm::inverse(vm)));
    }
    glm::mat3 to_eye_normal{1.0f};  // cloud-frame normal -> eye-space normal (inverse transpose)
    // The eye-space point at pixel (x, y) and eye depth w (lookAt: x right, y up, looking down -z).
    glm::vec3 eye_point(float x, float y, float w) const {
        return {(x - float(width) * 0.5f) * w / px_per_unit, -(y - float(height) * 0.5f) * w / px_per_unit,
                -w};
    }
    // False behind the eye plane (or not finite).
    bool operator()(const glm::vec3& p, float& x, float& y, float& w) const {
        w = fw.x * p.x + fw.y * p.y + fw.z * p.z + fw.w;
        if (!(w > 0.0f) || !std::isfinite(w)) return false;
        const float inv = 1.0f / w;
        x = (fx.x * p.x + fx.y * p.y + fx.z * p.z + fx.w) * inv;
        y = (fy.x * p.x + fy.y * p.y + fy.z * p.z + fy.w) * inv;
        return std::isfinite(x) && std::isfinite(y);
    }
    float footprint_px(float radius, float w) const { return radius * scale * px_per_unit / w; }
};

struct Box {
    double x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    bool empty() const { return x0 > x1 || y0 > y1; }
};

Box clip_to_viewport(Box b, const Projector& p) {
    return {std::max(b.x0, 0.0), std::max(b.y0, 0.0), std::min(b.x1, p.width), std::min(b.y1, p.height)};
}

// Whether any point of the block can land within `margin(block)` pixels of the box.
bool block_meets(const Block& blk, const Projector& p, const Box& box, double max_margin_px) {
    if (blk.empty()) return false;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY, wmin = INFINITY;
    int behind = 0;
    for (int c = 0; c < 8; ++c) {
        const glm::dvec4 q((c & 1) ? blk.hi.x : blk.lo.x, (c & 2) ? blk.hi.y : blk.lo.y,
                           (c & 4) ? blk.hi.z : blk.lo.z, 1.0);
        const double w = glm::dot(p.rw, q);
        if (w <= 1e-9) {
            ++behind;
            continue;
        }
        wmin = std::min(wmin, w);
        const double x = glm::dot(p.rx, q) / w, y = glm::dot(p.ry, q) / w;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    if (behind == 8) return false;  // depth is linear: every point of the box is behind the eye
    if (behind > 0) return true;    // straddles the eye plane: its projection is unbounded
    const double margin =
        std::min(max_margin_px, double(blk.max_radius) * double(p.scale) * double(p.px_per_unit) / wmin) +
        1.0;
    return !(x1 + margin < box.x0 || x0 - margin > box.x1 || y1 + margin < box.y0 || y0 - margin > box.y1);
}

// Indices of the blocks that can meet the box; counts what was culled.
std::vector<std::uint32_t> meeting_blocks(const Shown& s, const Projector& p, const Box& box,
                                          double max_margin_px, PointSelectState& state) {
    std::vector<std::uint32_t> out;
    const std::vector<Block>& blocks = s.cache->blocks;
    for (std::size_t b = 0; b < blocks.size(); ++b)
        if (block_meets(blocks[b], p, box, max_margin_px)) out.push_back(std::uint32_t(b));
    auto& stats = state.impl().stats;
    stats.blocks_tested = out.size();
    stats.blocks_culled = blocks.size() - out.size();
    return out;
}

template <class Fn>
void for_blocks(const std::vector<std::uint32_t>& blocks, Fn&& fn) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k != r.end(); ++k) fn(k, blocks[k]);
                      });
}

// A depth buffer over the pixels [ix0, ix1) x [iy0, iy1): per pixel the least eye depth of the non-gone
// points whose footprint covers the pixel's centre, or which lie in it. A footprint with a normal is its
// disc in 3D (the pixel's ray meets its plane within its radius; the depth is that of the plane there); a
// round one is the screen disc of its projected radius at the centre's depth. Either is clipped to a
// screen disc of kMaxFootprintPx.
struct DepthBuffer {
    int ix0 = 0, iy0 = 0, w = 0, h = 0;
    std::vector<std::uint32_t> depth;  // float bits (positive floats order as their bits)

    float at(float x, float y) const {
        const int px = std::clamp(int(std::floor(x)) - ix0, 0, w - 1);
        const int py = std::clamp(int(std::floor(y)) - iy0, 0, h - 1);
        return std::bit_cast<float>(depth[std::size_t(py) * std::size_t(w) + std::size_t(px)]);
    }
    void write(int px, int py, std::uint32_t bits) {
        std::atomic_ref<std::uint32_t> cell(
            depth[std::size_t(py - iy0) * std::size_t(w) + std::size_t(px - ix0)]);
        std::uint32_t old = cell.load(std::memory_order_relaxed);
        while (bits < old && !cell.compare_exchange_weak(old, bits, std::memory_order_relaxed)) {
        }
    }
};

DepthBuffer build_depth(const Shown& s, const Projector& p, const Box& box, PointSelectState& state) {
    DepthBuffer z;
    if (box.empty()) return z;
    z.ix0 = int(std::floor(box.x0)), z.iy0 = int(std::floor(box.y0));
    const int ix1 = std::min(int(std::ceil(p.width)), int(std::floor(box.x1)) + 1);
    const int iy1 = std::min(int(std::ceil(p.height)), int(std::floor(box.y1)) + 1);
    z.w = std::max(1, ix1 - z.ix0), z.h = std::max(1, iy1 - z.iy0);
    z.depth.assign(std::size_t(z.w) * std::size_t(z.h), std::bit_cast<std::uint32_t>(INFINITY));
    const std::vector<std::uint32_t> blocks = meeting_blocks(s, p, box, kMaxFootprintPx, state);
    const float cap = float(kMaxFootprintPx);
    for_blocks(blocks, [&](std::size_t, std::uint32_t b) {
        const std::size_t end = std::min(s.n, (std::size_t(b) + 1) * kBlockPoints);
        for (std::size_t i = std::size_t(b) * kBlockPoints; i < end; ++i) {
            float x, y, w;
            if (s.gone(i) || !p(s.positions[i], x, y, w)) continue;
            const float r = std::min(cap, p.footprint_px(s.cache->radius[i], w));
            // The footprint's plane: eye depth at pixel centre (u, v) is d0 / (a u + b v + c), clamped to
            // the centre depth +- the footprint radius (the disc ends there); no normal: the centre depth.
            const glm::vec3 n = p.to_eye_normal * s.cache->normal[i];
            const float f = p.px_per_unit, rw = s.cache->radius[i] * p.scale;
            const float a = n.x / f, bb = -n.y / f;
            const float c = -n.z - a * float(p.width) * 0.5f - bb * float(p.height) * 0.5f;
            const glm::vec3 centre = p.eye_point(x, y, w);
            const float d0 = glm::dot(n, centre), rw2 = rw * rw;
            const bool plane = n != glm::vec3(0.0f);
            const int cx = int(std::floor(x)), cy = int(std::floor(y));
            const int x0 = std::max(z.ix0, int(std::floor(x - r))),
                      x1 = std::min(z.ix0 + z.w - 1, int(std::floor(x + r)));
            const int y0 = std::max(z.iy0, int(std::floor(y - r))),
                      y1 = std::min(z.iy0 + z.h - 1, int(std::floor(y + r)));
            const float r2 = r * r;
            for (int py = y0; py <= y1; ++py) {
                const float dy = float(py) + 0.5f - y;
                for (int px = x0; px <= x1; ++px) {
                    const float dx = float(px) + 0.5f - x;
                    const bool own = px == cx && py == cy;
                    if (dx * dx + dy * dy > r2 && !own) continue;
                    float depth = w;
                    if (plane) {
                        // Where the pixel's ray meets the plane; only pixels whose ray meets the disc itself
                        // (within its radius of the centre) are covered, as drawn.
                        const float u = float(px) + 0.5f, v = float(py) + 0.5f;
                        const float q = d0 / (a * u + bb * v + c);
                        const bool on_disc =
                            std::isfinite(q) && q > 0.0f &&
                            glm::dot(p.eye_point(u, v, q) - centre, p.eye_point(u, v, q) - centre) <= rw2;
                        if (on_disc) {
                            depth = q;
                        } else if (!own) {
                            continue;
                        }
                    }
                    z.write(px, py, std::bit_cast<std::uint32_t>(std::max(depth, 1e-30f)));
                }
            }
        }
    });
    return z;
}

// The exact region tests, with a footprint disc of radius `r` pixels for Footprint::whole.
class RegionTest {
public:
    explicit RegionTest(const ScreenRegion& region) : m_region(region) {
        if (region.shape != ScreenRegion::Shape::polygon || region.vertices.size() < 3) return;
        const auto& v = region.vertices;
        double lo = INFINITY, hi = -INFINITY;
        for (const glm::dvec2& q : v) lo = std::min(lo, q.y), hi = std::max(hi, q.y);
        if (!std::isfinite(lo) || !std::isfinite(hi) || hi - lo > 1e7) return;
        m_row0 = int(std::floor(lo));
        const int rows = int(std::floor(hi)) - m_row0 + 1;
        // Edges bucketed by the rows their y range covers (CSR), so a point tests only the edges of its row.
        m_start.assign(std::size_t(rows) + 1, 0);
        auto rows_of = [&](std::size_t e, int& r0, int& r1) {
            const glm::dvec2 a = v[e], b = v[(e + 1) % v.size()];
            r0 = int(std::floor(std::min(a.y, b.y))) - m_row0,
            r1 = int(std::floor(std::max(a.y, b.y))) - m_row0;
        };
        for (std::size_t e = 0; e < v.size(); ++e) {
            int r0, r1;
            rows_of(e, r0, r1);
            for (int r = r0; r <= r1; ++r) ++m_start[std::size_t(r) + 1];
        }
        for (std::size_t r = 0; r < std::size_t(rows); ++r) m_start[r + 1] += m_start[r];
        m_edges.resize(m_start.back());
        std::vector<std::uint32_t> fill(m_start.begin(), m_start.end() - 1);
        for (std::size_t e = 0; e < v.size(); ++e) {
            int r0, r1;
            rows_of(e, r0, r1);
            for (int r = r0; r <= r1; ++r) m_edges[fill[std::size_t(r)]++] = std::uint32_t(e);
        }
        m_polygon = true;
    }

    Box bounds() const {
        switch (m_region.shape) {
            case ScreenRegion::Shape::rect:
                return {std::min(m_region.a.x, m_region.b.x), std::min(m_region.a.y, m_region.b.y),
                        std::max(m_region.a.x, m_region.b.x), std::max(m_region.a.y, m_region.b.y)};
            case ScreenRegion::Shape::circle: {
                const double r = m_region.radius;
                if (!(r >= 0.0)) return {};
                return {m_region.centre.x - r, m_region.centre.y - r, m_region.centre.x + r,
                        m_region.centre.y + r};
            }
            case ScreenRegion::Shape::polygon: {
                if (!m_polygon) return {};
                Box b{INFINITY, INFINITY, -INFINITY, -INFINITY};
                for (const glm::dvec2& q : m_region.vertices)
                    b = {std::min(b.x0, q.x), std::min(b.y0, q.y), std::max(b.x1, q.x), std::max(b.y1, q.y)};
                return b;
            }
        }
        return {};
    }

    // Centre inside (r < 0) or the disc of radius r inside.
    bool contains(double x, double y, double r) const {
        switch (m_region.shape) {
            case ScreenRegion::Shape::rect: {
                const double rr = std::max(r, 0.0);
                const Box b = bounds();
                return x - rr >= b.x0 && x + rr <= b.x1 && y - rr >= b.y0 && y + rr <= b.y1;
            }
            case ScreenRegion::Shape::circle: {
                const double dx = x - m_region.centre.x, dy = y - m_region.centre.y;
                if (r < 0.0) return dx * dx + dy * dy <= m_region.radius * m_region.radius;
                return std::sqrt(dx * dx + dy * dy) + r <= m_region.radius;
            }
            case ScreenRegion::Shape::polygon: return m_polygon && polygon_contains(x, y, r);
        }
        return false;
    }

private:
    std::pair<std::size_t, std::size_t> row_edges(int row) const {
        const int r = row - m_row0;
        if (r < 0 || r + 1 >= int(m_start.size())) return {0, 0};
        return {m_start[std::size_t(r)], m_start[std::size_t(r) + 1]};
    }

    bool polygon_contains(double x, double y, double r) const {
        const auto& v = m_region.vertices;
        bool inside = false;
        const auto [b, e] = row_edges(int(std::floor(y)));
        for (std::size_t k = b; k < e; ++k) {
            const glm::dvec2 p = v[m_edges[k]], q = v[(m_edges[k] + 1) % v.size()];
            if ((p.y > y) != (q.y > y) && x < p.x + (y - p.y) * (q.x - p.x) / (q.y - p.y)) inside = !inside;
        }
        if (!inside || r <= 0.0) return inside;
        // Whole footprint: no edge within r of the centre (such an edge meets rows y - r .. y + r).
        const int lo = int(std::floor(y - r)), hi = int(std::floor(y + r));
        for (int row = std::max(lo, m_row0); row <= std::min(hi, m_row0 + int(m_start.size()) - 2); ++row) {
            const auto [rb, re] = row_edges(row);
            for (std::size_t k = rb; k < re; ++k) {
                const glm::dvec2 p = v[m_edges[k]], q = v[(m_edges[k] + 1) % v.size()];
                const glm::dvec2 d = q - p, c = glm::dvec2(x, y) - p;
                const double len2 = glm::dot(d, d);
                const double t = len2 > 0.0 ? std::clamp(glm::dot(c, d) / len2, 0.0, 1.0) : 0.0;
                const glm::dvec2 off = c - t * d;
                if (glm::dot(off, off) < r * r) return false;
            }
        }
        return true;
    }

    const ScreenRegion& m_region;
    bool m_polygon = false;
    int m_row0 = 0;
    std::vector<std::uint32_t> m_start, m_edges;
};

struct Candidate {
    std::uint32_t index;
    float x, y, depth, tolerance;
};

}  // namespace

ScreenRegion rect_region(glm::dvec2 a, glm::dvec2 b) {
    ScreenRegion r;
    r.shape = ScreenRegion::Shape::rect, r.a = a, r.b = b;
    return r;
}

ScreenRegion circle_region(glm::dvec2 centre, double radius) {
    ScreenRegion r;
    r.shape = ScreenRegion::Shape::circle, r.centre = centre, r.radius = radius;
    return r;
}

ScreenRegion polygon_region(std::vector<glm::dvec2> vertices) {
    ScreenRegion r;
    r.shape = ScreenRegion::Shape::polygon, r.vertices = std::move(vertices);
    return r;
}

bool region_contains(const ScreenRegion& region, glm::dvec2 point) {
    return RegionTest(region).contains(point.x, point.y, -1.0);
}

std::vector<std::uint32_t> points_in_region(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                            const picking::ScreenView& view, const ScreenRegion& region,
                                            const ScreenOptions& options) {
    const Shown s = detail::shown_points(registry, state, e);
    if (s.n == 0) return {};
    const Projector p(view, s);
    const RegionTest test(region);
    const Box box = clip_to_viewport(test.bounds(), p);
    if (box.empty()) return {};
    DepthBuffer z;
    if (options.visible_only) z = build_depth(s, p, box, state);

    const std::vector<std::uint32_t> blocks = meeting_blocks(s, p, box, 0.0, state);
    std::vector<std::vector<std::uint32_t>> found(blocks.size());
    const bool whole = options.footprint == Footprint::whole;
    const float tol_units = float(options.depth_tolerance) * p.scale;
    for_blocks(blocks, [&](std::size_t k, std::uint32_t b) {
        const std::size_t end = std::min(s.n, (std::size_t(b) + 1) * kBlockPoints);
        for (std::size_t i = std::size_t(b) * kBlockPoints; i < end; ++i) {
            float x, y, w;
            if (s.gone(i) || !p(s.positions[i], x, y, w)) continue;
            const double dx = x, dy = y;
            if (dx < box.x0 || dx > box.x1 || dy < box.y0 || dy > box.y1) continue;
            const double r = whole ? std::max(0.5, double(p.footprint_px(s.cache->radius[i], w))) : -1.0;
            if (!test.contains(dx, dy, r)) continue;
            if (options.visible_only && w > z.at(x, y) + tol_units * s.cache->radius[i] + 1e-6f * w) continue;
            found[k].push_back(std::uint32_t(i));
        }
    });
    std::vector<std::uint32_t> out;
    for (const auto& f : found) out.insert(out.end(), f.begin(), f.end());
    return out;  // blocks ascend and each block's points ascend: sorted
}

SelectionDelta select_region(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                             const picking::ScreenView& view, const ScreenRegion& region,
                             const ScreenOptions& options) {
    const std::vector<std::uint32_t> c = points_in_region(registry, state, e, view, region, options);
    return commit(registry, e, c, options.mode);
}

std::optional<std::uint32_t> point_under_cursor(ecs::Registry& registry, PointSelectState& state,
                                                ecs::Entity e, const picking::ScreenView& view,
                                                glm::dvec2 cursor, const ClickOptions& options) {
    const Shown s = detail::shown_points(registry, state, e);
    if (s.n == 0) return std::nullopt;
    const Projector p(view, s);
    const double tol = std::max(0.0, options.tolerance_px);
    const Box box{cursor.x - tol, cursor.y - tol, cursor.x + tol, cursor.y + tol};
    // Covering footprints can come from far centres: cull with the unclamped footprint.
    const std::vector<std::uint32_t> blocks =
        meeting_blocks(s, p, box, std::numeric_limits<double>::infinity(), state);
    std::vector<std::vector<Candidate>> covers(blocks.size()), near(blocks.size());
    const float cx = float(cursor.x), cy = float(cursor.y), tol2 = float(tol * tol);
    const float tol_units = p.scale;  // the region tools' default depth tolerance, one footprint radius
    for_blocks(blocks, [&](std::size_t k, std::uint32_t b) {
        const std::size_t end = std::min(s.n, (std::size_t(b) + 1) * kBlockPoints);
        for (std::size_t i = std::size_t(b) * kBlockPoints; i < end; ++i) {
            float x, y, w;
            if (s.gone(i) || !p(s.positions[i], x, y, w)) continue;
            const float rpx = std::max(0.5f, p.footprint_px(s.cache->radius[i], w));
            const float d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
            const Candidate c{std::uint32_t(i), x, y, w, tol_units * s.cache->radius[i] + 1e-6f * w};
            if (d2 <= rpx * rpx) covers[k].push_back(c);
            if (d2 <= tol2) near[k].push_back(c);
        }
    });
    auto dist2 = [&](const Candidate& c) { return (c.x - cx) * (c.x - cx) + (c.y - cy) * (c.y - cy); };
    // Best by (key, index): blocks and their points ascend, so the first of equal keys has the lower index.
    auto best = [&](const std::vector<std::vector<Candidate>>& lists, auto&& key,
                    auto&& keep) -> std::optional<std::uint32_t> {
        std::optional<std::uint32_t> out;
        float best_key = INFINITY;
        for (const auto& list : lists)
            for (const Candidate& c : list)
                if (keep(c) && key(c) < best_key) best_key = key(c), out = c.index;
        return out;
    };
    auto any = [](const Candidate&) { return true; };
    if (options.visible_only) {
        if (auto hit = best(
                covers, [](const Candidate& c) { return c.depth; }, any))
            return hit;
        const DepthBuffer z = build_depth(s, p, clip_to_viewport(box, p), state);
        if (z.depth.empty()) return std::nullopt;
        return best(near, dist2, [&](const Candidate& c) { return c.depth <= z.at(c.x, c.y) + c.tolerance; });
    }
    if (auto hit = best(covers, dist2, any)) return hit;
    return best(near, dist2, any);
}

SelectionDelta select_click(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                            const picking::ScreenView& view, glm::dvec2 cursor, Mode mode,
                            const ClickOptions& options) {
    const std::optional<std::uint32_t> hit = point_under_cursor(registry, state, e, view, cursor, options);
    std::vector<std::uint32_t> c;
    if (hit) c.push_back(*hit);
    return commit(registry, e, c, mode);
}

}  // namespace sffd::point_select
