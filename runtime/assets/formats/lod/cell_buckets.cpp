#include "runtime/assets/formats/lod/cell_buckets.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {

// An unlinked temporary file: gone when closed, also when the process dies.
class SpillFile {
public:
    static Result<SpillFile> create(const fs::path& dir) {
        std::string templ = (dir / ".lod-spill-XXXXXX").string();
        const int fd = ::mkstemp(templ.data());
        if (fd < 0) return make_error(templ + ": cannot create a temporary file: " + std::strerror(errno));
        ::unlink(templ.c_str());
        return SpillFile(fd, std::move(templ));
    }
    SpillFile(SpillFile&& o) noexcept : m_fd(std::exchange(o.m_fd, -1)), m_name(std::move(o.m_name)) {}
    SpillFile& operator=(SpillFile&&) = delete;
    ~SpillFile() {
        if (m_fd >= 0) ::close(m_fd);
    }
    Status write_at(const std::byte* data, std::size_t bytes, std::uint64_t at) const {
        while (bytes > 0) {
            const ssize_t w = ::pwrite(m_fd, data, bytes, off_t(at));
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0) return make_error(m_name + ": write failed: " + std::strerror(errno));
            data += w, bytes -= std::size_t(w), at += std::uint64_t(w);
        }
        return {};
    }
    Status read_at(std::byte* data, std::size_t bytes, std::uint64_t at) const {
        while (bytes > 0) {
            const ssize_t r = ::pread(m_fd, data, bytes, off_t(at));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0) return make_error(m_name + ": read failed (the temporary file was cut short)");
            data += r, bytes -= std::size_t(r), at += std::uint64_t(r);
        }
        return {};
    }

private:
    SpillFile(int fd, std::string name) : m_fd(fd), m_name(std::move(name)) {}
    int m_fd = -1;
    std::string m_name;
};

// Sub-cell of a point in a grid of n per axis over the cell, clamped into the grid.
std::uint32_t sub_index(const double* p, const Cell& c, std::uint32_t n, int k) {
    std::uint32_t idx[3];
    for (int a = 0; a < 3; ++a) {
        const double t = (p[a] - c.lo[a]) / (c.hi[a] - c.lo[a]) * double(n);
        idx[a] = std::uint32_t(std::clamp(t, 0.0, double(n - 1)));
    }
    // Morton code with x the highest bit of each level: child order x·4 + y·2 + z at every level.
    std::uint32_t code = 0;
    for (int b = k - 1; b >= 0; --b)
        code = code << 3 | ((idx[0] >> b) & 1u) << 2 | ((idx[1] >> b) & 1u) << 1 | ((idx[2] >> b) & 1u);
    return code;
}

Cell sub_cell(const Cell& c, std::uint32_t code, int k) {
    Cell s;
    s.level = c.level + k;
    glm::u64vec3 idx(0);
    for (int b = k - 1; b >= 0; --b) {
        const std::uint32_t oct = (code >> (3 * b)) & 7u;
        idx.x = idx.x << 1 | ((oct >> 2) & 1u), idx.y = idx.y << 1 | ((oct >> 1) & 1u),
        idx.z = idx.z << 1 | (oct & 1u);
    }
    const double n = double(std::uint64_t(1) << k);
    s.coords = c.coords * (std::uint64_t(1) << k) + idx;
    for (int a = 0; a < 3; ++a) {
        const double size = (c.hi[a] - c.lo[a]) / n;
        s.lo[a] = c.lo[a] + size * double(idx[a]);
        s.hi[a] = idx[a] + 1 == std::uint64_t(n) ? c.hi[a] : c.lo[a] + size * double(idx[a] + 1);
    }
    return s;
}

}  // namespace

Cell root_cell(const glm::dvec3& lo, const glm::dvec3& hi) {
    const glm::dvec3 centre = 0.5 * (lo + hi);
    double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    side = side > 0 ? side * (1.0 + 1e-9) : 1.0;
    Cell c;
    c.lo = centre - glm::dvec3(0.5 * side), c.hi = centre + glm::dvec3(0.5 * side);
    return c;
}

