#include "runtime/gfx/ssbo_batch.h"

#include <algorithm>
#include <numeric>

#include "runtime/core/log.h"

namespace sffd::gfx {

Result<std::vector<SsboBatch>> ssbo_batches(std::uint64_t count, std::span<const std::uint64_t> strides,
                                            const GlLimits& limits) {
    std::vector<SsboBatch> out;
    if (count == 0) return out;
    const std::uint64_t block =
        limits.max_ssbo_block_size > 0 ? std::uint64_t(limits.max_ssbo_block_size) : 0;
    // GL 4.5 caps the alignment at 256 (§23, table 23.64: a maximum), so 256 is right when none was queried.
    const std::uint64_t align =
        limits.ssbo_offset_alignment > 0 ? std::uint64_t(limits.ssbo_offset_alignment) : 256;
    std::uint64_t per_batch = count, unit = 1;
    bool fits = true;
    for (const std::uint64_t stride : strides) {
        if (stride == 0) continue;
        fits = fits && ssbo_fits(count * stride, limits);
        per_batch = std::min(per_batch, stride <= block ? block / stride : 0);
        // first * stride must be a multiple of `align`: first a multiple of align / gcd(stride, align).
        unit = std::lcm(unit, align / std::gcd(stride, align));
    }
    if (fits) return std::vector<SsboBatch>{{0, count}};
    per_batch -= per_batch % unit;
    if (per_batch == 0)
        return make_error(
            log::str("ssbo_batches(): not one batch fits: ", unit, " elements of up to ",
                     *std::max_element(strides.begin(), strides.end()), " bytes (offsets aligned to ", align,
                     " bytes) exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (", limits.max_ssbo_block_size, ")"));
    for (std::uint64_t first = 0; first < count; first += per_batch)
        out.push_back({first, std::min(per_batch, count - first)});
    return out;
}

void bind_ssbo_range(GLuint binding, GLuint buffer, const SsboBatch& batch, std::uint64_t stride) {
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, binding, buffer, GLintptr(batch.first * stride),
                      GLsizeiptr(batch.count * stride));
}

}  // namespace sffd::gfx
