// The naive paper deformer against independent references: trilinear interpolation (1x1x1 lattice),
// affine maps (positions by the map, normals by its inverse transpose), identity, finite differences.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "systems/profiling/paper_ffd.h"

namespace sffd::profiling {
namespace {

SplatCloud random_cloud(std::size_t n, unsigned seed, glm::dvec3 origin = glm::dvec3(0.0)) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    SplatCloud c;
    c.origin = origin;
    for (std::size_t i = 0; i < n; ++i) {
        c.positions.emplace_back(u(rng), u(rng) * 0.5f, u(rng) * 2.0f);
        c.normals.push_back(glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0, 0.01f)));
    }
    return c;
}

void expect_near(glm::vec3 a, glm::vec3 b, float tol, const char* what, std::size_t i) {
    EXPECT_NEAR(a.x, b.x, tol) << what << " " << i;
    EXPECT_NEAR(a.y, b.y, tol) << what << " " << i;
    EXPECT_NEAR(a.z, b.z, tol) << what << " " << i;
}

TEST(PaperFfd, LatticeEnclosesTheCloudWith11CubedControlPoints) {
    const SplatCloud c = random_cloud(500, 1, glm::dvec3(1e6, 0, -3));
    const Lattice l = paper_lattice(c);
    EXPECT_EQ(l.size(), 1331u);
    EXPECT_EQ(l.rest.size(), 1331u);
    for (const auto& p : c.positions) {
        const glm::dvec3 d = c.origin + glm::dvec3(p) - l.origin;
        for (int a = 0; a < 3; ++a) {
            EXPECT_GT(d[a], 0.0);
            EXPECT_LT(d[a], l.axes[a][a]);
        }
    }
    // Rest control point (i,j,k) = X0 + i/l S + j/m T + k/n U (ffd-math.md, not the paper's eq. 5).
    const glm::dvec3 p = l.rest[l.index(3, 7, 9)];
    const glm::dvec3 want = l.origin + 0.3 * l.axes[0] + 0.7 * l.axes[1] + 0.9 * l.axes[2];
    EXPECT_NEAR(glm::length(p - want), 0.0, 1e-9);
}

TEST(PaperFfd, RestLatticeIsTheIdentity) {
    const SplatCloud c = random_cloud(200, 2, glm::dvec3(1e5, 2e5, 0));
    const Lattice l = paper_lattice(c, 6);
    std::vector<glm::vec3> pos, nrm;
    paper_ffd_naive(l, c, pos, nrm);
    for (std::size_t i = 0; i < c.size(); ++i) {
        expect_near(pos[i], c.positions[i], 2e-5f, "position", i);
        expect_near(nrm[i], c.normals[i], 1e-5f, "normal", i);
    }
}

TEST(PaperFfd, OneCellLatticeIsTrilinearInterpolationOfItsCorners) {
    SplatCloud c = random_cloud(100, 3);
    Lattice l = paper_lattice(c, 1);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    for (auto& p : l.current) p += glm::dvec3(u(rng), u(rng), u(rng));
    std::vector<glm::vec3> pos, nrm;
    paper_ffd_naive(l, c, pos, nrm);
    for (std::size_t n = 0; n < c.size(); ++n) {
        const glm::dvec3 d = glm::dvec3(c.positions[n]) - l.origin;
        const double s = d.x / l.axes[0].x, t = d.y / l.axes[1].y, w = d.z / l.axes[2].z;
        glm::dvec3 want(0.0);
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2; ++j)
                for (int k = 0; k < 2; ++k)
                    want +=
                        l.current[l.index(i, j, k)] * ((i ? s : 1 - s) * (j ? t : 1 - t) * (k ? w : 1 - w));
        expect_near(pos[n], glm::vec3(want), 1e-5f, "trilinear", n);
    }
}

