#include "runtime/assets/splat_estimation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/assets/point_tree.h"
#include "runtime/scene/sym_eigen.h"

namespace sffd::assets {

Neighbours find_neighbours(std::span<const glm::vec3> points, int k, const ProgressFn& progress) {
    Neighbours nb;
    nb.k = k;
    const std::size_t n = points.size();
    nb.index.assign(n * static_cast<std::size_t>(k), 0);
    nb.dist2.assign(n * static_cast<std::size_t>(k), 0.0f);
    if (n < 2 || k <= 0) return nb;
    ProgressCounter counter(progress, "finding neighbours", n);
    const detail::PointTree<glm::vec3> tree(points);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
            counter.add(r.size());
            std::vector<std::uint32_t> idx(static_cast<std::size_t>(k) + 1);
            std::vector<float> d2(static_cast<std::size_t>(k) + 1);
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const float q[3] = {points[i].x, points[i].y, points[i].z};
                const std::size_t found = tree.knn(q, static_cast<std::size_t>(k) + 1, idx.data(), d2.data());
                std::size_t out = 0;
                std::uint32_t last = static_cast<std::uint32_t>(i == 0 ? 1 : 0);
                float last_d = 0.0f;
                for (std::size_t j = 0; j < found && out < static_cast<std::size_t>(k); ++j) {
                    if (idx[j] == i) continue;
                    nb.index[i * k + out] = idx[j];
                    nb.dist2[i * k + out] = d2[j];
                    last = idx[j];
                    last_d = d2[j];
                    ++out;
                }
                for (; out < static_cast<std::size_t>(k); ++out) {
                    nb.index[i * k + out] = last;
                    nb.dist2[i * k + out] = last_d;
                }
            }
        });
    counter.done();
    return nb;
}

void symmetric_eigen(const glm::dmat3& input, glm::dvec3& values, glm::dmat3& vectors) {
    // Stops once the off-diagonal mass is 1e-30 of the diagonal's (or exactly zero); skips only exact zeros.
    constexpr double zero_only = std::numeric_limits<double>::denorm_min();  // |x| < denorm_min ⇔ x == 0
    const JacobiRule rule{.max_sweeps = 50,
                          .relative = 1e-30,
                          .relative_to_diagonal = true,
                          .floor = zero_only,
                          .skip_below = zero_only};
    const Eigen3 e = jacobi_eigen(input, glm::dmat3(1.0), rule, EigenOrder::ascending);
    values = e.values;
    vectors = e.vectors;
}

std::vector<glm::vec3> pca_normals(std::span<const glm::vec3> points, const Neighbours& nb,
                                   const ProgressFn& progress) {
    std::vector<glm::vec3> normals(points.size(), glm::vec3(0, 0, 1));
    const std::size_t k = static_cast<std::size_t>(nb.k);
    ProgressCounter counter(progress, "estimating normals", points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          counter.add(r.size());
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              glm::dvec3 mean(points[i]);
                              for (std::size_t j = 0; j < k; ++j)
                                  mean += glm::dvec3(points[nb.index[i * k + j]]);
                              mean /= static_cast<double>(k + 1);
                              glm::dmat3 cov(0.0);
                              auto add = [&](const glm::vec3& p) {
                                  const glm::dvec3 d = glm::dvec3(p) - mean;
                                  cov += glm::outerProduct(d, d);
                              };
                              add(points[i]);
                              for (std::size_t j = 0; j < k; ++j) add(points[nb.index[i * k + j]]);
                              glm::dvec3 values;
                              glm::dmat3 vectors;
                              symmetric_eigen(cov, values, vectors);
                              if (values[2] <= 0.0) continue;  // all neighbours coincide
                              const glm::dvec3 n = vectors[0];
                              const double len = glm::length(n);
                              if (len > 0.0 && std::isfinite(len)) normals[i] = glm::vec3(n / len);
                          }
                      });
    counter.done();
    return normals;
}

