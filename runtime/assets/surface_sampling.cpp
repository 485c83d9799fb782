// Mesh surface sampling (import.h sample_surface) and the weighted sample elimination it thins with.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>

#include <tbb/parallel_for.h>

#include "runtime/assets/import_detail.h"
#include "runtime/assets/point_tree.h"

namespace sffd::assets {
using namespace detail;

namespace detail {

// Weighted sample elimination (Yuksel 2015): removes the most crowded point until `keep` remain.
// `area` is the surface area the points cover (for the neighbourhood radius). Returns the kept indices
// in ascending order.
std::vector<std::uint32_t> eliminate(const std::vector<glm::dvec3>& pts, std::size_t keep, double area,
                                     const ProgressFn& progress) {
    const std::size_t n = pts.size();
    std::vector<std::uint32_t> kept;
    if (keep >= n) {
        kept.resize(n);
        std::iota(kept.begin(), kept.end(), 0u);
        return kept;
    }
    const double r_max = std::sqrt(area / (2.0 * std::sqrt(3.0) * static_cast<double>(keep)));
    const double r2 = 2.0 * r_max;
    ProgressCounter searched(progress, "finding neighbours for thinning", n);
    PointTree<glm::dvec3> tree(pts);
    // Neighbour lists in parallel blocks (the search dominates), concatenated in point order.
    constexpr std::size_t kBlock = 8192;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::vector<std::uint32_t>> block_nbr(blocks), block_count(blocks);
    std::vector<std::vector<float>> block_dist(blocks);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
        std::vector<std::pair<std::uint32_t, double>> found;
        nanoflann::SearchParams params(32, 0.0f, false);
        const std::size_t end = std::min(n, (b + 1) * kBlock);
        searched.add(end - b * kBlock);
        for (std::size_t i = b * kBlock; i < end; ++i) {
            const double q[3] = {pts[i].x, pts[i].y, pts[i].z};
            found.clear();
            tree.radius(q, r2 * r2, found, params);
            std::uint32_t taken = 0;
            for (const auto& [j, d2] : found) {
                if (j == i) continue;
                if (taken >= 64) break;  // duplicates piled on one spot: bound the work
                ++taken;
                block_nbr[b].push_back(j);
                block_dist[b].push_back(static_cast<float>(std::sqrt(d2)));
            }
            block_count[b].push_back(taken);
        }
    });
    searched.done();
    ProgressCounter thinned(progress, "thinning (sample elimination)", n - keep);
    std::vector<std::uint32_t> offsets(n + 1, 0);
    std::vector<std::uint32_t> nbr;
    std::vector<float> dist;
    for (std::size_t b = 0; b < blocks; ++b) {
        const std::size_t first = b * kBlock;
        for (std::size_t k = 0; k < block_count[b].size(); ++k)
            offsets[first + k + 1] = offsets[first + k] + block_count[b][k];
        nbr.insert(nbr.end(), block_nbr[b].begin(), block_nbr[b].end());
        dist.insert(dist.end(), block_dist[b].begin(), block_dist[b].end());
        std::vector<std::uint32_t>().swap(block_nbr[b]);
        std::vector<float>().swap(block_dist[b]);
    }
    std::vector<double> weight(n, 0.0);
    auto w = [&](float d) {
        const double x = 1.0 - static_cast<double>(d) / r2;
        return x * x * x * x * x * x * x * x;
    };
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) weight[i] += w(dist[e]);
    std::priority_queue<std::pair<double, std::uint32_t>> heap;
    for (std::size_t i = 0; i < n; ++i) heap.push({weight[i], static_cast<std::uint32_t>(i)});
    std::vector<char> removed(n, 0);
    std::size_t alive = n;
    while (alive > keep && !heap.empty()) {
        const auto [wt, i] = heap.top();
        heap.pop();
        if (removed[i] || wt != weight[i]) continue;  // stale entry (weights only decrease)
        removed[i] = 1;
        if (--alive % 4096 == 0) thinned.add(4096);
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
            const std::uint32_t j = nbr[e];
            if (removed[j]) continue;
            weight[j] -= w(dist[e]);
            heap.push({weight[j], j});
        }
    }
    thinned.done();
    for (std::size_t i = 0; i < n; ++i)
        if (!removed[i]) kept.push_back(static_cast<std::uint32_t>(i));
    return kept;
}

