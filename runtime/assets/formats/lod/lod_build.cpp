#include "runtime/assets/formats/lod/lod_build.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <numeric>
#include <set>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/lod/cell_buckets.h"
#include "runtime/assets/formats/lod/lod_merge.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/core/atomic_file.h"

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {

using json = nlohmann::ordered_json;

// One Gaussian on disk: x y z (double, absolute), scale 3, rotation w x y z, opacity, SH (floats).
struct RecordLayout {
    std::size_t k3 = 3, bytes = 0;
    explicit RecordLayout(int degree)
        : k3(std::size_t(sh_coeffs(degree)) * 3), bytes(24 + 4 * (3 + 4 + 1 + k3)) {}
};

void to_record(const GaussianCloud& g, std::size_t i, const RecordLayout& L, std::byte* out) {
    const double p[3] = {g.origin.x + double(g.positions[i].x), g.origin.y + double(g.positions[i].y),
                         g.origin.z + double(g.positions[i].z)};
    std::memcpy(out, p, 24);
    float f[8] = {g.scales[i].x,    g.scales[i].y,    g.scales[i].z,    g.rotations[i].w,
                  g.rotations[i].x, g.rotations[i].y, g.rotations[i].z, g.opacities[i]};
    std::memcpy(out + 24, f, 32);
    std::memcpy(out + 56, g.sh.data() + i * L.k3, 4 * L.k3);
}

void from_record(const std::byte* r, const RecordLayout& L, GaussianCloud& g) {
    double p[3];
    float f[8];
    std::memcpy(p, r, 24);
    std::memcpy(f, r + 24, 32);
    g.positions.push_back(glm::vec3(glm::dvec3(p[0], p[1], p[2]) - g.origin));
    g.scales.push_back({f[0], f[1], f[2]});
    g.rotations.push_back(glm::quat(f[3], f[4], f[5], f[6]));
    g.opacities.push_back(f[7]);
    const std::size_t at = g.sh.size();
    g.sh.resize(at + L.k3);
    std::memcpy(g.sh.data() + at, r + 56, 4 * L.k3);
}

std::uint64_t cloud_bytes_per(const RecordLayout& L) { return 12 + 12 + 16 + 4 + 4 * L.k3; }

// 7 significant digits, as splat-transform's replacer writes non-integers (toPrecision(7)).
double p7(double v) {
    if (!std::isfinite(v) || v == std::floor(v)) return v;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.7g", v);
    return std::strtod(buf, nullptr);
}

struct Box {
    glm::dvec3 lo{INFINITY}, hi{-INFINITY};
    void add(const Box& b) { lo = glm::min(lo, b.lo), hi = glm::max(hi, b.hi); }
};

json bound_json(const Box& b) {
    return {{"min", {p7(b.lo.x), p7(b.lo.y), p7(b.lo.z)}}, {"max", {p7(b.hi.x), p7(b.hi.y), p7(b.hi.z)}}};
}

// The box of Gaussians' 1σ ellipsoids, as splat-transform's calcBound (|R|·s half extents).
void ellipsoid_box(const GaussianCloud& g, Box& b) {
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dmat3 r = glm::mat3_cast(glm::dquat(g.rotations[i]));
        const glm::dvec3 s(g.scales[i]);
        const glm::dvec3 c = g.origin + glm::dvec3(g.positions[i]);
        glm::dvec3 e(0.0);
        for (int k = 0; k < 3; ++k) e += glm::abs(r[k]) * s[k];
        b.lo = glm::min(b.lo, c - e), b.hi = glm::max(b.hi, c + e);
    }
}

// Splits `idx` at its median along the longest side of its centres' box until each part satisfies
// `small(part, box)`; calls `part` for each, in order.
template <class Small, class Part>
void median_split(const GaussianCloud& g, std::uint32_t* first, std::uint32_t* last, const Small& small,
                  const Part& part) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (auto* p = first; p != last; ++p)
        lo = glm::min(lo, g.positions[*p]), hi = glm::max(hi, g.positions[*p]);
    const glm::vec3 ext = hi - lo;
    if (small(std::size_t(last - first), std::max({ext.x, ext.y, ext.z}))) return part(first, last);
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    std::uint32_t* mid = first + (last - first) / 2;
    std::nth_element(first, mid, last, [&](std::uint32_t a, std::uint32_t b) {
        return g.positions[a][axis] < g.positions[b][axis];
    });
    median_split(g, first, mid, small, part);
    median_split(g, mid, last, small, part);
}

