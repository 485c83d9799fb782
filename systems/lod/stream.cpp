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

#include "systems/lod/stream_sources.h"

namespace sffd::lod {
namespace fs = std::filesystem;
using namespace stream_detail;

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
            // A piece asked for again while its first load was finishing: the copy replaces it.
            if (auto it = held.find(k); it != held.end()) held_bytes -= it->second.bytes;
            held_bytes += r->bytes;
            ++stats.loads;
            held.insert_or_assign(k, std::move(*r));
        }
        return l;
    }

    // Asks the loader for what the cut lacks, within the memory budget; the drawn set from what is held.
    void refresh() {
        const Loader state = take_done();
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
        const std::optional<std::uint32_t> loading = state.busy;
        // The loader holds one decoded unit at a time and drops the old one before decoding the next,
        // so the units count as the largest of them, not their sum.
        std::uint64_t unit_reserve = state.scratch;
        std::uint64_t used = held_bytes + state.in_flight + unit_reserve;
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
            // A piece of another unit than the loader's decoded one brings that whole unit in too.
            std::uint64_t need = source->estimate(k);
            const std::int64_t unit = source->unit_of(k);
            std::uint64_t reserve = unit_reserve;
            if (unit >= 0 && unit != last_unit.load() && !units_counted.count(unit))
                reserve = std::max(reserve, source->unit_bytes(k));
            need += reserve - unit_reserve;
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
            unit_reserve = reserve;
            if (unit >= 0) units_counted.insert(unit);
            ask.push_back(k);
        }
        {
            // What the loader finished or started since take_done is not asked for twice.
            std::lock_guard lock(mutex);
            std::erase_if(ask, [&](std::uint32_t k) {
                return (busy && *busy == k) ||
                       std::any_of(done.begin(), done.end(), [&](const auto& d) { return d.first == k; });
            });
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
            // The cut's pieces and the largest unit the loader decodes them from.
            std::uint64_t need = 0, unit = 0;
            for (const std::uint32_t k : s.wanted.pieces)
                need += s.source->estimate(k), unit = std::max(unit, s.source->unit_bytes(k));
            need += unit;
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
