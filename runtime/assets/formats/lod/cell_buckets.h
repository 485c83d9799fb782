// Out-of-core bucketing for the hierarchy builders (lod_build.h, potree2_write.h): points as fixed records
// (a double x y z at byte 0, then whatever the builder carries) are streamed from their source, sorted
// by octree cell into an unlinked temporary file (a histogram pass, then a scatter pass through one
// small buffer per cell, together at most scatter_bytes), and every cell small enough to build in memory is
// handed to the builder whole; a cell still too large is bucketed again, into its own temporary file, one
// octree level of 8^k cells finer. Memory: at most `cap_records` records at once, plus the scatter buffers,
// each counted in the MemoryLedger. Cells are visited depth first in octree child order (child index x·4 +
// y·2 + z, Potree's), so a builder can write its output as it goes.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"

namespace sffd::lod {

// The bytes a builder holds, counted by the builder itself where it allocates (its peak is what the
// memory-budget test checks).
class MemoryLedger {
public:
    void add(std::uint64_t bytes) {
        const std::uint64_t now = m_now.fetch_add(bytes) + bytes;
        std::uint64_t peak = m_peak.load();
        while (now > peak && !m_peak.compare_exchange_weak(peak, now)) {
        }
    }
    void sub(std::uint64_t bytes) { m_now.fetch_sub(bytes); }
    std::uint64_t now() const { return m_now.load(); }
    std::uint64_t peak() const { return m_peak.load(); }

private:
    std::atomic<std::uint64_t> m_now{0}, m_peak{0};
};

// A ledger entry for the lifetime of a scope.
class LedgerHold {
public:
    LedgerHold(MemoryLedger& l, std::uint64_t bytes) : m_l(l), m_bytes(bytes) { m_l.add(bytes); }
    ~LedgerHold() { m_l.sub(m_bytes); }
    LedgerHold(const LedgerHold&) = delete;
    LedgerHold& operator=(const LedgerHold&) = delete;

private:
    MemoryLedger& m_l;
    std::uint64_t m_bytes;
};

inline constexpr std::uint64_t kScatterBytes = std::uint64_t(32) << 20;
inline constexpr int kMaxCellLevel = 20;  // a cell this deep is built in memory whatever its size

// Records in blocks: the sink is called with `n` records of record_bytes each, back to back.
using RecordSink = std::function<Status(const std::byte* records, std::size_t n)>;
// A source that can be read more than once (every read gives the same records in the same order).
using RecordScan = std::function<Status(const RecordSink& sink)>;

// An octree cell: `level` below the root cube, integer coordinates in [0, 2^level) per axis.
struct Cell {
    int level = 0;
    glm::u64vec3 coords{0};
    glm::dvec3 lo{0.0}, hi{0.0};
};

struct BucketOptions {
    std::size_t record_bytes = 0;
    std::uint64_t cap_records = 0;                // the most records handed over at once
    std::uint64_t scatter_bytes = kScatterBytes;  // the scatter buffers of one pass, all cells together
    std::filesystem::path temp_dir;
    MemoryLedger* ledger = nullptr;
    std::function<void(std::uint64_t records)> scattered;  // progress: records written to a spill file
};

// Called once per non-empty cell with its records (n of them, the vector may be reused after the call).
using CellBuilder = std::function<Status(std::vector<std::byte>& records, std::size_t n, const Cell& cell)>;

// Buckets the `count` records of `scan` (all inside `root`, a cube) and calls `build` for every cell
// small enough (or at kMaxCellLevel), depth first in child order. Errors name `name` (the input) or the
// temporary file.
Status bucket_cells(const RecordScan& scan, std::uint64_t count, const Cell& root,
                    const BucketOptions& options, const std::string& name, const CellBuilder& build);

// The child index (x·4 + y·2 + z) of a cell below its ancestor `levels` up: used by builders that
// rebuild the octree from the cells.
inline glm::u64vec3 child_coords(const Cell& c, int child) {
    return {c.coords.x * 2 + ((child >> 2) & 1), c.coords.y * 2 + ((child >> 1) & 1),
            c.coords.z * 2 + (child & 1)};
}

// The cube around a box (its largest side, centred), slightly grown so no point lies on its upper faces.
Cell root_cell(const glm::dvec3& lo, const glm::dvec3& hi);

}  // namespace sffd::lod