GaussianCloud subset(const GaussianCloud& g, const std::vector<std::uint32_t>& idx, std::size_t k3) {
    GaussianCloud out;
    out.origin = g.origin, out.sh_degree = g.sh_degree;
    out.positions.reserve(idx.size()), out.scales.reserve(idx.size()), out.rotations.reserve(idx.size());
    out.opacities.reserve(idx.size()), out.sh.reserve(idx.size() * k3);
    for (const std::uint32_t i : idx) {
        out.positions.push_back(g.positions[i]), out.scales.push_back(g.scales[i]);
        out.rotations.push_back(g.rotations[i]), out.opacities.push_back(g.opacities[i]);
        out.sh.insert(out.sh.end(), g.sh.begin() + long(i * k3), g.sh.begin() + long((i + 1) * k3));
    }
    return out;
}

void append(GaussianCloud& to, const GaussianCloud& from) {
    to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
    to.scales.insert(to.scales.end(), from.scales.begin(), from.scales.end());
    to.rotations.insert(to.rotations.end(), from.rotations.begin(), from.rotations.end());
    to.opacities.insert(to.opacities.end(), from.opacities.begin(), from.opacities.end());
    to.sh.insert(to.sh.end(), from.sh.begin(), from.sh.end());
}

class Builder {
public:
    Builder(const fs::path& lod_meta, const LodBuildOptions& o, int degree, glm::dvec3 origin)
        : meta_(lod_meta), dir_(lod_meta.parent_path()), o_(o), L_(degree), degree_(degree), origin_(origin) {
        units_.resize(std::size_t(o.levels));
        for (auto& u : units_) u.cloud.origin = origin, u.cloud.sh_degree = degree;
        counts_.assign(std::size_t(o.levels), 0);
    }

    MemoryLedger ledger;
    std::uint64_t chunk_count = 0;
    LodBuildStats stats;

    const RecordLayout& layout() const { return L_; }

    // One cell: its chunks, their levels, their runs; the cell's subtree kept for the tree above.
    Status cell(std::vector<std::byte>& records, std::size_t n, const Cell& c) {
        GaussianCloud g;
        g.origin = origin_, g.sh_degree = degree_;
        const std::uint64_t cloud_bytes = n * cloud_bytes_per(L_);
        LedgerHold hold(ledger, cloud_bytes + n * 4);
        g.positions.reserve(n), g.scales.reserve(n), g.rotations.reserve(n), g.opacities.reserve(n);
        g.sh.reserve(n * L_.k3);
        for (std::size_t i = 0; i < n; ++i) from_record(records.data() + i * L_.bytes, L_, g);
        std::vector<std::byte>().swap(records);  // the records are in the cloud now
        ledger.sub(n * L_.bytes);
        stats.cell_cap = std::max<std::uint64_t>(stats.cell_cap, n);
        ++stats.cells;
        std::vector<std::uint32_t> idx(n);
        std::iota(idx.begin(), idx.end(), 0u);
        Status status;
        json node = split(g, idx.data(), idx.data() + n, status);
        ledger.add(n * L_.bytes);  // bucket_cells releases what it handed over
        if (!status) return status;
        cells_[{c.level, c.coords.x, c.coords.y, c.coords.z}] = std::move(node);
        for (int l = 1; l <= c.level; ++l)
            ancestors_.insert({c.level - l, c.coords.x >> l, c.coords.y >> l, c.coords.z >> l});
        return {};
    }

    Status finish(const LodBuildOptions& o) {
        for (std::size_t l = 0; l < units_.size(); ++l)
            if (Status s = close_unit(int(l)); !s) return s;
        Box root;
        json tree = assemble(0, 0, 0, 0, root);
        json meta;
        meta["version"] = 1;
        meta["asset"] = {{"generator", "splatffd"}};
        meta["count"] = std::accumulate(counts_.begin(), counts_.end(), std::uint64_t(0));
        meta["counts"] = counts_;
        meta["lodLevels"] = o.levels;
        meta["filenames"] = filenames_;
        meta["tree"] = std::move(tree);
        const std::string text = meta.dump();
        stats.counts = counts_;
        stats.units = filenames_.size();
        stats.peak_bytes = ledger.peak();
        stats.chunk_count = chunk_count;
        return write_file_atomic(meta_, [&](std::FILE* f) -> Status {
            if (std::fwrite(text.data(), 1, text.size(), f) != text.size())
                return make_error(meta_.string() + ": write failed");
            return {};
        });
    }

private:
    struct Unit {
        int index = 0;           // i of "l_i"
        std::int64_t file = -1;  // its place in filenames, once used
        GaussianCloud cloud;
    };

