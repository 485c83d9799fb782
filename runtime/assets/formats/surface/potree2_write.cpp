#include "runtime/assets/formats/surface/potree2_write.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include <nlohmann/json.hpp>
#include <stb/stb_image_write.h>

#include "runtime/assets/formats/lod/cell_buckets.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_detail.h"
#include "runtime/core/atomic_file.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using lod::Cell;
using lod::LedgerHold;
using lod::MemoryLedger;

namespace {

using json = nlohmann::ordered_json;
using potree2_detail::Rec;

// The columns a source has (every chunk alike).
struct Columns {
    bool colors = false, alpha = false, uvs = false, uv_axes = false;
};

Rec to_rec(const SplatCloud& c, std::size_t i, const Columns& k) {
    Rec r{};
    const glm::dvec3 p = c.origin + glm::dvec3(c.positions[i]);
    r.p[0] = p.x, r.p[1] = p.y, r.p[2] = p.z;
    std::memcpy(r.n, &c.normals[i], 12);
    std::memcpy(r.u, &c.axis_u[i], 12);
    std::memcpy(r.v, &c.axis_v[i], 12);
    r.radius = std::max(glm::length(c.axis_u[i]), glm::length(c.axis_v[i]));
    r.color = k.colors ? c.colors[i] : 0xffffffffu;
    if (k.uvs) std::memcpy(r.uv, &c.uvs[i], 8);
    if (k.uv_axes) std::memcpy(r.uva, &c.uv_axes[i], 16);
    return r;
}

using Key = std::tuple<int, std::uint64_t, std::uint64_t, std::uint64_t>;

struct NodeEntry {
    std::uint32_t points = 0;
    std::uint64_t offset = 0, size = 0;
    bool inner = false;  // was split
};

// An octree node being built: its cube and the points it holds now.
struct Work {
    Key key;
    glm::dvec3 lo, hi;
    std::vector<Rec> pts;
    std::vector<std::size_t> kids;  // indices into the builder's arena
};

// A point as the cover pass needs it (the children of a cell's root, kept until the root is final).
struct CoverPt {
    double p[3];
    float radius;
};

float own_radius(const Rec& r) {
    return std::max(glm::length(glm::vec3(r.u[0], r.u[1], r.u[2])),
                    glm::length(glm::vec3(r.v[0], r.v[1], r.v[2])));
}

class Builder {
public:
    Builder(const Potree2BuildOptions& o, const potree2_detail::Layout& layout, std::FILE* octree,
            std::string out)
        : o_(o), layout_(layout), f_(octree), out_(std::move(out)) {}

    MemoryLedger ledger;
    Potree2BuildStats stats;
    std::map<Key, NodeEntry> table;
    potree2_detail::Bounds bounds;

    // One bucketed cell: its subtree built and covered, every node but its root written; the root waits.
    Status cell(std::vector<std::byte>& records, std::size_t n, const Cell& c) {
        // The records become the points; bucket_cells still counts them as records until we return.
        std::vector<Rec> pts(n);
        std::memcpy(pts.data(), records.data(), n * sizeof(Rec));
        std::vector<std::byte>().swap(records);
        // Splitting copies a node's points into its octants once: twice the cell at most.
        LedgerHold hold(ledger, n * sizeof(Rec));
        stats.cell_cap = std::max<std::uint64_t>(stats.cell_cap, n);
        ++stats.cells;
        std::vector<Work> arena;
        const Key key{c.level, c.coords.x, c.coords.y, c.coords.z};
        build(arena, key, c.lo, c.hi, std::move(pts));
        // Preorder: children after their parent, so backwards is bottom up.
        for (std::size_t i = arena.size(); i-- > 1;) cover_from_kids(arena, i);
        for (std::size_t i = 1; i < arena.size(); ++i)
            if (Status s = emit(arena[i]); !s) return s;
        Work& root = arena[0];
        std::vector<CoverPt> kept;
        for (std::size_t kid : root.kids)
            for (const Rec& r : arena[kid].pts) kept.push_back({{r.p[0], r.p[1], r.p[2]}, r.radius});
        hold_ += root.pts.size() * sizeof(Rec) + kept.size() * sizeof(CoverPt);
        ledger.add(root.pts.size() * sizeof(Rec) + kept.size() * sizeof(CoverPt));
        table[key].inner = !root.kids.empty();
        root.kids.clear();
        kept_.emplace(key, std::move(kept));
        waiting_.emplace(key, std::move(root));
        for (int l = 1; l <= c.level; ++l)
            ancestors_.insert({c.level - l, c.coords.x >> l, c.coords.y >> l, c.coords.z >> l});
        return {};
    }

