#include "systems/splat_render/storage_limits.h"

#include <algorithm>
#include <cassert>
#include <mutex>
#include <set>
#include <string>

#include <glm/glm.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/limits.h"
#include "shaders/common/bindings.h"
#include "shaders/splat_render/compute_raster.h"
#include "shaders/splat_render/splat_record.h"

namespace sffd::render {

Status compute_raster_fits(int width, int height) {
    const std::uint64_t pixels = std::uint64_t(std::max(width, 1)) * std::uint64_t(std::max(height, 1));
    const std::uint64_t sums = pixels * SFFD_RASTER_SUM_WORDS * sizeof(std::uint32_t);
    const std::uint64_t depth = pixels * sizeof(std::uint32_t);
    if (!gfx::ssbo_fits(sums))
        return make_error(gfx::ssbo_too_large("render.compute.sums", sums) + "; using the raster path");
    if (!gfx::ssbo_fits(depth))
        return make_error(gfx::ssbo_too_large("render.compute.depth", depth) + "; using the raster path");
    return {};
}

Status compute_cull_fits(std::size_t splats) {
    const std::uint64_t n = std::max<std::uint64_t>(splats, 1);
    // The cull binds the first of the records buffer's two runs of `capacity` (the sprites; the second, the
    // flat-coloured sprites, is the CPU cull's alone): 16M splats' records fit a 2 GiB block that way.
    const std::uint64_t records = n * SFFD_SPLAT_RECORD_BYTES;
    const std::uint64_t cloud = n * SFFD_GPU_SPLAT_BYTES;
    if (!gfx::ssbo_fits(records)) return make_error(gfx::ssbo_too_large("render.visible_splats", records));
    if (!gfx::ssbo_fits(cloud)) return make_error(gfx::ssbo_too_large("splats", cloud));
    return {};
}

Status compute_raster_records_fit(std::size_t capacity, bool flat_list) {
    // The passes bind the records from the first to the end of the last list they read.
    const std::uint64_t records =
        (flat_list ? 2 : 1) * std::max<std::uint64_t>(capacity, 1) * SFFD_SPLAT_RECORD_BYTES;
    if (!gfx::ssbo_fits(records))
        return make_error(gfx::ssbo_too_large("render.visible_splats", records) + "; using the raster path");
    return {};
}

std::vector<QuadBatch> layout_quad_batches(std::span<const std::uint32_t> quads,
                                           std::span<const gfx::SsboBatch> batches, std::uint32_t align_words,
                                           std::vector<std::uint32_t>& out) {
    align_words = std::max<std::uint32_t>(align_words, 1);
    out.clear();
    std::vector<QuadBatch> result;
    result.reserve(batches.size());
    std::size_t q = 0;
    for (const gfx::SsboBatch& b : batches) {
        out.resize((out.size() + align_words - 1) / align_words * align_words, 0u);
        QuadBatch qb;
        qb.splats = b;
        qb.quad_first = std::uint32_t(out.size());
        for (; q < quads.size() && quads[q] < b.first + b.count; ++q) {
            assert(quads[q] >= b.first && "quads must ascend");
            out.push_back(std::uint32_t(quads[q] - b.first));
        }
        qb.quad_count = std::uint32_t(out.size()) - qb.quad_first;
        result.push_back(qb);
    }
    return result;
}

void warn_once(const std::string& message) {
    static std::mutex mutex;
    static std::set<std::string> seen;
    std::lock_guard lock(mutex);
    if (seen.insert(message).second) log::warn(message);
}

}  // namespace sffd::render
