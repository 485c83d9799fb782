// The two kinds of hierarchy a HierarchyStream (stream.h) draws, behind one interface: what a piece is,
// how the cut is chosen, how a piece loads and how the drawn set is laid out and assembled. Internal to
// stream.cpp (one includer), split out to keep each file readable.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "systems/lod/lattice_bounds.h"
#include "systems/lod/stream.h"

namespace sffd::lod::stream_detail {

struct Piece {
    GaussianCloud gaussians;
    SplatCloud splats;
    std::vector<float> lod_radius;  // Potree: each splat's radius when its node stands for its children
    std::uint64_t bytes = 0;
    std::uint64_t used = 0;  // the last update that wanted or drew it
};
using Held = std::unordered_map<std::uint32_t, Piece>;

struct Wanted {
    std::vector<std::uint32_t> pieces;  // most important first (Potree: parents before children)
    std::uint64_t splats = 0;
    std::size_t cut_nodes = 0;
    bool budget_limited = false;
};

template <class T>
inline std::uint64_t bytes_of(const std::vector<T>& v) {
    return std::uint64_t(v.size()) * sizeof(T);
}
inline std::uint64_t cloud_bytes(const GaussianCloud& g) {
    return bytes_of(g.positions) + bytes_of(g.scales) + bytes_of(g.rotations) + bytes_of(g.opacities) +
           bytes_of(g.sh);
}
inline std::uint64_t cloud_bytes(const SplatCloud& c) {
    return bytes_of(c.positions) + bytes_of(c.normals) + bytes_of(c.axis_u) + bytes_of(c.axis_v) +
           bytes_of(c.colors) + bytes_of(c.uvs) + bytes_of(c.uv_axes);
}

// 10 bits per axis of `p` in `box`, interleaved: pieces near each other in space get near codes.
inline std::uint32_t morton(const glm::dvec3& p, const ffd::Box& box) {
    const glm::dvec3 e = glm::max(box.hi - box.lo, glm::dvec3(1e-30));
    std::uint32_t code = 0;
    std::uint32_t q[3];
    for (int a = 0; a < 3; ++a)
        q[a] = std::uint32_t(std::clamp((p[a] - box.lo[a]) / e[a], 0.0, 1.0) * 1023.0);
    for (int bit = 9; bit >= 0; --bit)
        for (int a = 0; a < 3; ++a) code = code << 1 | ((q[a] >> bit) & 1u);
    return code;
}

// What differs between the two kinds of hierarchy. select() and drawn() run on the caller's thread, load()
// on the loader's: load() reads only what open() made, which nothing changes afterwards.
class Source {
public:
    virtual ~Source() = default;
    virtual bool gaussians() const = 0;
    virtual std::uint64_t full_detail() const = 0;
    virtual ffd::Box bounds() const = 0;
    virtual glm::dvec3 origin() const = 0;
    // The node boxes through `lattices` (empty: at rest).
    virtual void rebound(std::span<const Lattice* const> lattices, bool weighted) = 0;
    virtual Wanted select(const CutView& view, const StreamOptions& o) = 0;
    virtual std::uint64_t estimate(std::uint32_t piece) const = 0;
    virtual std::uint64_t splats(std::uint32_t piece) const = 0;
    virtual std::int64_t unit_of(std::uint32_t) const { return -1; }
    // What decoding the piece's unit holds while it is decoded and kept (0: no units).
    virtual std::uint64_t unit_bytes(std::uint32_t) const { return 0; }
    virtual Result<Piece> load(std::uint32_t piece) = 0;
    virtual std::uint64_t scratch_bytes() const { return 0; }
    virtual std::vector<std::uint32_t> drawn(const Wanted& wanted, const Held& held) const = 0;
    // The piece's rest box centre in the cloud's frame (the drawn set is laid out in space order).
    virtual glm::dvec3 center(std::uint32_t piece) const = 0;
    virtual void assemble(const std::vector<std::uint32_t>& drawn, const Held& held, GaussianCloud& g,
                          SplatCloud& s) const = 0;
};

// ---- streamed SOG: a piece is a cut-tree node that draws one leaf at one level ----

class SogSource final : public Source {
public:
    explicit SogSource(StreamedSog sog) : m_sog(std::move(sog)) {
        m_rest = cut_tree(m_sog);
        m_tree = m_rest;
        m_leaf_pieces.resize(m_sog.nodes.size());
        for (std::uint32_t i = 0; i < m_tree.nodes.size(); ++i) {
            const CutNode& n = m_tree.nodes[i];
            if (n.level >= 0) m_leaf_pieces[n.source].push_back(i);  // coarsest first (cut_tree's chain)
        }
        const LodNode& root = m_sog.nodes.front();
        m_bounds.add(root.lo), m_bounds.add(root.hi);
        m_origin = 0.5 * (root.lo + root.hi);
        m_full = m_sog.counts.empty() ? 0 : m_sog.counts.front();
    }
    bool gaussians() const override { return true; }
    std::uint64_t full_detail() const override { return m_full; }
    ffd::Box bounds() const override { return m_bounds; }
    glm::dvec3 origin() const override { return m_origin; }
    void rebound(std::span<const Lattice* const> lattices, bool weighted) override {
        m_tree = lattices.empty() ? m_rest : deformed_cut_tree(m_rest, lattices, weighted);
    }
    Wanted select(const CutView& view, const StreamOptions& o) override {
        Wanted w;
        const Cut cut = select_cut(m_tree, view, {o.tau_pixels, o.splat_budget, o.cull});
        w.splats = cut.splats, w.cut_nodes = cut.nodes.size(), w.budget_limited = cut.budget_limited;
        std::vector<std::pair<double, std::uint32_t>> order;
        std::vector<std::uint32_t> stack;
        for (const std::uint32_t n : cut.nodes) {
            stack.assign(1, n);
            // A spatial node above the leaves draws every leaf below it at its coarsest level.
            while (!stack.empty()) {
                const std::uint32_t k = stack.back();
                stack.pop_back();
                const CutNode& node = m_tree.nodes[k];
                if (node.level >= 0) {
                    order.emplace_back(projected_size(node, view, o.cull), k);
                    continue;
                }
                for (const std::uint32_t c : node.children) stack.push_back(c);
            }
        }
        std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
            return a.first != b.first ? a.first > b.first : a.second < b.second;
        });
        for (const auto& [size, k] : order) w.pieces.push_back(k);
        return w;
    }
    // From the rest tree, which the loader may read while the caller bounds m_tree again.
    const LodRun& run(std::uint32_t piece) const {
        const CutNode& n = m_rest.nodes[piece];
        return *m_sog.nodes[n.source].lods[std::size_t(n.level)];
    }
    std::uint64_t estimate(std::uint32_t piece) const override {
        return run(piece).count * m_bytes_per_gaussian.load();
    }
    std::uint64_t splats(std::uint32_t piece) const override { return run(piece).count; }
    std::int64_t unit_of(std::uint32_t piece) const override { return run(piece).file; }
    std::uint64_t unit_bytes(std::uint32_t piece) const override {
        return m_sog.units[run(piece).file].count * m_bytes_per_gaussian.load();
    }
    Result<Piece> load(std::uint32_t piece) override {
        const LodRun& r = run(piece);
        if (!m_unit || m_unit_file != r.file) {
            m_unit.reset();
            m_scratch = 0;
            auto u = read_unit(m_sog, r.file);
            if (!u) return u.error();
            m_unit = std::move(*u);
            m_unit_file = r.file;
            m_scratch = cloud_bytes(*m_unit);
            if (m_unit->size() > 0)
                m_bytes_per_gaussian = std::max<std::uint64_t>(1, m_scratch / m_unit->size());
        }
        Piece p;
        p.gaussians = slice(*m_unit, r);
        const glm::dvec3 shift = p.gaussians.origin - m_origin;
        for (glm::vec3& x : p.gaussians.positions) x = glm::vec3(glm::dvec3(x) + shift);
        p.gaussians.origin = m_origin;
        if (Status s = gaussian::validate(p.gaussians, m_sog.units[r.file].path.string(), r.offset); !s)
            return s.error();
        p.bytes = cloud_bytes(p.gaussians);
        return p;
    }
    std::uint64_t scratch_bytes() const override { return m_scratch.load(); }
    glm::dvec3 center(std::uint32_t piece) const override {
        const CutNode& n = m_rest.nodes[piece];
        return 0.5 * (n.lo + n.hi);
    }
    std::vector<std::uint32_t> drawn(const Wanted& wanted, const Held& held) const override {
        std::vector<std::uint32_t> out;
        std::unordered_set<std::uint32_t> leaves;
        for (const std::uint32_t k : wanted.pieces) {
            const std::uint32_t leaf = m_tree.nodes[k].source;
            if (!leaves.insert(leaf).second) continue;
            if (held.count(k)) {
                out.push_back(k);
                continue;
            }
            // The nearest loaded level of the same leaf, coarser first: every level covers the region.
            const auto& chain = m_leaf_pieces[leaf];  // coarsest first
            const auto at = std::find(chain.begin(), chain.end(), k) - chain.begin();
            std::optional<std::uint32_t> pick;
            for (auto i = at; i-- > 0 && !pick;)
                if (held.count(chain[std::size_t(i)])) pick = chain[std::size_t(i)];
            for (auto i = at + 1; i < std::ptrdiff_t(chain.size()) && !pick; ++i)
                if (held.count(chain[std::size_t(i)])) pick = chain[std::size_t(i)];
            if (pick) out.push_back(*pick);
        }
        return out;
    }
    void assemble(const std::vector<std::uint32_t>& drawn, const Held& held, GaussianCloud& g,
                  SplatCloud&) const override {
        g = GaussianCloud{};
        g.origin = m_origin;
        std::size_t n = 0;
        for (const std::uint32_t k : drawn) n += held.at(k).gaussians.size();
        bool first = true;
        for (const std::uint32_t k : drawn) {
            const GaussianCloud& p = held.at(k).gaussians;
            if (first) {
                g.sh_degree = p.sh_degree;
                g.positions.reserve(n), g.scales.reserve(n), g.rotations.reserve(n), g.opacities.reserve(n);
                g.sh.reserve(n * std::size_t(sh_coeffs(p.sh_degree)) * 3);
                first = false;
            }
            if (p.sh_degree != g.sh_degree) continue;  // refused by the reader's unit checks; never mixed
            g.positions.insert(g.positions.end(), p.positions.begin(), p.positions.end());
            g.scales.insert(g.scales.end(), p.scales.begin(), p.scales.end());
            g.rotations.insert(g.rotations.end(), p.rotations.begin(), p.rotations.end());
            g.opacities.insert(g.opacities.end(), p.opacities.begin(), p.opacities.end());
            g.sh.insert(g.sh.end(), p.sh.begin(), p.sh.end());
        }
    }