    // The octree above the cells from the waiting roots: representatives bottom up, then every waiting
    // node's cover (bottom up, each from its children's final points), then written.
    Status finish(const Cell& root) {
        std::vector<Key> up(ancestors_.begin(), ancestors_.end());
        const auto deeper = [](const Key& a, const Key& b) { return std::get<0>(a) > std::get<0>(b); };
        std::sort(up.begin(), up.end(), deeper);
        std::map<Key, std::vector<Key>> kids_of;
        for (const Key& k : up) {
            const auto [level, x, y, z] = k;
            Work w;
            w.key = k;
            const double size = (root.hi.x - root.lo.x) / double(std::uint64_t(1) << level);
            w.lo = root.lo + glm::dvec3(double(x), double(y), double(z)) * size;
            w.hi = w.lo + glm::dvec3(size);
            std::vector<Work*> kids;
            std::vector<char> inner;
            std::vector<Key> kid_keys;
            for (int c = 0; c < 8; ++c) {
                const Key ck{level + 1, x * 2 + std::uint64_t((c >> 2) & 1),
                             y * 2 + std::uint64_t((c >> 1) & 1), z * 2 + std::uint64_t(c & 1)};
                if (auto it = waiting_.find(ck); it != waiting_.end()) {
                    kids.push_back(&it->second), kid_keys.push_back(ck), inner.push_back(table[ck].inner);
                }
            }
            subsample(w, kids, inner);
            for (std::size_t i = 0; i < kids.size(); ++i)
                if (kids[i]->pts.empty() && !inner[i]) {
                    table.erase(kid_keys[i]);
                    waiting_.erase(kid_keys[i]);
                } else {
                    kids_of[k].push_back(kid_keys[i]);
                }
            table[k].inner = true;
            waiting_.emplace(k, std::move(w));
        }
        std::vector<Key> all;
        for (const auto& [k, w] : waiting_) all.push_back(k);
        std::stable_sort(all.begin(), all.end(), deeper);
        for (const Key& k : all) {
            Work& w = waiting_.at(k);
            std::vector<CoverPt> from;
            if (auto it = kept_.find(k); it != kept_.end()) from = std::move(it->second);
            for (const Key& ck : kids_of[k])
                for (const Rec& r : waiting_.at(ck).pts) from.push_back({{r.p[0], r.p[1], r.p[2]}, r.radius});
            cover(w, from);
        }
        for (auto& [k, w] : waiting_)
            if (Status s = emit(w); !s) return s;
        waiting_.clear();
        kept_.clear();
        ledger.sub(hold_);
        return {};
    }

private:
    // Splits while the node is too full, then takes representatives out of its children.
    std::size_t build(std::vector<Work>& arena, const Key& key, glm::dvec3 lo, glm::dvec3 hi,
                      std::vector<Rec> pts) {
        const std::size_t self = arena.size();
        arena.push_back(Work{key, lo, hi, {}, {}});
        const int level = std::get<0>(key);
        if (pts.size() <= o_.max_leaf || level >= kMaxPotreeDepth) {
            arena[self].pts = std::move(pts);
            return self;
        }
        const glm::dvec3 mid = 0.5 * (lo + hi);
        std::array<std::vector<Rec>, 8> parts;
        for (const Rec& r : pts)
            parts[std::size_t((r.p[0] >= mid.x) << 2 | (r.p[1] >= mid.y) << 1 | (r.p[2] >= mid.z))].push_back(
                r);
        std::vector<Rec>().swap(pts);
        const auto [l, x, y, z] = key;
        for (int c = 0; c < 8; ++c) {
            if (parts[std::size_t(c)].empty()) continue;
            const glm::dvec3 clo((c & 4) ? mid.x : lo.x, (c & 2) ? mid.y : lo.y, (c & 1) ? mid.z : lo.z);
            const glm::dvec3 chi((c & 4) ? hi.x : mid.x, (c & 2) ? hi.y : mid.y, (c & 1) ? hi.z : mid.z);
            const Key ck{l + 1, x * 2 + std::uint64_t((c >> 2) & 1), y * 2 + std::uint64_t((c >> 1) & 1),
                         z * 2 + std::uint64_t(c & 1)};
            const std::size_t kid = build(arena, ck, clo, chi, std::move(parts[std::size_t(c)]));
            arena[self].kids.push_back(kid);
        }
        std::vector<Work*> kids;
        std::vector<char> inner;
        for (std::size_t kid : arena[self].kids)
            kids.push_back(&arena[kid]), inner.push_back(!arena[kid].kids.empty());
        subsample(arena[self], kids, inner);
        // Leaves emptied by the subsampling are dropped (an inner node always keeps a point).
        std::vector<std::size_t> kept;
        for (std::size_t kid : arena[self].kids)
            if (!arena[kid].pts.empty() || !arena[kid].kids.empty()) kept.push_back(kid);
            else arena[kid].key = Key{-1, 0, 0, 0};
        arena[self].kids = std::move(kept);
        return self;
    }