glm::vec4 sample_texture(const Image& img, glm::vec2 uv) {
    if (img.width <= 0 || img.height <= 0) return glm::vec4(1.0f);
    const float fx = (uv.x - std::floor(uv.x)) * static_cast<float>(img.width) - 0.5f;
    const float fy = (uv.y - std::floor(uv.y)) * static_cast<float>(img.height) - 0.5f;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const float tx = fx - static_cast<float>(x0), ty = fy - static_cast<float>(y0);
    auto texel = [&](int x, int y) {
        x = ((x % img.width) + img.width) % img.width;
        y = ((y % img.height) + img.height) % img.height;
        const std::uint8_t* p =
            &img.rgba8[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                        static_cast<std::size_t>(x)) *
                       4];
        return glm::vec4(p[0], p[1], p[2], p[3]) / 255.0f;
    };
    return glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), tx),
                    glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), tx), ty);
}

int single_texture(const Geometry& mesh) {
    if (mesh.uvs.size() != mesh.positions.size() || !mesh.colors.empty() || mesh.triangle_count() == 0)
        return -1;
    int texture = -1;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const int m = mesh.triangle_material.empty() ? (mesh.materials.size() == 1 ? 0 : -1)
                                                     : mesh.triangle_material[t];
        if (m < 0) return -1;
        const MeshMaterial& mat = mesh.materials[static_cast<std::size_t>(m)];
        // White within 8-bit rounding: the renderer's textured path has no base-colour factor.
        if (mat.texture < 0 || glm::any(glm::lessThan(mat.base_color, glm::vec4(254.5f / 255.0f)))) return -1;
        if (texture >= 0 && mat.texture != texture) return -1;
        texture = mat.texture;
    }
    const Image& img = mesh.textures[static_cast<std::size_t>(texture)];
    if (img.width <= 0 || img.height <= 0 ||
        img.rgba8.size() != std::size_t(img.width) * std::size_t(img.height) * 4)
        return -1;
    return texture;
}

void triangle_uv_gradients(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, glm::dvec2 ta,
                           glm::dvec2 tb, glm::dvec2 tc, glm::dvec3& grad_u, glm::dvec3& grad_v) {
    // grad = alpha e1 + beta e2 (in the plane) with grad . e1 = d1, grad . e2 = d2: the 2x2 Gram system.
    const glm::dvec3 e1 = b - a, e2 = c - a;
    const double g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2);
    const double det = g11 * g22 - g12 * g12;
    grad_u = grad_v = glm::dvec3(0.0);
    if (!(det > 1e-24 * g11 * g22) || !std::isfinite(det)) return;
    const glm::dvec2 d1 = tb - ta, d2 = tc - ta;
    auto solve = [&](double r1, double r2) {
        const double alpha = (g22 * r1 - g12 * r2) / det, beta = (g11 * r2 - g12 * r1) / det;
        return alpha * e1 + beta * e2;
    };
    grad_u = solve(d1.x, d2.x);
    grad_v = solve(d1.y, d2.y);
}

}  // namespace detail

