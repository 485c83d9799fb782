#include "runtime/gfx/radix_sort.h"

#include <string>
#include <utility>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/radix_sort_layout.h"

namespace sffd::gfx {

Result<RadixSorter> create_radix_sorter() {
    RadixSorter s;
    auto count = load_compute_program("common/radix_sort_count.comp", "radix_sort.count");
    if (!count) return count.error();
    auto scan = load_compute_program("common/radix_sort_scan.comp", "radix_sort.scan");
    if (!scan) return scan.error();
    auto scatter = load_compute_program("common/radix_sort_scatter.comp", "radix_sort.scatter");
    if (!scatter) return scatter.error();
    auto reduce = load_compute_program("common/scan_reduce.comp", "scan.reduce");
    if (!reduce) return reduce.error();
    auto add = load_compute_program("common/scan_add.comp", "scan.add");
    if (!add) return add.error();
    s.count = std::move(*count), s.scan = std::move(*scan), s.scatter = std::move(*scatter);
    s.scan_reduce = std::move(*reduce), s.scan_add = std::move(*add);
    s.scan_sums = Buffer::create("scan.block_sums");
    s.keys_scratch = Buffer::create("radix_sort.keys_scratch");
    s.values_scratch = Buffer::create("radix_sort.values_scratch");
    s.histogram = Buffer::create("radix_sort.histogram");
    return s;
}

namespace {

// What the callers do next with a sort's or a scan's results: SSBO reads (the tile passes), read-backs and
// copies (the tile entry count, the odd-pass copy home), and indirect commands built from them. A caller
// that fetches them as vertex attributes or indices adds its own barrier.
constexpr GLbitfield kResultBarrier =
    GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT;

// Grow-only storage (reallocating drops the contents, which are scratch).
void grow(const Buffer& b, std::uint64_t need) {
    glNamedBufferData(b.id(), GLsizeiptr(need * sizeof(std::uint32_t)), nullptr, GL_DYNAMIC_COPY);
}

void bind(GLuint binding, GLuint buffer) { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer); }

// One round of both algorithms: `per_block` over the blocks (a histogram or a sum each), the one-group
// scan of those entries, `apply` over the blocks (scatter, or add the block's offset). Leaves `apply`
// bound; the caller places the barrier its next reader needs.
Status block_scan_round(const RadixSorter& s, GLuint per_block, GLuint apply, std::uint32_t blocks,
                        std::uint32_t max_x) {
    glUseProgram(per_block);
    if (Status st = dispatch_1d(std::uint64_t(blocks) * SFFD_RADIX_THREADS, SFFD_RADIX_THREADS, max_x); !st)
        return st;
    // The per-block entries are read by the scan as SSBOs, and the scan's results by `apply`.
    memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "radix.blocks");
    glUseProgram(s.scan.id());
    glDispatchCompute(1, 1, 1);
    memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "radix.scan");
    glUseProgram(apply);
    return dispatch_1d(std::uint64_t(blocks) * SFFD_RADIX_THREADS, SFFD_RADIX_THREADS, max_x);
}

}  // namespace