    json split(const GaussianCloud& g, std::uint32_t* first, std::uint32_t* last, Status& status) {
        const std::size_t n = std::size_t(last - first);
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (auto* p = first; p != last; ++p)
            lo = glm::min(lo, g.positions[*p]), hi = glm::max(hi, g.positions[*p]);
        const glm::vec3 ext = hi - lo;
        const float largest = std::max({ext.x, ext.y, ext.z});
        // splat-transform 3.7's rule: split a node of more than 256 while it holds more than the chunk
        // count, or is wider than the extent and holds more than the chunk minimum.
        if (n <= 256 || (n <= chunk_count && !(double(largest) > o_.chunk_extent && n > o_.chunk_min)))
            return chunk(g, first, last, status);
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        std::uint32_t* mid = first + n / 2;
        std::nth_element(first, mid, last, [&](std::uint32_t a, std::uint32_t b) {
            return g.positions[a][axis] < g.positions[b][axis];
        });
        json a = split(g, first, mid, status);
        if (!status) return {};
        json b = split(g, mid, last, status);
        if (!status) return {};
        return pair(std::move(a), std::move(b));
    }

    static Box box_of(const json& node) {
        Box b;
        for (int a = 0; a < 3; ++a) b.lo[a] = node["bound"]["min"][a], b.hi[a] = node["bound"]["max"][a];
        return b;
    }
    static json pair(json a, json b) {
        Box box = box_of(a);
        box.add(box_of(b));
        json n;
        n["bound"] = bound_json(box);
        n["children"] = json::array({std::move(a), std::move(b)});
        return n;
    }

    json chunk(const GaussianCloud& g, std::uint32_t* first, std::uint32_t* last, Status& status) {
        ++stats.chunks;
        std::vector<GaussianCloud> levels;
        levels.push_back(subset(g, std::vector<std::uint32_t>(first, last), L_.k3));
        std::uint64_t held = levels[0].size() * cloud_bytes_per(L_);
        for (int l = 1; l < o_.levels; ++l) {
            const GaussianCloud& below = levels.back();
            GaussianCloud up;
            up.origin = below.origin, up.sh_degree = below.sh_degree;
            std::vector<std::uint32_t> idx(below.size());
            std::iota(idx.begin(), idx.end(), 0u);
            median_split(
                below, idx.data(), idx.data() + idx.size(),
                [&](std::size_t m, float) { return m <= std::size_t(o_.ratio); },
                [&](std::uint32_t* a, std::uint32_t* b) {
                    merge_gaussians(below, std::span<const std::uint32_t>(a, std::size_t(b - a)), up);
                });
            held += up.size() * cloud_bytes_per(L_);
            ledger.add(up.size() * cloud_bytes_per(L_));
            levels.push_back(std::move(up));
        }
        ledger.add(levels[0].size() * cloud_bytes_per(L_));
        Box box;
        for (const GaussianCloud& c : levels) ellipsoid_box(c, box);
        json node;
        node["bound"] = bound_json(box);
        json lods = json::object();
        for (int l = 0; l < o_.levels && status; ++l) {
            GaussianCloud& c = levels[std::size_t(l)];
            std::vector<glm::vec3> abs(c.size());
            for (std::size_t i = 0; i < c.size(); ++i)
                abs[i] = glm::vec3(c.origin + glm::dvec3(c.positions[i]));
            std::vector<std::uint32_t> order(c.size());
            std::iota(order.begin(), order.end(), 0u);
            sort_morton(abs, order);
            Unit& u = units_[std::size_t(l)];
            if (u.file < 0) {
                u.file = std::int64_t(filenames_.size());
                filenames_.push_back(std::to_string(l) + "_" + std::to_string(u.index) + "/meta.json");
            }
            const std::uint64_t offset = u.cloud.size();
            append(u.cloud, subset(c, order, L_.k3));
            ledger.add(c.size() * cloud_bytes_per(L_));
            lods[std::to_string(l)] = {{"file", u.file}, {"offset", offset}, {"count", c.size()}};
            counts_[std::size_t(l)] += c.size();
            if (u.cloud.size() > chunk_count) status = close_unit(l);
        }
        ledger.sub(held);
        node["lods"] = std::move(lods);
        return node;
    }

    Status close_unit(int l) {
        Unit& u = units_[std::size_t(l)];
        if (u.file < 0) return {};
        const fs::path path = dir_ / filenames_[std::size_t(u.file)];
        std::error_code ec;
        fs::create_directories(path.parent_path(), ec);
        if (ec)
            return make_error(path.parent_path().string() + ": cannot create the folder: " + ec.message());
        gaussian::SogWriteOptions so;
        if (Status s = gaussian::write_sog(path, u.cloud, so); !s) return s;
        ledger.sub(u.cloud.size() * cloud_bytes_per(L_));
        u.cloud = GaussianCloud{};
        u.cloud.origin = origin_, u.cloud.sh_degree = degree_;
        u.file = -1;
        ++u.index;
        return {};
    }

