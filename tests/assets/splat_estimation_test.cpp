// Normals, orientation and radii against analytic shapes: PCA normals must match the true surface normal,
// orientation must make every normal of closed shapes (sphere, torus, two separate spheres) point
// outward, and the estimated discs must cover the whole surface (no holes).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/import.h"
#include "runtime/assets/splat_estimation.h"

using namespace sffd;
using namespace sffd::assets;

namespace {

glm::dvec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g(0.0, 1.0);
    glm::dvec3 v(g(rng), g(rng), g(rng));
    return glm::normalize(v);
}

// Torus around the y axis: major radius R, minor r. Returns point and outward normal.
std::pair<glm::dvec3, glm::dvec3> torus_point(double u, double v, double R, double r) {
    const glm::dvec3 centre(R * std::cos(u), 0.0, R * std::sin(u));
    const glm::dvec3 n(std::cos(v) * std::cos(u), std::sin(v), std::cos(v) * std::sin(u));
    return {centre + r * n, n};
}

// An icosphere mesh (subdivided icosahedron) of radius 1, for surface sampling.
Geometry icosphere(int levels) {
    Geometry g;
    g.source = "icosphere";
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<glm::dvec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::uint32_t> f = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                                    4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                                    6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
    for (auto& p : v) p = glm::normalize(p);
    for (int l = 0; l < levels; ++l) {
        std::vector<std::uint32_t> nf;
        for (std::size_t i = 0; i < f.size(); i += 3) {
            std::uint32_t m[3];
            for (int e = 0; e < 3; ++e) {
                v.push_back(glm::normalize(v[f[i + e]] + v[f[i + (e + 1) % 3]]));
                m[e] = static_cast<std::uint32_t>(v.size() - 1);
            }
            nf.insert(nf.end(),
                      {f[i], m[0], m[2], f[i + 1], m[1], m[0], f[i + 2], m[2], m[1], m[0], m[1], m[2]});
        }
        f = nf;
    }
    g.positions = v;
    g.triangles = f;
    return g;
}

// Fraction of probe points on the unit sphere not covered by any splat disc of `c`.
double uncovered_fraction(const SplatCloud& c, int probes, std::uint32_t seed) {
    std::mt19937 rng(seed);
    int missed = 0;
    for (int k = 0; k < probes; ++k) {
        const glm::dvec3 q = random_unit(rng);
        bool covered = false;
        for (std::size_t i = 0; i < c.size() && !covered; ++i) {
            const glm::dvec3 d = q - (c.origin + glm::dvec3(c.positions[i]));
            if (glm::dot(d, d) > 0.04) continue;
            // Ellipse test in the splat's own frame: (d.u/|u|^2)^2 + (d.v/|v|^2)^2 <= 1.
            const glm::dvec3 u(c.axis_u[i]), v(c.axis_v[i]);
            const double a = glm::dot(d, u) / glm::dot(u, u), b = glm::dot(d, v) / glm::dot(v, v);
            covered = a * a + b * b <= 1.0;
        }
        missed += covered ? 0 : 1;
    }
    return static_cast<double>(missed) / probes;
}

}  // namespace

TEST(SymmetricEigen, RecoversAKnownDecomposition) {
    std::mt19937 rng(3);
    for (int trial = 0; trial < 50; ++trial) {
        const glm::dvec3 axis = random_unit(rng);
        const glm::dmat3 r(glm::rotate(glm::dmat4(1.0), 0.3 + trial * 0.1, axis));
        const glm::dvec3 d(0.01 * (trial % 5), 1.0 + trial, 3.0 + 2.0 * trial);
        const glm::dmat3 a = r * glm::dmat3(d.x, 0, 0, 0, d.y, 0, 0, 0, d.z) * glm::transpose(r);
        glm::dvec3 values;
        glm::dmat3 vectors;
        symmetric_eigen(a, values, vectors);
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(values[i], d[i], 1e-9 * (1.0 + d.z));
            EXPECT_NEAR(std::abs(glm::dot(vectors[i], r[i])), 1.0, 1e-9);
        }
    }
}

TEST(PcaNormals, MatchAPlaneNormal) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    const glm::dvec3 n = glm::normalize(glm::dvec3(0.3, -0.2, 1.0));
    const glm::dvec3 t = glm::normalize(glm::cross(n, glm::dvec3(1, 0, 0)));
    const glm::dvec3 b = glm::cross(n, t);
    std::vector<glm::vec3> pts;
    for (int i = 0; i < 2000; ++i) pts.push_back(glm::vec3(u(rng) * t + u(rng) * b + glm::dvec3(4, 5, 6)));
    const Neighbours nb = find_neighbours(pts, 16);
    auto normals = pca_normals(pts, nb);
    orient_normals(pts, nb, normals);
    for (const auto& m : normals) EXPECT_GT(glm::dot(glm::dvec3(m), n), 0.9999);  // seed turns to +z, n.z > 0
}