    // One representative per occupied grid cell of `w` (the splat nearest the cell's centre), taken out of
    // the children; an inner child gives up its last splat to nobody, so every inner node keeps one.
    void subsample(Work& w, const std::vector<Work*>& kids, const std::vector<char>& inner) {
        struct Cand {
            std::uint32_t cell;
            double d2;
            std::uint32_t kid, index;
        };
        const std::uint32_t g = std::uint32_t(o_.grid_cells);
        const glm::dvec3 size = (w.hi - w.lo) / double(g);
        std::vector<Cand> cand;
        std::vector<std::size_t> left(kids.size());
        for (std::uint32_t k = 0; k < kids.size(); ++k) {
            left[k] = kids[k]->pts.size();
            for (std::uint32_t i = 0; i < kids[k]->pts.size(); ++i) {
                const Rec& r = kids[k]->pts[i];
                std::uint32_t idx[3];
                double d2 = 0;
                for (int a = 0; a < 3; ++a) {
                    const double t = (r.p[a] - w.lo[a]) / size[a];
                    idx[a] = std::uint32_t(std::clamp(t, 0.0, double(g - 1)));
                    const double c = w.lo[a] + (double(idx[a]) + 0.5) * size[a];
                    d2 += (r.p[a] - c) * (r.p[a] - c);
                }
                cand.push_back({idx[0] + g * (idx[1] + g * idx[2]), d2, k, i});
            }
        }
        std::sort(cand.begin(), cand.end(), [](const Cand& a, const Cand& b) {
            return std::tie(a.cell, a.d2, a.kid, a.index) < std::tie(b.cell, b.d2, b.kid, b.index);
        });
        std::vector<std::vector<char>> taken(kids.size());
        for (std::size_t k = 0; k < kids.size(); ++k) taken[k].assign(kids[k]->pts.size(), 0);
        for (std::size_t a = 0; a < cand.size();) {
            std::size_t b = a;
            while (b < cand.size() && cand[b].cell == cand[a].cell) ++b;
            for (std::size_t c = a; c < b; ++c) {
                const Cand& q = cand[c];
                if (inner[q.kid] && left[q.kid] <= 1) continue;
                --left[q.kid];
                taken[q.kid][q.index] = 1;
                w.pts.push_back(kids[q.kid]->pts[q.index]);
                break;
            }
            a = b;
        }
        for (std::size_t k = 0; k < kids.size(); ++k) {
            std::vector<Rec>& v = kids[k]->pts;
            std::size_t o = 0;
            for (std::size_t i = 0; i < v.size(); ++i)
                if (!taken[k][i]) v[o++] = v[i];
            v.resize(o);
        }
    }