TEST(PaperFfd, AffineControlPointsMoveNormalsByInverseTranspose) {
    const SplatCloud c = random_cloud(150, 5);
    Lattice l = paper_lattice(c, 4);
    // A shear + anisotropic scale + rotation-ish linear map A and a translation b.
    const glm::dmat3 A(glm::dvec3(1.3, 0.2, 0.0), glm::dvec3(-0.4, 0.8, 0.1), glm::dvec3(0.3, 0.0, 1.7));
    const glm::dvec3 b(0.5, -2.0, 1.0);
    for (std::size_t i = 0; i < l.size(); ++i) l.current[i] = A * l.rest[i] + b;
    std::vector<glm::vec3> pos, nrm;
    paper_ffd_naive(l, c, pos, nrm);
    const glm::dmat3 inv_t = glm::transpose(glm::inverse(A));
    for (std::size_t i = 0; i < c.size(); ++i) {
        expect_near(pos[i], glm::vec3(A * glm::dvec3(c.positions[i]) + b), 2e-5f, "position", i);
        expect_near(nrm[i], glm::vec3(glm::normalize(inv_t * glm::dvec3(c.normals[i]))), 2e-5f, "normal", i);
    }
}

TEST(PaperFfd, NormalsMatchFiniteDifferencesOfTheDeformation) {
    SplatCloud c = random_cloud(20, 6);
    Lattice l = paper_lattice(c, 5);
    apply_paper_case(l, paper_cases[1], 1.0);  // local twist: a genuinely non-linear deformation
    std::vector<glm::vec3> pos, nrm;
    paper_ffd_naive(l, c, pos, nrm);
    const double h = 1e-3;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 n = glm::dvec3(c.normals[i]);
        const glm::dvec3 a =
            glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        const glm::dvec3 bt = glm::cross(n, a);
        // Deform p +- h a and p +- h b with the same deformer (central differences).
        SplatCloud probe;
        const glm::dvec3 p = glm::dvec3(c.positions[i]);
        for (glm::dvec3 off : {a * h, -a * h, bt * h, -bt * h}) {
            probe.positions.push_back(glm::vec3(p + off));
            probe.normals.push_back(glm::vec3(n));
        }
        std::vector<glm::vec3> pp, pn;
        paper_ffd_naive(l, probe, pp, pn);
        const glm::dvec3 da = glm::dvec3(pp[0]) - glm::dvec3(pp[1]),
                         db = glm::dvec3(pp[2]) - glm::dvec3(pp[3]);
        const glm::dvec3 want = glm::normalize(glm::cross(da, db));
        EXPECT_GT(glm::dot(want, glm::dvec3(nrm[i])), 0.999) << i;
    }
}

TEST(PaperFfd, CasesMoveTheirSelectionOnly) {
    const SplatCloud c = random_cloud(10, 7);
    Lattice l = paper_lattice(c);
    for (const auto& pc : paper_cases) {
        const auto sel = paper_case_selection(l, pc);
        EXPECT_EQ(sel.size(), pc.local ? 5u * 5u * 3u : 1331u) << pc.name;
        apply_paper_case(l, pc, 1.0);
        std::size_t moved = 0;
        for (std::size_t i = 0; i < l.size(); ++i) moved += glm::length(l.current[i] - l.rest[i]) > 1e-12;
        // A twist leaves the control points on its axis in place.
        if (pc.twist) EXPECT_LE(moved, sel.size()) << pc.name;
        else EXPECT_EQ(moved, sel.size()) << pc.name;
        EXPECT_GT(moved, sel.size() / 2) << pc.name;
        apply_paper_case(l, pc, 0.0);
        for (std::size_t i = 0; i < l.size(); ++i) EXPECT_EQ(l.current[i], l.rest[i]);
    }
}

TEST(PaperFfd, PointsOutsideTheLatticeAreCopied) {
    SplatCloud c = random_cloud(10, 8);
    Lattice l = paper_lattice(c, 3);
    for (auto& p : l.current) p += glm::dvec3(1, 2, 3);
    c.positions.push_back(glm::vec3(50, 0, 0));
    c.normals.push_back(glm::vec3(0, 1, 0));
    std::vector<glm::vec3> pos, nrm;
    paper_ffd_naive(l, c, pos, nrm);
    EXPECT_EQ(pos.back(), glm::vec3(50, 0, 0));
    EXPECT_EQ(nrm.back(), glm::vec3(0, 1, 0));
    expect_near(pos[0], c.positions[0] + glm::vec3(1, 2, 3), 1e-5f, "translated", 0);
}

}  // namespace
}  // namespace sffd::profiling
