// Splat estimation for raw points: k nearest neighbours
// (nanoflann k-d tree), normals by PCA of the neighbourhood, consistent orientation, splat radii from
// neighbour spacing, and tangent axes.
//
// Orientation (Hoppe et al. 1992): PCA gives each normal only up to sign. We build the symmetric k-NN
// graph, weight edge (i, j) by 1 - |n_i . n_j| (nearly parallel normals = cheap), and grow a minimum
// spanning tree with Prim's algorithm from a seed per connected component; each normal is flipped to
// agree with its tree parent. The seed is the component's point with the largest z, whose normal is
// turned to +z: on a closed surface the extreme point's outward normal points away from the shape, so
// the whole component ends up facing outward. Sharp creases thinner than the neighbourhood can still
// flip a region; meshes keep their face normals instead (import.cpp).
//
// Radii: radius_i = scale * distance to the k_r-th nearest neighbour (k_r = 6 by default), clamped to
// 4x the cloud's median radius so isolated outliers do not become huge discs. For samples of roughly
// even density this makes neighbouring discs overlap, so the rendered surface closes (the coverage test
// in tests/assets/splat_estimation_test.cpp checks that every point of a sampled sphere lies on a disc).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/progress.h"
#include "runtime/scene/components.h"

namespace sffd::assets {

// k nearest neighbours of every point (excluding the point itself), row i = entries [i*k, (i+1)*k),
// nearest first. Rows of clouds with fewer than k+1 points are padded with the last found neighbour.
struct Neighbours {
    int k = 0;
    std::vector<std::uint32_t> index;
    std::vector<float> dist2;
};

Neighbours find_neighbours(std::span<const glm::vec3> points, int k, const ProgressFn& progress = {});

// Unit normals by PCA (eigenvector of the smallest eigenvalue of the neighbourhood covariance), not yet
// oriented. Degenerate neighbourhoods (all points equal) get (0, 0, 1).
std::vector<glm::vec3> pca_normals(std::span<const glm::vec3> points, const Neighbours& nb,
                                   const ProgressFn& progress = {});

// Flips normals in place so that they agree along a minimum spanning tree of the k-NN graph (see above).
void orient_normals(std::span<const glm::vec3> points, const Neighbours& nb, std::span<glm::vec3> normals,
                    const ProgressFn& progress = {});

// Splat radius per point from neighbour spacing (see above). `kth` <= nb.k.
std::vector<float> estimate_radii(const Neighbours& nb, int kth = 6, float scale = 1.0f);

// Circular splats: axis_u, axis_v = orthonormal tangent basis of each normal scaled by the radius.
void make_circular_axes(std::span<const glm::vec3> normals, std::span<const float> radii,
                        std::vector<glm::vec3>& axis_u, std::vector<glm::vec3>& axis_v);

// A unit vector perpendicular to n (stable for every direction; Duff et al. 2017 basis).
glm::vec3 any_tangent(const glm::vec3& n);

// Symmetric 3x3 eigen-decomposition (Jacobi): eigenvalues ascending, eigenvectors as columns.
void symmetric_eigen(const glm::dmat3& a, glm::dvec3& values, glm::dmat3& vectors);

struct EstimateOptions {
    bool normals = true;  // estimate normals (PCA + orientation)
    bool radii = true;    // estimate radii and axes
    int k = 16;           // neighbourhood for PCA and orientation
    ProgressFn progress;  // each step's progress (splatffd convert prints it); may be empty
};

// Fills normals / axis_u / axis_v of `cloud` as requested (normals also when missing and radii wanted).
void estimate_splats(SplatCloud& cloud, const EstimateOptions& options);

}  // namespace sffd::assets