    // The tree above the cells: octree node (level, x, y, z) as halves along x, then y, then z.
    json assemble(int level, std::uint64_t x, std::uint64_t y, std::uint64_t z, Box& box) {
        const Key key{level, x, y, z};
        if (auto it = cells_.find(key); it != cells_.end()) {
            json n = std::move(it->second);
            box = box_of(n);
            return n;
        }
        if (!ancestors_.count(key)) return nullptr;
        std::vector<json> kids(8);
        for (int c = 0; c < 8; ++c) {
            Box b;
            kids[std::size_t(c)] =
                assemble(level + 1, x * 2 + std::uint64_t((c >> 2) & 1), y * 2 + std::uint64_t((c >> 1) & 1),
                         z * 2 + std::uint64_t(c & 1), b);
        }
        // Pair up z, then y, then x: children c and c + 1 differ in z, c and c + 2 in y, c and c + 4 in x.
        for (int step : {1, 2, 4})
            for (int c = 0; c < 8; c += 2 * step) {
                json& a = kids[std::size_t(c)];
                json& b = kids[std::size_t(c + step)];
                if (a.is_null()) a = std::move(b);
                else if (!b.is_null()) a = pair(std::move(a), std::move(b));
                b = nullptr;
            }
        box = kids[0].is_null() ? Box{} : box_of(kids[0]);
        return std::move(kids[0]);
    }

    using Key = std::tuple<int, std::uint64_t, std::uint64_t, std::uint64_t>;
    fs::path meta_, dir_;
    LodBuildOptions o_;
    RecordLayout L_;
    int degree_;
    glm::dvec3 origin_;
    std::vector<Unit> units_;
    std::vector<std::string> filenames_;
    std::vector<std::uint64_t> counts_;
    std::map<Key, json> cells_;
    std::set<Key> ancestors_;
};

}  // namespace

void sort_morton(const std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices) {
    const auto part = [](std::uint32_t v) {
        v &= 0x3ff;
        v = (v ^ (v << 16)) & 0xff0000ff;
        v = (v ^ (v << 8)) & 0x0300f00f;
        v = (v ^ (v << 4)) & 0x030c30c3;
        v = (v ^ (v << 2)) & 0x09249249;
        return v;
    };
    std::vector<std::uint32_t> morton, order, tmp;
    const std::function<void(std::uint32_t*, std::size_t)> generate = [&](std::uint32_t* idx, std::size_t n) {
        if (n == 0) return;
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (std::size_t i = 0; i < n; ++i)
            lo = glm::min(lo, positions[idx[i]]), hi = glm::max(hi, positions[idx[i]]);
        const glm::vec3 len = hi - lo;
        if (!std::isfinite(len.x) || !std::isfinite(len.y) || !std::isfinite(len.z)) return;
        if (len.x == 0 && len.y == 0 && len.z == 0) return;
        // splat-transform's arithmetic is in doubles on float inputs; so is this.
        const double mul[3] = {len.x == 0 ? 0.0 : 1024.0 / double(len.x),
                               len.y == 0 ? 0.0 : 1024.0 / double(len.y),
                               len.z == 0 ? 0.0 : 1024.0 / double(len.z)};
        std::vector<std::uint32_t> code(n), ord(n);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::vec3& p = positions[idx[i]];
            std::uint32_t q[3];
            for (int a = 0; a < 3; ++a)
                q[a] = std::uint32_t(std::min(1023.0, (double(p[a]) - double(lo[a])) * mul[a]));
            code[i] = (part(q[2]) << 2) + (part(q[1]) << 1) + part(q[0]);
            ord[i] = std::uint32_t(i);
        }
        std::stable_sort(ord.begin(), ord.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b]; });
        std::vector<std::uint32_t> copy(idx, idx + n);
        for (std::size_t i = 0; i < n; ++i) idx[i] = copy[ord[i]];
        std::size_t start = 0, end = 1;
        while (start < n) {
            while (end < n && code[ord[end]] == code[ord[start]]) ++end;
            if (end - start > 256) generate(idx + start, end - start);
            start = end;
        }
    };
    generate(indices.data(), indices.size());
}