Status radix_sort(RadixSorter& s, GLuint keys, GLuint values, std::uint32_t count, int key_bits) {
    if (key_bits < 1 || key_bits > 32)
        return make_error("radix_sort(): key_bits " + std::to_string(key_bits) + " is not in 1..32");
    if (count <= 1) return {};
    // Every pass reads and writes whole key and value arrays as storage blocks (random scatter): no
    // ranges, so arrays past GL_MAX_SHADER_STORAGE_BLOCK_SIZE are refused, not read past its end.
    if (!ssbo_fits(std::uint64_t(count) * sizeof(std::uint32_t)))
        return make_error("radix_sort(): " +
                          ssbo_too_large("keys", std::uint64_t(count) * sizeof(std::uint32_t)));
    const std::uint32_t blocks = (count + SFFD_RADIX_BLOCK - 1) / SFFD_RADIX_BLOCK;
    if (count > s.scratch_elements) {
        grow(s.keys_scratch, count), grow(s.values_scratch, count);
        s.scratch_elements = count;
    }
    const std::uint64_t entries = std::uint64_t(blocks) * SFFD_RADIX_BUCKETS + 1;  // + the scan's total
    if (entries > s.histogram_entries) {
        grow(s.histogram, entries);
        s.histogram_entries = entries;
    }
    const std::uint32_t max_x = s.max_groups_x ? s.max_groups_x : dispatch_group_limit();
    const int passes = (key_bits + int(SFFD_RADIX_BITS) - 1) / int(SFFD_RADIX_BITS);
    GLuint keys_in = keys, values_in = values, keys_out = s.keys_scratch.id(),
           values_out = s.values_scratch.id();
    for (GLuint p : {s.count.id(), s.scatter.id()}) {
        glProgramUniform1ui(p, SFFD_RADIX_LOC_COUNT, count);
        glProgramUniform1ui(p, SFFD_RADIX_LOC_BLOCKS, blocks);
    }
    glProgramUniform1ui(s.scan.id(), SFFD_RADIX_LOC_COUNT, blocks * SFFD_RADIX_BUCKETS);
    bind(SFFD_RADIX_SSBO_HISTOGRAM, s.histogram.id());
    for (int pass = 0; pass < passes; ++pass) {
        const GLuint shift = GLuint(pass) * SFFD_RADIX_BITS;
        bind(SFFD_RADIX_SSBO_KEYS_IN, keys_in);
        bind(SFFD_RADIX_SSBO_VALUES_IN, values_in);
        bind(SFFD_RADIX_SSBO_KEYS_OUT, keys_out);
        bind(SFFD_RADIX_SSBO_VALUES_OUT, values_out);
        glProgramUniform1ui(s.count.id(), SFFD_RADIX_LOC_SHIFT, shift);
        glProgramUniform1ui(s.scatter.id(), SFFD_RADIX_LOC_SHIFT, shift);
        if (Status st = block_scan_round(s, s.count.id(), s.scatter.id(), blocks, max_x); !st) return st;
        // The next pass reads the scattered keys as SSBOs, and its count overwrites the histogram this
        // scatter read (write-after-read): both are SHADER_STORAGE.
        memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "radix.pass");
        std::swap(keys_in, keys_out), std::swap(values_in, values_out);
    }
    glUseProgram(0);
    if (passes % 2 == 1) {  // the result is in the scratch buffers: copy it home
        memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT, "radix.copy");  // a copy reads shader writes
        glCopyNamedBufferSubData(keys_in, keys, 0, 0, GLsizeiptr(count) * 4);
        glCopyNamedBufferSubData(values_in, values, 0, 0, GLsizeiptr(count) * 4);
    }
    memory_barrier(kResultBarrier, "radix.sort");
    return {};
}

Status exclusive_scan(RadixSorter& s, GLuint buffer, std::uint32_t count) {
    if (count == 0xffffffffu)
        return make_error("exclusive_scan(): the total of 2^32 - 1 elements has no slot");
    if (count == 0) {
        const GLuint zero = 0;
        glClearNamedBufferSubData(buffer, GL_R32UI, 0, sizeof(GLuint), GL_RED_INTEGER, GL_UNSIGNED_INT,
                                  &zero);
        return {};
    }
    if (!ssbo_fits((std::uint64_t(count) + 1) * sizeof(std::uint32_t)))
        return make_error("exclusive_scan(): " +
                          ssbo_too_large("values", (std::uint64_t(count) + 1) * sizeof(std::uint32_t)));
    const std::uint32_t blocks = (count + SFFD_RADIX_BLOCK - 1) / SFFD_RADIX_BLOCK;
    if (blocks + 1u > s.scan_sum_entries) {
        grow(s.scan_sums, blocks + 1u);
        s.scan_sum_entries = blocks + 1u;
    }
    const std::uint32_t max_x = s.max_groups_x ? s.max_groups_x : dispatch_group_limit();
    for (GLuint p : {s.scan_reduce.id(), s.scan_add.id()}) {
        glProgramUniform1ui(p, SFFD_RADIX_LOC_COUNT, count);
        glProgramUniform1ui(p, SFFD_RADIX_LOC_BLOCKS, blocks);
    }
    glProgramUniform1ui(s.scan.id(), SFFD_RADIX_LOC_COUNT, blocks);
    bind(SFFD_RADIX_SSBO_KEYS_IN, buffer);
    bind(SFFD_RADIX_SSBO_HISTOGRAM, s.scan_sums.id());
    if (Status st = block_scan_round(s, s.scan_reduce.id(), s.scan_add.id(), blocks, max_x); !st) return st;
    glUseProgram(0);
    memory_barrier(kResultBarrier, "radix.scan_result");
    return {};
}

}  // namespace sffd::gfx
