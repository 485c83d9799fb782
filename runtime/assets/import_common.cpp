// Helpers shared by the importers (import_detail.h): geometry validation and texture loading through the
// resource resolver (runtime/core/file_io.h) with the decoded-size budgets.
#include "runtime/assets/import_detail.h"

#include <atomic>

#include <stb/stb_image.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/core/file_io.h"

namespace sffd::assets {
namespace fs = std::filesystem;

namespace {

// The smallest i < n with bad(i), or n. Millions of points are checked in parallel; each range stops at its
// own first bad point, so the one reported is the first in order, as a serial loop reports it.
template <class Bad>
std::size_t first_bad(std::size_t n, const Bad& bad) {
    std::atomic<std::size_t> first{n};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end() && i < first.load(std::memory_order_relaxed); ++i)
                if (bad(i)) {
                    std::size_t seen = first.load();
                    while (i < seen && !first.compare_exchange_weak(seen, i)) {
                    }
                    return;
                }
        });
    return first.load();
}

}  // namespace

namespace detail {

Status check_geometry(const Geometry& g) {
    const std::size_t n = g.positions.size();
    if (const std::size_t i = first_bad(n, [&](std::size_t k) { return !finite3(g.positions[k]); }); i < n)
        return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite coordinate");
    if (const std::size_t i =
            first_bad(g.normals.size(), [&](std::size_t k) { return !finite3(glm::dvec3(g.normals[k])); });
        i < g.normals.size())
        return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite normal");
    if (const std::size_t i = first_bad(
            g.uvs.size(),
            [&](std::size_t k) { return !std::isfinite(g.uvs[k].x) || !std::isfinite(g.uvs[k].y); });
        i < g.uvs.size())
        return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite texture coordinate");
    if (const std::size_t i = first_bad(g.axis_u.size(),
                                        [&](std::size_t k) {
                                            return !finite3(glm::dvec3(g.axis_u[k])) ||
                                                   !finite3(glm::dvec3(g.axis_v[k]));
                                        });
        i < g.axis_u.size())
        return make_error(g.source + ": point " + std::to_string(i) + " has non-finite splat axes");
    if (const std::size_t i = first_bad(g.uv_axes.size(),
                                        [&](std::size_t k) {
                                            const glm::vec4& f = g.uv_axes[k];
                                            return !std::isfinite(f.x + f.y + f.z + f.w);
                                        });
        i < g.uv_axes.size())
        return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite uv frame");
    if ((!g.uv_axes.empty() && (g.uv_axes.size() != n || g.axis_u.size() != n)) ||
        (!g.uv_grad_u.empty() && (g.uv_grad_u.size() != n || g.uv_grad_v.size() != n)))
        return make_error(g.source + ": attribute arrays do not match the point count");
    if ((!g.normals.empty() && g.normals.size() != n) || (!g.colors.empty() && g.colors.size() != n) ||
        (!g.uvs.empty() && g.uvs.size() != n) || g.axis_u.size() != g.axis_v.size() ||
        (!g.axis_u.empty() && g.axis_u.size() != n))
        return make_error(g.source + ": attribute arrays do not match the point count");
    for (std::size_t i = 0; i < g.triangles.size(); ++i)
        if (g.triangles[i] >= n)
            return make_error(g.source + ": face " + std::to_string(i / 3) + " refers to vertex " +
                              std::to_string(g.triangles[i]) + " but there are only " + std::to_string(n));
    for (std::int32_t m : g.triangle_material)
        if (m >= static_cast<std::int32_t>(g.materials.size()))
            return make_error(g.source + ": bad material index");
    for (const MeshMaterial& m : g.materials)
        if (m.texture >= static_cast<int>(g.textures.size()))
            return make_error(g.source + ": bad texture index");
    return {};
}

Result<Image> decode_image(const fs::path& path, std::uint64_t* budget_left) {
    auto bytes = read_file(path, kMaxResourceBytes);
    if (!bytes) return bytes.error();
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes->data());
    const int size = static_cast<int>(std::min<std::size_t>(bytes->size(), 0x7fffffff));
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(data, size, &w, &h, &comp) || w <= 0 || h <= 0)
        return make_error(path.string() + ": cannot decode image: " +
                          (stbi_failure_reason() ? stbi_failure_reason() : "unknown format"));
    const std::uint64_t pixels = static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h);
    if (pixels > kMaxImagePixels)
        return make_error(path.string() + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                          ", larger than 8192x8192");
    if (budget_left) {
        if (pixels * 4 > *budget_left)
            return make_error(path.string() + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                              "; the textures of one file may decode to at most " +
                              std::to_string(kDecodedTextureBudget >> 20) + " MiB in total");
        *budget_left -= pixels * 4;
    }
    stbi_uc* pixels_rgba = stbi_load_from_memory(data, size, &w, &h, &comp, 4);
    if (!pixels_rgba)
        return make_error(path.string() +
                          ": cannot decode image: " + (stbi_failure_reason() ? stbi_failure_reason() : "?"));
    Image img;
    img.width = w;
    img.height = h;
    img.rgba8.assign(pixels_rgba,
                     pixels_rgba + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
    stbi_image_free(pixels_rgba);
    return img;
}

Result<Image> load_named_image(const fs::path& owner, const std::string& name, const std::string& source,
                               std::uint64_t* budget_left, bool& missing) {
    missing = false;
    auto where = resolve_resource(owner, name);
    if (!where) {
        missing = where.message().size() >= 9 &&
                  where.message().compare(where.message().size() - 9, 9, "not found") == 0;
        return where.error();
    }
    auto img = decode_image(*where, budget_left);
    if (!img) return make_error(source + ": texture '" + name + "': " + img.message());
    return img;
}

}  // namespace detail

}  // namespace sffd::assets