Result<LodBuildStats> build_streamed_sog(const GaussianSource& source, const fs::path& lod_meta,
                                         const LodBuildOptions& o) {
    const std::string out = lod_meta.string();
    if (lod_meta.filename() != "lod-meta.json")
        return make_error(out + ": a streamed SOG is written as a folder's lod-meta.json");
    if (o.levels < 1 || o.levels > kMaxLodLevels)
        return make_error(out + ": levels must be 1 to " + std::to_string(kMaxLodLevels));
    if (o.ratio < 2) return make_error(out + ": the ratio must be at least 2");
    if (o.chunk_count < 256) return make_error(out + ": the chunk count must be at least 256");
    // 1. Count, bounds, degree.
    std::uint64_t count = 0;
    int degree = -1;
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    report_progress(o.progress, "reading", 0.0);
    if (Status s = source.scan([&](const GaussianCloud& g) -> Status {
            if (degree >= 0 && g.sh_degree != degree)
                return make_error(source.name + ": the SH degree changes");
            degree = g.sh_degree;
            for (std::size_t i = 0; i < g.size(); ++i) {
                const glm::dvec3 p = g.origin + glm::dvec3(g.positions[i]);
                lo = glm::min(lo, p), hi = glm::max(hi, p);
            }
            count += g.size();
            return {};
        });
        !s)
        return s.error();
    report_progress(o.progress, "reading", 1.0);
    if (count == 0) return make_error(source.name + ": no Gaussians to build a hierarchy of");
    std::error_code ec;
    fs::create_directories(lod_meta.parent_path().empty() ? fs::path(".") : lod_meta.parent_path(), ec);
    if (ec)
        return make_error(lod_meta.parent_path().string() + ": cannot create the folder: " + ec.message());
    const Cell root = root_cell(lo, hi);
    Builder b(lod_meta.parent_path().empty() ? fs::path("lod-meta.json") : lod_meta, o, degree,
              0.5 * (root.lo + root.hi));
    const RecordLayout& L = b.layout();
    // 2. The budget: open units (each level up to 2 chunk counts), then cells (a record, its cloud, the
    // chunk's copy and levels: about R + 3·C a Gaussian), then the scatter buffers.
    const std::uint64_t C = cloud_bytes_per(L), budget = o.memory_budget;
    const std::uint64_t scatter = std::min<std::uint64_t>(kScatterBytes, budget / 8);
    b.chunk_count = std::max<std::uint64_t>(
        256, std::min<std::uint64_t>(o.chunk_count, budget / 4 / (2 * std::uint64_t(o.levels) * C)));
    const std::uint64_t units_max = 2 * std::uint64_t(o.levels) * b.chunk_count * C;
    const std::uint64_t rest =
        budget > units_max + 2 * scatter ? budget - units_max - 2 * scatter : budget / 4;
    BucketOptions bo;
    bo.record_bytes = L.bytes;
    bo.cap_records = std::max<std::uint64_t>(1024, rest / (L.bytes + 3 * C + 16));
    bo.scatter_bytes = scatter;
    bo.temp_dir = o.temp_dir.empty()
                      ? (lod_meta.parent_path().empty() ? fs::path(".") : lod_meta.parent_path())
                      : o.temp_dir;
    bo.ledger = &b.ledger;
    std::uint64_t scattered = 0, built = 0;
    bo.scattered = [&](std::uint64_t m) {
        scattered += m;
        if (o.progress && count > 0)
            o.progress("bucketing", std::min(1.0, double(scattered) / double(count)));
    };
    const RecordScan scan = [&](const RecordSink& sink) -> Status {
        std::vector<std::byte> buf;
        return source.scan([&](const GaussianCloud& g) -> Status {
            LedgerHold hold(b.ledger, g.size() * (L.bytes + C));
            buf.resize(g.size() * L.bytes);
            for (std::size_t i = 0; i < g.size(); ++i) to_record(g, i, L, buf.data() + i * L.bytes);
            return sink(buf.data(), g.size());
        });
    };
    if (Status s = bucket_cells(scan, count, root, bo, source.name,
                                [&](std::vector<std::byte>& r, std::size_t n, const Cell& c) -> Status {
                                    if (built == 0) report_progress(o.progress, "building", 0.0);
                                    Status st = b.cell(r, n, c);
                                    built += n;
                                    report_progress(o.progress, "building", double(built) / double(count));
                                    return st;
                                });
        !s)
        return s.error();
    // The open units (the last chunks of every level) and lod-meta.json.
    report_progress(o.progress, "writing", 0.0);
    if (Status s = b.finish(o); !s) return s.error();
    report_progress(o.progress, "writing", 1.0);
    return b.stats;
}

}  // namespace sffd::lod
