#include "systems/splat_render/storage_limits.h"

#include <algorithm>
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
    // Sprite records then the flat-coloured records: two runs of `capacity` (splat_render.cpp).
    const std::uint64_t records = 2 * n * SFFD_SPLAT_RECORD_BYTES;
    const std::uint64_t cloud = n * SFFD_GPU_SPLAT_BYTES;
    if (!gfx::ssbo_fits(records)) return make_error(gfx::ssbo_too_large("render.visible_splats", records));
    if (!gfx::ssbo_fits(cloud)) return make_error(gfx::ssbo_too_large("splats", cloud));
    return {};
}

void warn_once(const std::string& message) {
    static std::mutex mutex;
    static std::set<std::string> seen;
    std::lock_guard lock(mutex);
    if (seen.insert(message).second) log::warn(message);
}

}  // namespace sffd::render
