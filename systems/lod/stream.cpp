#include "systems/lod/stream.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <queue>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "systems/lod/lattice_bounds.h"

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {

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
std::uint64_t bytes_of(const std::vector<T>& v) {
    return std::uint64_t(v.size()) * sizeof(T);
}
std::uint64_t cloud_bytes(const GaussianCloud& g) {
    return bytes_of(g.positions) + bytes_of(g.scales) + bytes_of(g.rotations) + bytes_of(g.opacities) +
           bytes_of(g.sh);
}
std::uint64_t cloud_bytes(const SplatCloud& c) {
    return bytes_of(c.positions) + bytes_of(c.normals) + bytes_of(c.axis_u) + bytes_of(c.axis_v) +
           bytes_of(c.colors) + bytes_of(c.uvs) + bytes_of(c.uv_axes);
}

// 10 bits per axis of `p` in `box`, interleaved: pieces near each other in space get near codes.
std::uint32_t morton(const glm::dvec3& p, const ffd::Box& box) {
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

}  // namespace

bool is_streamable(const fs::path& path) {
    if (path.filename() == "lod-meta.json") return true;
    if (path.filename() != "metadata.json") return false;
    auto o = assets::open_potree2(path);
    return o && o->attribute("sffd_axis_u") && o->attribute("sffd_axis_v") && o->attribute("normal");
}

struct HierarchyStream::Impl {
    fs::path path;
    StreamOptions options;
    std::unique_ptr<Source> source;

    Held held;
    std::uint64_t held_bytes = 0;
    std::uint64_t frame = 0;
    Wanted wanted;
    std::vector<std::uint32_t> drawn, assembled;
    bool have_assembled = false;
    std::uint64_t lattice_stamp = 0;
    bool bounded = false;     // rebound ran at least once
    double rebound_at = 0.0;  // steady-clock seconds of the last rebound
    StreamStats stats;
    std::unordered_set<std::uint32_t> failed;
    std::optional<std::string> first_error;

    std::mutex mutex;
    std::condition_variable wake, finished;
    std::deque<std::uint32_t> queue;
    std::vector<std::pair<std::uint32_t, Result<Piece>>> done;
    std::optional<std::uint32_t> busy;
    std::uint64_t busy_estimate = 0;
    bool stop = false;
    std::thread loader;

    void loader_loop() {
        for (;;) {
            std::uint32_t piece = 0;
            {
                std::unique_lock lock(mutex);
                wake.wait(lock, [&] { return stop || !queue.empty(); });
                if (stop) return;
                // A queued piece of the unit the loader holds decoded goes first: decoding is the cost.
                auto it = queue.begin();
                if (const std::int64_t u = last_unit; u >= 0)
                    if (auto same = std::find_if(queue.begin(), queue.end(),
                                                 [&](std::uint32_t q) { return source->unit_of(q) == u; });
                        same != queue.end())
                        it = same;
                piece = *it;
                queue.erase(it);
                busy = piece;
                busy_estimate = source->estimate(piece);
                const std::int64_t u = source->unit_of(piece);
                if (u >= 0 && u != last_unit.load()) busy_estimate += source->unit_bytes(piece);
            }
            Result<Piece> r = source->load(piece);
            last_unit = source->unit_of(piece);
            {
                std::lock_guard lock(mutex);
                busy.reset();
                busy_estimate = 0;
                done.emplace_back(piece, std::move(r));
            }
            finished.notify_all();
        }
    }
    std::atomic<std::int64_t> last_unit{-1};

    struct Loader {
        std::uint64_t scratch = 0, in_flight = 0;
        std::optional<std::uint32_t> busy;
    };
    // Takes the finished loads and, in the same moment, what the loader holds besides them: a load that
    // finishes later is still counted as in flight here.
    Loader take_done() {
        std::vector<std::pair<std::uint32_t, Result<Piece>>> got;
        Loader l;
        {
            std::lock_guard lock(mutex);
            got.swap(done);
            l.scratch = source->scratch_bytes(), l.in_flight = busy_estimate, l.busy = busy;
        }
        for (auto& [k, r] : got) {
            if (!r) {
                failed.insert(k);
                if (!first_error) first_error = r.error().message;
                continue;
            }
            r->used = frame;
            held_bytes += r->bytes;
            ++stats.loads;
            held.insert_or_assign(k, std::move(*r));
        }
        return l;
    }

    // Asks the loader for what the cut lacks, within the memory budget; the drawn set from what is held.
    void refresh() {
        const Loader loader = take_done();
        std::unordered_set<std::uint32_t> wanted_set(wanted.pieces.begin(), wanted.pieces.end());
        for (const std::uint32_t k : wanted.pieces)
            if (auto it = held.find(k); it != held.end()) it->second.used = frame;
        drawn = source->drawn(wanted, held);
        // In space order: the cloud's pages (runtime/scene/point_pages.h) then hold nearby pieces, so a
        // control-point edit re-deforms only the pages it reaches and the renderer culls whole pages.
        {
            const ffd::Box box = source->bounds();
            std::vector<std::pair<std::uint32_t, std::uint32_t>> order;
            order.reserve(drawn.size());
            for (const std::uint32_t k : drawn) order.emplace_back(morton(source->center(k), box), k);
            std::sort(order.begin(), order.end());
            for (std::size_t i = 0; i < order.size(); ++i) drawn[i] = order[i].second;
        }
        std::unordered_set<std::uint32_t> keep(drawn.begin(), drawn.end());
        for (const std::uint32_t k : drawn) held.at(k).used = frame;
        // What was drawn last is a copy in the cloud component: its pieces are not needed to show it.
        keep.insert(wanted_set.begin(), wanted_set.end());

        std::vector<std::uint32_t> ask;
        const std::optional<std::uint32_t> loading = loader.busy;
        std::uint64_t used = held_bytes + loader.scratch + loader.in_flight;
        std::vector<std::pair<std::uint64_t, std::uint32_t>> evictable;  // (last use, piece), oldest last
        bool sorted = false;
        std::unordered_set<std::int64_t> units_counted;
        stats.memory_limited = false;
        std::size_t missing = 0;
        for (const std::uint32_t k : wanted.pieces) {
            if (held.count(k) || failed.count(k)) continue;
            ++missing;
            if (loading && *loading == k) continue;
            if (stats.memory_limited) continue;
            // A piece of another unit than the loader's decoded one brings that whole unit in too (the
            // old one is dropped first, but it is counted in `used` until then).
            std::uint64_t need = source->estimate(k);
            const std::int64_t unit = source->unit_of(k);
            if (unit >= 0 && unit != last_unit.load() && !units_counted.count(unit))
                need += source->unit_bytes(k);
            while (used + need > options.memory_budget) {
                if (!sorted) {
                    // Least recently used first; then, as a last resort, the coarser levels drawn in
                    // place of wanted pieces (a brief hole where one was, until its wanted piece
                    // arrives: otherwise they could hold the memory the wanted pieces need forever).
                    for (const auto& [id, p] : held)
                        if (!keep.count(id)) evictable.emplace_back(p.used, id);
                        else if (!wanted_set.count(id)) evictable.emplace_back(p.used + frame + 1, id);
                    std::sort(evictable.begin(), evictable.end(), std::greater<>());
                    sorted = true;
                }
                if (evictable.empty()) break;
                const std::uint32_t victim = evictable.back().second;
                evictable.pop_back();
                auto it = held.find(victim);
                used -= it->second.bytes, held_bytes -= it->second.bytes;
                held.erase(it);
                ++stats.evictions;
            }
            if (used + need > options.memory_budget) {
                stats.memory_limited = true;
                continue;
            }
            used += need;
            if (unit >= 0) units_counted.insert(unit);
            ask.push_back(k);
        }
        {
            std::lock_guard lock(mutex);
            queue.assign(ask.begin(), ask.end());
        }
        if (!ask.empty()) wake.notify_one();

        stats.resident_bytes = used;
        stats.peak_resident_bytes = std::max(stats.peak_resident_bytes, used);
        stats.resident_pieces = held.size();
        stats.queued = ask.size();
        stats.cut_nodes = wanted.cut_nodes;
        stats.wanted_pieces = wanted.pieces.size();
        stats.missing_pieces = missing;
        stats.wanted_splats = wanted.splats;
        stats.budget_limited = wanted.budget_limited;
        stats.drawn_splats = 0;
        for (const std::uint32_t k : drawn) stats.drawn_splats += source->splats(k);
    }
};

HierarchyStream::HierarchyStream(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {
    m_impl->loader = std::thread([impl = m_impl.get()] { impl->loader_loop(); });
}

HierarchyStream::~HierarchyStream() {
    {
        std::lock_guard lock(m_impl->mutex);
        m_impl->stop = true;
    }
    m_impl->wake.notify_all();
    if (m_impl->loader.joinable()) m_impl->loader.join();
}

Result<std::unique_ptr<HierarchyStream>> HierarchyStream::open(const fs::path& path, const StreamOptions& o) {
    auto impl = std::make_unique<Impl>();
    impl->path = path, impl->options = o;
    if (path.filename() == "lod-meta.json") {
        auto s = open_streamed_sog(path);
        if (!s) return s.error();
        if (s->nodes.empty()) return make_error(path.string() + ": the hierarchy has no nodes");
        impl->source = std::make_unique<SogSource>(std::move(*s));
    } else if (path.filename() == "metadata.json") {
        auto oc = assets::open_potree2(path);
        if (!oc) return oc.error();
        if (!oc->attribute("sffd_axis_u") || !oc->attribute("sffd_axis_v") || !oc->attribute("normal"))
            return make_error(path.string() +
                              ": a Potree 2 octree without \"normal\", \"sffd_axis_u\" and \"sffd_axis_v\" "
                              "(not written by splatffd) cannot be streamed: open it whole");
        if (oc->nodes.empty()) return make_error(path.string() + ": the octree has no nodes");
        // The origin and the texture: the reader decodes the texture only for points with uvs, so the
        // root is read once here and its points dropped.
        auto empty = assets::read_potree2_nodes(*oc, {0});
        if (!empty) return empty.error();
        SplatTexture texture = std::move(empty->texture);
        const glm::dvec3 origin = empty->origin;
        *empty = SplatCloud{};
        empty->origin = origin, empty->texture = std::move(texture);
        impl->source = std::make_unique<PotreeSource>(std::move(*oc), std::move(*empty));
    } else {
        return make_error(path.string() +
                          ": not a level-of-detail hierarchy (expected a streamed SOG's lod-meta.json or a "
                          "Potree 2 metadata.json)");
    }
    return std::unique_ptr<HierarchyStream>(new HierarchyStream(std::move(impl)));
}

bool HierarchyStream::gaussians() const { return m_impl->source->gaussians(); }
const fs::path& HierarchyStream::path() const { return m_impl->path; }
std::uint64_t HierarchyStream::full_detail() const { return m_impl->source->full_detail(); }
ffd::Box HierarchyStream::bounds() const { return m_impl->source->bounds(); }
glm::dvec3 HierarchyStream::origin() const { return m_impl->source->origin(); }
const StreamOptions& HierarchyStream::options() const { return m_impl->options; }
void HierarchyStream::set_options(const StreamOptions& o) { m_impl->options = o; }

bool HierarchyStream::update(const CutView& view, std::span<const Lattice* const> lattices,
                             std::uint64_t lattice_stamp, bool weighted) {
    Impl& s = *m_impl;
    ++s.frame;
    const auto t0 = std::chrono::steady_clock::now();
    const double now = std::chrono::duration<double>(t0.time_since_epoch()).count();
    if (!s.bounded || (lattice_stamp != s.lattice_stamp &&
                       (now - s.rebound_at >= s.options.rebound_interval_s || lattices.empty()))) {
        s.source->rebound(lattices, weighted);
        s.lattice_stamp = lattice_stamp, s.bounded = true, s.rebound_at = now;
    }
    s.wanted = s.source->select(view, s.options);
    s.stats.select_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    s.refresh();
    return !s.have_assembled || s.drawn != s.assembled;
}

void HierarchyStream::assemble(GaussianCloud& out) {
    SplatCloud unused;
    m_impl->source->assemble(m_impl->drawn, m_impl->held, out, unused);
    if (!gaussians()) out = GaussianCloud{};
    m_impl->assembled = m_impl->drawn, m_impl->have_assembled = true;
}

void HierarchyStream::assemble(SplatCloud& out) {
    GaussianCloud unused;
    m_impl->source->assemble(m_impl->drawn, m_impl->held, unused, out);
    if (gaussians()) out = SplatCloud{};
    m_impl->assembled = m_impl->drawn, m_impl->have_assembled = true;
}

bool HierarchyStream::complete() const {
    return m_impl->stats.missing_pieces == 0 && m_impl->have_assembled && m_impl->drawn == m_impl->assembled;
}

Status HierarchyStream::wait_complete() {
    Impl& s = *m_impl;
    for (;;) {
        s.refresh();
        for (const std::uint32_t k : s.wanted.pieces)
            if (s.failed.count(k)) return make_error(*s.first_error);
        if (s.stats.missing_pieces == 0) return {};
        bool loading = false;
        {
            std::lock_guard lock(s.mutex);
            loading = s.busy.has_value() || !s.done.empty() || !s.queue.empty();
        }
        // A piece of an earlier cut still being decoded holds memory it will give back: wait for it.
        if (s.stats.memory_limited && !loading) {
            std::uint64_t need = 0;
            for (const std::uint32_t k : s.wanted.pieces) need += s.source->estimate(k);
            char line[160];
            std::snprintf(line, sizeof line, "needs about %.1f MB, more than the memory budget of %.1f MB",
                          double(need) / 1048576.0, double(s.options.memory_budget) / 1048576.0);
            return make_error(s.path.string() + ": the cut of " + std::to_string(s.wanted.splats) +
                              " splats " + line + " (raise the memory budget or lower the splat budget)");
        }
        std::unique_lock lock(s.mutex);
        s.finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return !s.done.empty(); });
    }
}

StreamStats HierarchyStream::stats() const { return m_impl->stats; }

Status HierarchyStream::error() const {
    if (m_impl->first_error) return make_error(*m_impl->first_error);
    return {};
}

}  // namespace sffd::lod