void orient_normals(std::span<const glm::vec3> points, const Neighbours& nb, std::span<glm::vec3> normals,
                    const ProgressFn& progress) {
    const std::size_t n = points.size();
    const std::size_t k = static_cast<std::size_t>(nb.k);
    if (n == 0) return;
    // Symmetric adjacency (CSR): the k-NN relation is not symmetric, the tree must be able to use both.
    std::vector<std::uint32_t> degree(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < k; ++j) {
            const std::uint32_t o = nb.index[i * k + j];
            if (o == i) continue;
            ++degree[i + 1];
            ++degree[o + 1];
        }
    for (std::size_t i = 0; i < n; ++i) degree[i + 1] += degree[i];
    std::vector<std::uint32_t> adj(degree[n]);
    std::vector<std::uint32_t> fill(degree.begin(), degree.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < k; ++j) {
            const std::uint32_t o = nb.index[i * k + j];
            if (o == i) continue;
            adj[fill[i]++] = o;
            adj[fill[o]++] = static_cast<std::uint32_t>(i);
        }

    // Seeds in order of decreasing z: the first unvisited one starts a new component.
    std::vector<std::uint32_t> by_z(n);
    for (std::size_t i = 0; i < n; ++i) by_z[i] = static_cast<std::uint32_t>(i);
    std::sort(by_z.begin(), by_z.end(),
              [&](std::uint32_t a, std::uint32_t b) { return points[a].z > points[b].z; });

    ProgressCounter counter(progress, "orienting normals", n);
    std::size_t visited = 0;
    std::vector<char> done(n, 0);
    using Item = std::pair<float, std::pair<std::uint32_t, std::uint32_t>>;  // weight, (parent, node)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    for (std::uint32_t seed : by_z) {
        if (done[seed]) continue;
        if (normals[seed].z < 0.0f) normals[seed] = -normals[seed];
        heap.push({0.0f, {seed, seed}});
        while (!heap.empty()) {
            const auto [w, edge] = heap.top();
            heap.pop();
            const auto [parent, node] = edge;
            if (done[node]) continue;
            done[node] = 1;
            if (++visited % 4096 == 0) counter.add(4096);
            if (node != parent && glm::dot(normals[node], normals[parent]) < 0.0f)
                normals[node] = -normals[node];
            for (std::uint32_t e = degree[node]; e < degree[node + 1]; ++e) {
                const std::uint32_t o = adj[e];
                if (!done[o]) heap.push({1.0f - std::abs(glm::dot(normals[node], normals[o])), {node, o}});
            }
        }
    }
    counter.done();
}

std::vector<float> estimate_radii(const Neighbours& nb, int kth, float scale) {
    const std::size_t n = nb.k > 0 ? nb.index.size() / static_cast<std::size_t>(nb.k) : 0;
    std::vector<float> radii(n, 0.0f);
    if (n == 0) return radii;
    kth = std::clamp(kth, 1, nb.k);
    for (std::size_t i = 0; i < n; ++i)
        radii[i] = scale * std::sqrt(nb.dist2[i * nb.k + static_cast<std::size_t>(kth - 1)]);
    std::vector<float> sorted = radii;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(n / 2), sorted.end());
    const float median = sorted[n / 2];
    if (median > 0.0f)
        for (float& r : radii) r = std::clamp(r, 0.25f * median, 4.0f * median);
    return radii;
}

glm::vec3 any_tangent(const glm::vec3& n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    return glm::vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

void make_circular_axes(std::span<const glm::vec3> normals, std::span<const float> radii,
                        std::vector<glm::vec3>& axis_u, std::vector<glm::vec3>& axis_v) {
    axis_u.resize(normals.size());
    axis_v.resize(normals.size());
    for (std::size_t i = 0; i < normals.size(); ++i) {
        const glm::vec3 t = glm::normalize(any_tangent(normals[i]));
        const glm::vec3 b = glm::normalize(glm::cross(normals[i], t));
        axis_u[i] = t * radii[i];
        axis_v[i] = b * radii[i];
    }
}

void estimate_splats(SplatCloud& cloud, const EstimateOptions& options) {
    const bool want_normals = options.normals || (options.radii && cloud.normals.size() != cloud.size());
    if (!want_normals && !options.radii) return;
    const int k = std::max(options.k, 8);
    const Neighbours nb = find_neighbours(cloud.positions, k, options.progress);
    if (want_normals) {
        cloud.normals = pca_normals(cloud.positions, nb, options.progress);
        orient_normals(cloud.positions, nb, cloud.normals, options.progress);
    }
    if (options.radii) {
        report_progress(options.progress, "splat radii and axes", 0.0);
        const std::vector<float> radii = estimate_radii(nb, 6, 1.0f);
        make_circular_axes(cloud.normals, radii, cloud.axis_u, cloud.axis_v);
        report_progress(options.progress, "splat radii and axes", 1.0);
    }
}

}  // namespace sffd::assets