    void cover_from_kids(std::vector<Work>& arena, std::size_t i) {
        std::vector<CoverPt> from;
        for (std::size_t kid : arena[i].kids)
            for (const Rec& r : arena[kid].pts) from.push_back({{r.p[0], r.p[1], r.p[2]}, r.radius});
        cover(arena[i], from);
    }

    // Each splat's lod radius: its own radius, grown so that every splat of the children (each with its
    // own lod radius, which covers the subtree below it) lies inside its nearest representative's.
    void cover(Work& w, const std::vector<CoverPt>& from) {
        for (Rec& r : w.pts) r.radius = own_radius(r);
        if (from.empty() || w.pts.empty()) return;
        // A search grid of twice the sampling grid's cells: the nearest representative is nearly always
        // in the point's own search cell or a neighbour.
        const std::int64_t g = std::max(1, o_.grid_cells / 2);
        const glm::dvec3 size = (w.hi - w.lo) / double(g);
        const auto cell_of = [&](const double* p, std::int64_t* idx) {
            for (int a = 0; a < 3; ++a)
                idx[a] = std::int64_t(std::clamp((p[a] - w.lo[a]) / size[a], 0.0, double(g - 1)));
        };
        // The representatives sorted by grid cell, found by binary search.
        std::vector<std::pair<std::int64_t, std::uint32_t>> grid(w.pts.size());
        for (std::uint32_t i = 0; i < w.pts.size(); ++i) {
            std::int64_t idx[3];
            cell_of(w.pts[i].p, idx);
            grid[i] = {idx[0] + g * (idx[1] + g * idx[2]), i};
        }
        std::sort(grid.begin(), grid.end());
        std::vector<double> reach(w.pts.size());
        for (std::size_t i = 0; i < w.pts.size(); ++i) reach[i] = double(w.pts[i].radius);
        const double step = std::min({size.x, size.y, size.z});
        for (const CoverPt& p : from) {
            std::int64_t c[3];
            cell_of(p.p, c);
            double best = std::numeric_limits<double>::infinity();
            std::uint32_t best_i = 0;
            for (std::int64_t ring = 0; ring < g; ++ring) {
                // Cells of this ring are at least (ring - 1) cells away.
                if (best < double(ring - 1) * step) break;
                for (std::int64_t dx = -ring; dx <= ring; ++dx)
                    for (std::int64_t dy = -ring; dy <= ring; ++dy)
                        for (std::int64_t dz = -ring; dz <= ring; ++dz) {
                            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
                            const std::int64_t x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
                            if (x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g) continue;
                            const std::int64_t key = x + g * (y + g * z);
                            auto it =
                                std::lower_bound(grid.begin(), grid.end(), std::pair{key, std::uint32_t(0)});
                            for (; it != grid.end() && it->first == key; ++it) {
                                const Rec& q = w.pts[it->second];
                                const double d = glm::length(
                                    glm::dvec3(p.p[0] - q.p[0], p.p[1] - q.p[1], p.p[2] - q.p[2]));
                                if (d < best) best = d, best_i = it->second;
                            }
                        }
            }
            reach[best_i] = std::max(reach[best_i], best + double(p.radius));
        }
        // Float rounding must not undercut the cover.
        for (std::size_t i = 0; i < w.pts.size(); ++i)
            w.pts[i].radius = std::nextafter(float(reach[i]), INFINITY);
    }