Status bucket_cells(const RecordScan& scan, std::uint64_t count, const Cell& cell, const BucketOptions& o,
                    const std::string& name, const CellBuilder& build) {
    const std::size_t R = o.record_bytes;
    if (count <= o.cap_records || cell.level >= kMaxCellLevel) {
        std::vector<std::byte> records;
        LedgerHold hold(*o.ledger, count * R);
        records.resize(std::size_t(count) * R);
        std::size_t at = 0;
        if (Status s = scan([&](const std::byte* p, std::size_t n) -> Status {
                if (at + n > count) return make_error(name + ": the input changed while it was read");
                std::memcpy(records.data() + at * R, p, n * R);
                at += n;
                return {};
            });
            !s)
            return s;
        if (at != count) return make_error(name + ": the input changed while it was read");
        return build(records, at, cell);
    }
    // Levels to go down at once: enough that the average cell fits (8^k ≥ 2·count / cap), at most 3
    // (512 cells: the scatter buffers stay small) and never below kMaxCellLevel.
    int k = 1;
    while (k < 3 && double(std::uint64_t(1) << (3 * k)) < 2.0 * double(count) / double(o.cap_records)) ++k;
    k = std::min(k, kMaxCellLevel - cell.level);
    const std::uint32_t n = 1u << k, cells = 1u << (3 * k);
    std::vector<std::uint64_t> counts(cells, 0);
    std::uint64_t seen = 0;
    if (Status s = scan([&](const std::byte* p, std::size_t m) -> Status {
            for (std::size_t i = 0; i < m; ++i) {
                double xyz[3];
                std::memcpy(xyz, p + i * R, sizeof xyz);
                ++counts[sub_index(xyz, cell, n, k)];
            }
            seen += m;
            return {};
        });
        !s)
        return s;
    if (seen != count) return make_error(name + ": the input changed while it was read");
    std::vector<std::uint64_t> start(cells + 1, 0);
    for (std::uint32_t c = 0; c < cells; ++c) start[c + 1] = start[c] + counts[c];
    auto spill = SpillFile::create(o.temp_dir);
    if (!spill) return spill.error();
    {
        // One buffer per cell, flushed when full; the buffers together within scatter_bytes.
        const std::size_t per =
            std::max<std::size_t>(1, std::min<std::size_t>(o.scatter_bytes / cells / R, 1u << 14));
        LedgerHold hold(*o.ledger, std::uint64_t(per) * R * cells);
        std::vector<std::byte> buffers(per * R * cells);
        std::vector<std::size_t> fill(cells, 0);
        std::vector<std::uint64_t> cursor(start.begin(), start.end() - 1);
        const auto flush = [&](std::uint32_t c) -> Status {
            if (fill[c] == 0) return {};
            if (cursor[c] + fill[c] > start[c + 1])
                return make_error(name + ": the input changed while it was read");
            if (Status s =
                    spill->write_at(buffers.data() + std::size_t(c) * per * R, fill[c] * R, cursor[c] * R);
                !s)
                return s;
            cursor[c] += fill[c];
            fill[c] = 0;
            return {};
        };
        if (Status s = scan([&](const std::byte* p, std::size_t m) -> Status {
                for (std::size_t i = 0; i < m; ++i) {
                    double xyz[3];
                    std::memcpy(xyz, p + i * R, sizeof xyz);
                    const std::uint32_t c = sub_index(xyz, cell, n, k);
                    std::memcpy(buffers.data() + (std::size_t(c) * per + fill[c]) * R, p + i * R, R);
                    if (++fill[c] == per)
                        if (Status f = flush(c); !f) return f;
                }
                if (o.scattered) o.scattered(m);
                return {};
            });
            !s)
            return s;
        for (std::uint32_t c = 0; c < cells; ++c)
            if (Status f = flush(c); !f) return f;
        for (std::uint32_t c = 0; c < cells; ++c)
            if (cursor[c] != start[c + 1]) return make_error(name + ": the input changed while it was read");
    }
    for (std::uint32_t c = 0; c < cells; ++c) {
        if (counts[c] == 0) continue;
        const std::uint64_t first = start[c], total = counts[c];
        const RecordScan slice = [&, first, total](const RecordSink& sink) -> Status {
            const std::size_t block =
                std::max<std::size_t>(1, std::size_t(std::min<std::uint64_t>(o.scatter_bytes, 4u << 20)) / R);
            LedgerHold hold(*o.ledger, std::uint64_t(block) * R);
            std::vector<std::byte> buf(block * R);
            for (std::uint64_t at = 0; at < total;) {
                const std::size_t m = std::size_t(std::min<std::uint64_t>(block, total - at));
                if (Status s = spill->read_at(buf.data(), m * R, (first + at) * R); !s) return s;
                if (Status s = sink(buf.data(), m); !s) return s;
                at += m;
            }
            return {};
        };
        if (Status s = bucket_cells(slice, total, sub_cell(cell, c, k), o, name, build); !s) return s;
    }
    return {};
}

}  // namespace sffd::lod