Result<Geometry> sample_surface(const Geometry& mesh, std::size_t count, std::uint32_t seed,
                                const ProgressFn& progress) {
    const std::size_t nt = mesh.triangle_count();
    if (nt == 0) return make_error(mesh.source + ": no triangles to sample");
    if (count == 0) return make_error(mesh.source + ": cannot sample 0 splats");
    std::vector<double> cumulative(nt);
    double total = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
        const glm::dvec3& a = mesh.positions[mesh.triangles[3 * t]];
        const glm::dvec3& b = mesh.positions[mesh.triangles[3 * t + 1]];
        const glm::dvec3& c = mesh.positions[mesh.triangles[3 * t + 2]];
        total += 0.5 * glm::length(glm::cross(b - a, c - a));
        cumulative[t] = total;
    }
    if (!(total > 0.0) || !std::isfinite(total))
        return make_error(mesh.source + ": the mesh has no surface area");
    // Candidates: 4x the target (1x beyond 4M splats to bound memory), then thin to exactly `count`.
    const std::size_t candidates = count <= (std::size_t(4) << 20) ? 4 * count : count;
    Rng rng(seed);
    std::vector<glm::dvec3> pos(candidates);
    std::vector<std::uint32_t> tri(candidates);
    std::vector<glm::dvec2> bary(candidates);
    ProgressCounter sampled(progress, "sampling the surface", candidates);
    for (std::size_t i = 0; i < candidates; ++i) {
        if (i % 4096 == 4095) sampled.add(4096);
        const double r = rng.uniform() * total;
        const std::size_t t = std::min<std::size_t>(
            static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), r) -
                                     cumulative.begin()),
            nt - 1);
        double u = rng.uniform(), v = rng.uniform();
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        const glm::dvec3& a = mesh.positions[mesh.triangles[3 * t]];
        const glm::dvec3& b = mesh.positions[mesh.triangles[3 * t + 1]];
        const glm::dvec3& c = mesh.positions[mesh.triangles[3 * t + 2]];
        pos[i] = a + u * (b - a) + v * (c - a);
        tri[i] = static_cast<std::uint32_t>(t);
        bary[i] = glm::dvec2(u, v);
    }
    sampled.done();
    std::vector<std::uint32_t> kept = eliminate(pos, count, total, progress);
    // Spatial locality for the renderer and the cache: order samples by triangle.
    std::stable_sort(kept.begin(), kept.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return tri[x] < tri[y]; });

    Geometry out;
    out.source = mesh.source;
    out.attributes = mesh.attributes;
    const bool vertex_normals = mesh.normals.size() == mesh.positions.size();
    const bool bake_colour = !mesh.colors.empty() || !mesh.materials.empty();
    // One texture over the whole mesh: the cloud keeps it with a uv frame per splat (colours are still
    // baked: the untextured fallback, e.g. a PLY whose texture file went missing).
    const int texture = single_texture(mesh);
    if (texture >= 0) {
        const Image& img = mesh.textures[static_cast<std::size_t>(texture)];
        out.splat_texture.width = img.width;
        out.splat_texture.height = img.height;
        out.splat_texture.rgba8 = img.rgba8;
        out.uvs.reserve(count);
        out.uv_grad_u.reserve(count);
        out.uv_grad_v.reserve(count);
    }
    out.positions.reserve(count);
    out.normals.reserve(count);
    if (bake_colour) out.colors.reserve(count);
    for (std::uint32_t i : kept) {
        const std::size_t t = tri[i];
        const std::uint32_t ia = mesh.triangles[3 * t], ib = mesh.triangles[3 * t + 1],
                            ic = mesh.triangles[3 * t + 2];
        const double u = bary[i].x, v = bary[i].y, w0 = 1.0 - u - v;
        out.positions.push_back(pos[i]);
        const glm::dvec3 face =
            glm::cross(mesh.positions[ib] - mesh.positions[ia], mesh.positions[ic] - mesh.positions[ia]);
        glm::dvec3 n = glm::length(face) > 0.0 ? glm::normalize(face) : glm::dvec3(0, 0, 1);
        if (vertex_normals) {
            const glm::dvec3 vn = w0 * glm::dvec3(mesh.normals[ia]) + u * glm::dvec3(mesh.normals[ib]) +
                                  v * glm::dvec3(mesh.normals[ic]);
            if (glm::length(vn) > 1e-12) n = glm::normalize(vn);
        }
        out.normals.emplace_back(n);
        if (texture >= 0) {
            const glm::dvec2 ta(mesh.uvs[ia]), tb(mesh.uvs[ib]), tc(mesh.uvs[ic]);
            out.uvs.emplace_back(w0 * ta + u * tb + v * tc);
            glm::dvec3 gu, gv;
            triangle_uv_gradients(mesh.positions[ia], mesh.positions[ib], mesh.positions[ic], ta, tb, tc, gu,
                                  gv);
            out.uv_grad_u.emplace_back(gu);
            out.uv_grad_v.emplace_back(gv);
        }
        if (bake_colour) {
            glm::vec4 col(1.0f);
            if (!mesh.colors.empty())
                col = static_cast<float>(w0) * unpack_rgba(mesh.colors[ia]) +
                      static_cast<float>(u) * unpack_rgba(mesh.colors[ib]) +
                      static_cast<float>(v) * unpack_rgba(mesh.colors[ic]);
            const int m = mesh.triangle_material.empty() ? (mesh.materials.size() == 1 ? 0 : -1)
                                                         : mesh.triangle_material[t];
            if (m >= 0) {
                const MeshMaterial& mat = mesh.materials[static_cast<std::size_t>(m)];
                col *= mat.base_color;
                if (mat.texture >= 0 && !mesh.uvs.empty()) {
                    const glm::vec2 uv = static_cast<float>(w0) * mesh.uvs[ia] +
                                         static_cast<float>(u) * mesh.uvs[ib] +
                                         static_cast<float>(v) * mesh.uvs[ic];
                    col *= sample_texture(mesh.textures[static_cast<std::size_t>(mat.texture)], uv);
                }
            }
            out.colors.push_back(pack_rgba(col.x, col.y, col.z, col.w));
        }
    }
    return out;
}

}  // namespace sffd::assets