private:
    StreamedSog m_sog;
    CutTree m_rest, m_tree;
    std::vector<std::vector<std::uint32_t>> m_leaf_pieces;  // per spatial leaf: its pieces, coarsest first
    ffd::Box m_bounds;
    glm::dvec3 m_origin{0.0};
    std::uint64_t m_full = 0;
    // Before the first unit is decoded: SH degree 0 (positions, scales, rotation, opacity, DC colour).
    std::atomic<std::uint64_t> m_bytes_per_gaussian{12 + 12 + 16 + 4 + 12};
    // The loader's last decoded unit: WebP decodes whole, and consecutive pieces often share a unit.
    std::optional<GaussianCloud> m_unit;
    std::uint32_t m_unit_file = 0;
    std::atomic<std::uint64_t> m_scratch{0};
};

// ---- Potree 2: a piece is an octree node, drawn with all of its ancestors ----

class PotreeSource final : public Source {
public:
    PotreeSource(assets::PotreeOctree octree, SplatCloud empty)
        : m_octree(std::move(octree)), m_empty(std::move(empty)) {
        m_bounds.add(m_octree.lo), m_bounds.add(m_octree.hi);
        m_rest_box.resize(m_octree.nodes.size());
        for (std::size_t i = 0; i < m_octree.nodes.size(); ++i) {
            // A splat reaches past its node's cube by its radius: the cube grown by the spacing of the
            // level above, the largest radius a representative there is given.
            const assets::PotreeNode& n = m_octree.nodes[i];
            const double pad = m_octree.spacing / std::ldexp(1.0, n.level) * 2.0;
            m_rest_box[i].add(n.lo - pad), m_rest_box[i].add(n.hi + pad);
        }
        m_box = m_rest_box;
        m_stamp.assign(m_octree.nodes.size(), 0);
        const bool uv = m_octree.attribute("sffd_uv") != nullptr;
        m_point_bytes = 4 * 12 + 4 + 4 + (uv ? 8 + 16 : 0);
    }
    bool gaussians() const override { return false; }
    std::uint64_t full_detail() const override { return m_octree.points; }
    ffd::Box bounds() const override { return m_bounds; }
    glm::dvec3 origin() const override { return m_empty.origin; }
    void rebound(std::span<const Lattice* const> lattices, bool weighted) override {
        // Copies: boxes are bounded lazily, in later updates too (the caller's lattices live one update).
        m_lattice_copies.clear();
        for (const Lattice* l : lattices) m_lattice_copies.push_back(*l);
        m_lattices.clear();
        for (const Lattice& l : m_lattice_copies) m_lattices.push_back(&l);
        m_weighted = weighted;
        ++m_generation;  // boxes are bounded again when next visited
    }
    const ffd::Box& box(std::uint32_t i) {
        if (m_lattices.empty()) return m_rest_box[i];
        if (m_stamp[i] != m_generation) {
            m_box[i] = lattice_node_bounds(m_lattices, m_rest_box[i], m_weighted);
            m_stamp[i] = m_generation;
        }
        return m_box[i];
    }
    double projected(std::uint32_t i, const CutView& view, bool cull) {
        const ffd::Box& b = box(i);
        CutNode n;
        n.lo = b.lo, n.hi = b.hi;
        n.size = m_octree.spacing / std::ldexp(1.0, m_octree.nodes[i].level);
        // Grown as much as the box's diagonal grew (deformed_cut_tree's rule).
        const double rest = glm::length(m_rest_box[i].hi - m_rest_box[i].lo);
        if (rest > 0.0) n.size *= std::max(1.0, glm::length(b.hi - b.lo) / rest);
        return projected_size(n, view, cull);
    }
    Wanted select(const CutView& view, const StreamOptions& o) override {
        // Potree's own traversal: the root, then the largest projected node next while it fits.
        Wanted w;
        if (m_octree.nodes.empty()) return w;
        using Entry = std::pair<double, std::uint32_t>;
        std::priority_queue<Entry> open;
        open.push({std::numeric_limits<double>::infinity(), 0});
        while (!open.empty()) {
            const auto [size, i] = open.top();
            open.pop();
            if (!(size > o.tau_pixels)) break;
            const std::uint64_t pts = m_octree.nodes[i].points;
            if (i != 0 && w.splats + pts > o.splat_budget) {
                w.budget_limited = true;
                continue;
            }
            w.pieces.push_back(i);
            w.splats += pts;
            for (const std::int32_t c : m_octree.nodes[i].children)
                if (c >= 0) open.push({projected(std::uint32_t(c), view, o.cull), std::uint32_t(c)});
        }
        w.cut_nodes = w.pieces.size();
        return w;
    }
    std::uint64_t estimate(std::uint32_t piece) const override {
        return std::uint64_t(m_octree.nodes[piece].points) * m_point_bytes;
    }
    std::uint64_t splats(std::uint32_t piece) const override { return m_octree.nodes[piece].points; }
    glm::dvec3 center(std::uint32_t piece) const override {
        return 0.5 * (m_octree.nodes[piece].lo + m_octree.nodes[piece].hi);
    }
    Result<Piece> load(std::uint32_t piece) override {
        auto r = assets::read_potree2_node_points(m_octree, piece);
        if (!r) return r.error();
        Piece p;
        p.splats = std::move(r->cloud);
        p.lod_radius = std::move(r->lod_radius);
        p.bytes = cloud_bytes(p.splats) + bytes_of(p.lod_radius);
        return p;
    }
    std::vector<std::uint32_t> drawn(const Wanted& wanted, const Held& held) const override {
        std::vector<std::uint32_t> out;
        std::unordered_set<std::uint32_t> in;
        for (const std::uint32_t i : wanted.pieces) {  // parents come first
            const std::int32_t parent = m_octree.nodes[i].parent;
            if (!held.count(i) || (parent >= 0 && !in.count(std::uint32_t(parent)))) continue;
            in.insert(i);
            out.push_back(i);
        }
        return out;
    }
    void assemble(const std::vector<std::uint32_t>& drawn, const Held& held, GaussianCloud&,
                  SplatCloud& s) const override {
        s = SplatCloud{};
        s.origin = m_empty.origin;
        s.texture = m_empty.texture;
        std::unordered_set<std::uint32_t> in(drawn.begin(), drawn.end());
        std::size_t n = 0;
        for (const std::uint32_t k : drawn) n += held.at(k).splats.size();
        const bool uv = !drawn.empty() && !held.at(drawn.front()).splats.uvs.empty();
        s.positions.reserve(n), s.normals.reserve(n), s.axis_u.reserve(n), s.axis_v.reserve(n);
        s.colors.reserve(n);
        if (uv) s.uvs.reserve(n), s.uv_axes.reserve(n);
        const auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
        for (const std::uint32_t k : drawn) {
            const Piece& p = held.at(k);
            const std::size_t first = s.size();
            append(s.positions, p.splats.positions), append(s.normals, p.splats.normals);
            append(s.axis_u, p.splats.axis_u), append(s.axis_v, p.splats.axis_v);
            append(s.colors, p.splats.colors);
            if (uv) append(s.uvs, p.splats.uvs), append(s.uv_axes, p.splats.uv_axes);
            bool all = true;
            for (const std::int32_t c : m_octree.nodes[k].children)
                if (c >= 0 && !in.count(std::uint32_t(c))) all = false;
            if (!all) assets::grow_to_lod_radius(s, first, p.lod_radius);
        }
    }

private:
    assets::PotreeOctree m_octree;
    SplatCloud m_empty;  // the origin and the texture
    ffd::Box m_bounds;
    std::vector<ffd::Box> m_rest_box, m_box;
    std::vector<std::uint64_t> m_stamp;
    std::uint64_t m_generation = 1;
    std::deque<Lattice> m_lattice_copies;
    std::vector<const Lattice*> m_lattices;  // into m_lattice_copies
    bool m_weighted = false;
    std::uint64_t m_point_bytes = 0;
};

}  // namespace sffd::lod::stream_detail