    // A finished node's points to octree.bin.
    Status emit(const Work& w) {
        if (std::get<0>(w.key) < 0) return {};
        NodeEntry& e = table[w.key];
        e.points = std::uint32_t(w.pts.size());
        e.offset = written_;
        e.size = std::uint64_t(w.pts.size()) * layout_.point_bytes;
        std::vector<std::uint8_t> buf(std::size_t(e.size));
        for (std::size_t i = 0; i < w.pts.size(); ++i)
            potree2_detail::encode(w.pts[i], layout_, buf.data() + i * layout_.point_bytes, bounds);
        if (!buf.empty() && std::fwrite(buf.data(), 1, buf.size(), f_) != buf.size())
            return make_error(out_ + ": write failed");
        written_ += e.size;
        stats.octree_bytes = written_;

        return {};
    }

    const Potree2BuildOptions& o_;
    const potree2_detail::Layout& layout_;
    std::FILE* f_;
    std::string out_;
    std::uint64_t written_ = 0, hold_ = 0;
    std::map<Key, Work> waiting_;
    std::map<Key, std::vector<CoverPt>> kept_;
    std::set<Key> ancestors_;
};

// hierarchy.bin as PotreeConverter's createHierarchy writes it: chunks of `step` levels, breadth first
// within a chunk, the chunks in the order a stack of proxies gives.
std::string hierarchy_bytes(const std::map<Key, NodeEntry>& table, int step, std::uint64_t& first_chunk,
                            std::size_t& chunk_count) {
    const auto children = [&](const Key& k) {
        std::vector<Key> out;
        const auto [l, x, y, z] = k;
        for (int c = 0; c < 8; ++c) {
            const Key ck{l + 1, x * 2 + std::uint64_t((c >> 2) & 1), y * 2 + std::uint64_t((c >> 1) & 1),
                         z * 2 + std::uint64_t(c & 1)};
            if (table.count(ck)) out.push_back(ck);
        }
        return out;
    };
    std::vector<std::vector<Key>> chunks;
    std::vector<Key> stack{Key{0, 0, 0, 0}};
    while (!stack.empty()) {
        const Key top = stack.back();
        stack.pop_back();
        std::vector<Key> chunk{top};  // breadth first: parents before children, children in order
        for (std::size_t i = 0; i < chunk.size(); ++i) {
            if (std::get<0>(chunk[i]) == std::get<0>(top) + step) {
                stack.push_back(chunk[i]);
                continue;
            }
            for (const Key& c : children(chunk[i])) chunk.push_back(c);
        }
        chunks.push_back(std::move(chunk));
    }
    std::map<Key, std::size_t> chunk_of;
    std::vector<std::uint64_t> at(chunks.size() + 1, 0);
    for (std::size_t i = 0; i < chunks.size(); ++i) {
        chunk_of[chunks[i][0]] = i;
        at[i + 1] = at[i] + chunks[i].size() * kPotreeNodeBytes;
    }
    std::string out(std::size_t(at.back()), '\0');
    std::size_t o = 0;
    for (const auto& chunk : chunks) {
        const int level0 = std::get<0>(chunk[0]);
        for (const Key& k : chunk) {
            const NodeEntry& e = table.at(k);
            std::uint8_t mask = 0;
            const auto [l, x, y, z] = k;
            for (int c = 0; c < 8; ++c)
                if (table.count({l + 1, x * 2 + std::uint64_t((c >> 2) & 1),
                                 y * 2 + std::uint64_t((c >> 1) & 1), z * 2 + std::uint64_t(c & 1)}))
                    mask = std::uint8_t(mask | (1u << c));
            std::uint8_t type = mask == 0 ? 1 : 0;
            std::uint64_t off = e.offset, size = e.size;
            if (l == level0 + step) {
                const std::size_t target = chunk_of.at(k);
                type = 2, off = at[target], size = chunks[target].size() * kPotreeNodeBytes;
            }
            out[o] = char(type), out[o + 1] = char(mask);
            std::memcpy(&out[o + 2], &e.points, 4);
            std::memcpy(&out[o + 6], &off, 8);
            std::memcpy(&out[o + 14], &size, 8);
            o += kPotreeNodeBytes;
        }
    }
    first_chunk = at[1];
    chunk_count = chunks.size();
    return out;
}

json vec_json(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }

}  // namespace