TEST(Orientation, EveryNormalOfClosedShapesPointsOutward) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
    std::vector<glm::vec3> pts;
    std::vector<glm::dvec3> truth;
    // Two separate spheres (two graph components) and a torus (not star-shaped: a "point away from
    // the centre" rule would fail on its inner side).
    for (const glm::dvec3 c : {glm::dvec3(-3, 0, 0), glm::dvec3(3, 1, 0)})
        for (int i = 0; i < 4000; ++i) {
            const glm::dvec3 d = random_unit(rng);
            pts.push_back(glm::vec3(c + d));
            truth.push_back(d);
        }
    for (int i = 0; i < 12000; ++i) {
        // Area-uniform torus samples (rejection on the minor angle).
        double v = angle(rng);
        while (std::uniform_real_distribution<double>(0, 1.6)(rng) > 1.0 + 0.6 * std::cos(v)) v = angle(rng);
        auto [p, n] = torus_point(angle(rng), v, 1.0, 0.4);
        pts.push_back(glm::vec3(p + glm::dvec3(0, 0, 6)));
        truth.push_back(n);
    }
    const Neighbours nb = find_neighbours(pts, 16);
    auto normals = pca_normals(pts, nb);
    orient_normals(pts, nb, normals);
    std::size_t wrong = 0, imprecise = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double d = glm::dot(glm::dvec3(normals[i]), truth[i]);
        wrong += d < 0.0;
        imprecise += d < 0.95;
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_LT(imprecise, pts.size() / 200);
}

TEST(Radii, SampledSphereSurfaceHasNoHoles) {
    // The import pipeline on a mesh: blue-noise surface samples, face normals, kNN radii.
    const Geometry mesh = icosphere(3);
    ImportOptions opt;
    opt.splats = 3000;
    auto cloud = make_splat_cloud(mesh, opt);
    ASSERT_TRUE(cloud.ok()) << cloud.message();
    ASSERT_EQ(cloud->size(), 3000u);
    EXPECT_EQ(uncovered_fraction(*cloud, 20000, 1), 0.0);
    // Radii stay local: no disc larger than a few sample spacings (sqrt(area / N) ~ 0.065).
    for (const auto& a : cloud->axis_u) EXPECT_LT(glm::length(a), 0.2f);
}

TEST(Radii, RawRandomPointsGetNormalsAndCloseTheSurface) {
    // Raw points (no faces, no normals): PCA + orientation + radii, the path a scanned PLY takes.
    std::mt19937 rng(17);
    Geometry g;
    g.source = "random sphere";
    for (int i = 0; i < 4000; ++i) g.positions.push_back(random_unit(rng));
    auto cloud = make_splat_cloud(g, {});
    ASSERT_TRUE(cloud.ok()) << cloud.message();
    for (std::size_t i = 0; i < cloud->size(); ++i)
        ASSERT_GT(glm::dot(glm::normalize(glm::dvec3(cloud->positions[i])), glm::dvec3(cloud->normals[i])),
                  0.9)
            << i;
    // Uniform random points have clumps and gaps; the 6th-neighbour radius still leaves (almost) none.
    EXPECT_LT(uncovered_fraction(*cloud, 20000, 2), 1e-3);
}

TEST(Radii, BuiltinSphereIsClosedAndAxesFollowTheTexture) {
    const SplatCloud s = make_sphere_cloud(20000);
    EXPECT_EQ(uncovered_fraction(s, 20000, 3), 0.0);
    for (std::size_t i = 0; i < s.size(); i += 97) {
        const glm::dvec3 p(s.positions[i]);
        // axis_u points along increasing longitude u = atan2(z, x) / 2pi.
        const glm::dvec3 east = glm::normalize(glm::cross(p, glm::dvec3(0, 1, 0)));
        if (glm::length(glm::cross(p, glm::dvec3(0, 1, 0))) > 0.05) {
            EXPECT_GT(glm::dot(glm::normalize(glm::dvec3(s.axis_u[i])), east), 0.999);
        }
        EXPECT_NEAR(glm::dot(glm::dvec3(s.axis_u[i]), p), 0.0, 1e-6);
        EXPECT_NEAR(glm::dot(glm::dvec3(s.axis_v[i]), p), 0.0, 1e-6);
    }
}