Result<Potree2BuildStats> build_potree2(const SplatSource& source, const fs::path& metadata,
                                        const Potree2BuildOptions& o) {
    const std::string out = metadata.string();
    if (metadata.filename() != "metadata.json")
        return make_error(out + ": a Potree 2 octree is written as a folder's metadata.json");
    if (o.max_leaf < 16) return make_error(out + ": the leaf size must be at least 16");
    if (o.grid_cells < 2 || o.grid_cells > 1024)
        return make_error(out + ": the grid must be 2 to 1024 cells");
    // 1. Count, bounds, columns.
    std::uint64_t count = 0;
    Columns k;
    bool first = true;
    const double inf = std::numeric_limits<double>::infinity();
    glm::dvec3 lo(inf), hi(-inf), origin(0.0);
    report_progress(o.progress, "reading", 0.0);
    if (Status s = source.scan([&](const SplatCloud& c) -> Status {
            const std::size_t n = c.size();
            if (c.normals.size() != n || c.axis_u.size() != n || c.axis_v.size() != n)
                return make_error(source.name + ": every splat needs a normal and its axes");
            const Columns ck{!c.colors.empty(), false, !c.uvs.empty(), !c.uv_axes.empty()};
            if ((ck.colors && c.colors.size() != n) || (ck.uvs && c.uvs.size() != n) ||
                (ck.uv_axes && c.uv_axes.size() != n))
                return make_error(source.name + ": a column of the wrong length");
            if (n == 0) return {};
            if (first) k = ck, origin = c.origin, first = false;
            else if (ck.colors != k.colors || ck.uvs != k.uvs || ck.uv_axes != k.uv_axes)
                return make_error(source.name + ": the columns change from chunk to chunk");
            for (std::size_t i = 0; i < n; ++i) {
                const glm::dvec3 p = c.origin + glm::dvec3(c.positions[i]);
                if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                    return make_error(source.name + ": splat " + std::to_string(count + i) +
                                      " is not finite");
                lo = glm::min(lo, p), hi = glm::max(hi, p);
                if (k.colors && (c.colors[i] >> 24) != 255u) k.alpha = true;
            }
            count += n;
            return {};
        });
        !s)
        return s.error();
    report_progress(o.progress, "reading", 1.0);
    if (count == 0) return make_error(source.name + ": no splats to build an octree of");
    if (count > kMaxPotreePoints)
        return make_error(source.name + ": " + std::to_string(count) + " splats, more than the " +
                          std::to_string(kMaxPotreePoints) + " an octree holds");
    const fs::path dir = metadata.parent_path().empty() ? fs::path(".") : metadata.parent_path();
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return make_error(dir.string() + ": cannot create the folder: " + ec.message());
    const Cell root = lod::root_cell(lo, hi);
    potree2_detail::Layout layout;
    layout.offset = root.lo;
    const double side = root.hi.x - root.lo.x;
    layout.scale = glm::dvec3(std::ldexp(1.0, int(std::ceil(std::log2(side / double(1 << 30))))));
    layout.colors = k.colors, layout.alpha = k.alpha, layout.uvs = k.uvs, layout.uv_axes = k.uv_axes;
    potree2_detail::finish_layout(layout);

    Potree2BuildStats stats;
    potree2_detail::Bounds bounds;
    std::map<Key, NodeEntry> table;
    const fs::path octree_path = dir / "octree.bin";
    Status built = write_file_atomic(octree_path, [&](std::FILE* f) -> Status {
        Builder b(o, layout, f, octree_path.string());
        const std::uint64_t budget = o.memory_budget;
        const std::uint64_t scatter = std::min<std::uint64_t>(lod::kScatterBytes, budget / 8);
        lod::BucketOptions bo;
        bo.record_bytes = sizeof(Rec);
        // A cell's records, its points and their octant copies: about 3 records a splat.
        bo.cap_records = std::max<std::uint64_t>(4 * o.max_leaf, (budget - 2 * scatter) / (4 * sizeof(Rec)));
        bo.scatter_bytes = scatter;
        bo.temp_dir = o.temp_dir.empty() ? dir : o.temp_dir;
        bo.ledger = &b.ledger;
        std::uint64_t scattered = 0, in_cells = 0;
        bo.scattered = [&](std::uint64_t m) {
            scattered += m;
            report_progress(o.progress, "bucketing", std::min(1.0, double(scattered) / double(count)));
        };
        const lod::RecordScan scan = [&](const lod::RecordSink& sink) -> Status {
            std::vector<Rec> buf;
            return source.scan([&](const SplatCloud& c) -> Status {
                LedgerHold hold(b.ledger, c.size() * sizeof(Rec));
                buf.resize(c.size());
                for (std::size_t i = 0; i < c.size(); ++i) buf[i] = to_rec(c, i, k);
                return sink(reinterpret_cast<const std::byte*>(buf.data()), buf.size());
            });
        };
        if (Status s = lod::bucket_cells(
                scan, count, root, bo, source.name,
                [&](std::vector<std::byte>& r, std::size_t n, const Cell& c) -> Status {
                    report_progress(o.progress, "building cells", double(in_cells) / double(count));
                    Status st = b.cell(r, n, c);
                    in_cells += n;
                    report_progress(o.progress, "building cells", double(in_cells) / double(count));
                    return st;
                });
            !s)
            return s;
        report_progress(o.progress, "building the top", 0.0);
        if (Status s = b.finish(root); !s) return s;
        stats = b.stats;
        stats.peak_bytes = b.ledger.peak();
        bounds = b.bounds;
        table = std::move(b.table);
        return {};
    });
    if (!built) return built.error();

    // 5. hierarchy.bin, the texture, metadata.json.
    report_progress(o.progress, "writing the hierarchy", 0.0);
    std::uint64_t first_chunk = 0;
    const std::string hier = hierarchy_bytes(table, 4, first_chunk, stats.chunks);
    if (Status s = write_file_atomic(dir / "hierarchy.bin", hier); !s) return s.error();
    json sffd = {{"origin", vec_json(origin)}};
    if (!source.texture.rgba8.empty()) {
        const SplatTexture& t = source.texture;
        if (t.width <= 0 || t.height <= 0 ||
            t.rgba8.size() != std::size_t(t.width) * std::size_t(t.height) * 4)
            return make_error(source.name + ": the texture's size does not match its texels");
        std::string png;
        auto append = [](void* ctx, void* data, int size) {
            static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), std::size_t(size));
        };
        if (!stbi_write_png_to_func(append, &png, t.width, t.height, 4, t.rgba8.data(), t.width * 4))
            return make_error(out + ": could not encode the texture as PNG");
        if (Status s = write_file_atomic(dir / "texture.png", png); !s) return s.error();
        sffd["texture"] = "texture.png";
    }
    int depth = 0;
    for (const auto& [key, e] : table) depth = std::max(depth, std::get<0>(key));
    json meta;
    meta["version"] = "2.0";
    meta["name"] = o.name.empty() ? fs::absolute(dir).lexically_normal().filename().string() : o.name;
    meta["description"] = "";
    meta["points"] = count;
    meta["projection"] = "";
    meta["hierarchy"] = {{"firstChunkSize", first_chunk}, {"stepSize", 4}, {"depth", depth}};
    meta["offset"] = vec_json(layout.offset);
    meta["scale"] = vec_json(layout.scale);
    meta["spacing"] = side / double(o.grid_cells);
    meta["boundingBox"] = {{"min", vec_json(root.lo)}, {"max", vec_json(root.hi)}};
    meta["encoding"] = "DEFAULT";
    meta["attributes"] = potree2_detail::attributes_json(layout, bounds);
    meta["sffd"] = std::move(sffd);
    const std::string text = meta.dump(1, '\t');
    if (Status s = write_file_atomic(metadata, text); !s) return s.error();
    report_progress(o.progress, "writing the hierarchy", 1.0);
    stats.points = count;
    stats.nodes = table.size();
    stats.depth = depth;
    stats.hierarchy_bytes = hier.size();
    return stats;
}

}  // namespace sffd::assets
