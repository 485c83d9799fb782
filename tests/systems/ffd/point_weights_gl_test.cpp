// Per-point weights on the compute path (shaders/ffd/deform.comp with FFD_WEIGHTS): weights 0, 0.5, 1 and
// random ones against the double reference (weights_reference.h) and the CPU kernels to 1e-5; the system's
// GPU path uploads the weight column into the cloud's residency only while the cloud has weights, and a
// cloud without them runs the unweighted program (its output the same bytes as the deformer's without
// weights).
#include <gtest/gtest.h>

#include <cstring>
#include <optional>
#include <random>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/ffd_system.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/systems/ffd/weights_reference.h"
#include "tests/test_util/headless_gl.h"

namespace sffd {
namespace {

class PointWeightsGl : public test::HeadlessGlTest {};

struct Points {
    glm::dvec3 origin{0.25, -0.5, 0.125};
    std::vector<glm::vec3> p, n, u, v;
    std::vector<float> w;
};

Points weighted_points(const Lattice& l, std::size_t count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0.03, 0.97), dir(-1, 1);
    std::uniform_real_distribution<float> wr(0.0f, 1.0f);
    Points c;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 x = l.origin + u01(rng) * l.axes[0] + u01(rng) * l.axes[1] + u01(rng) * l.axes[2];
        glm::dvec3 nn;
        do nn = glm::dvec3(dir(rng), dir(rng), dir(rng));
        while (glm::length(nn) < 0.2);
        nn = glm::normalize(nn);
        const glm::dvec3 t =
            glm::normalize(glm::cross(nn, std::abs(nn.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        c.p.push_back(glm::vec3(x - c.origin));
        c.n.push_back(glm::vec3(nn));
        c.u.push_back(glm::vec3(t * 0.02));
        c.v.push_back(glm::vec3(glm::cross(nn, t) * 0.03));
        const std::size_t run = (i / 64) % 4;
        c.w.push_back(run == 0 ? 0.0f : run == 1 ? 0.5f : run == 2 ? 1.0f : (i % 9 == 4 ? 0.0f : wr(rng)));
    }
    return c;
}

struct Out {
    std::vector<glm::vec3> p, n, u, v;
    explicit Out(std::size_t k) : p(k), n(k), u(k), v(k) {}
    ffd::PointsOut out() { return {p.data(), n.data(), u.data(), v.data()}; }
};

TEST_F(PointWeightsGl, ComputePassBlendsLikeTheReferenceAndTheCpu) {
    std::optional<ffd::GpuDeformer> gpu;
    test::emplace_made(gpu, ffd::GpuDeformer::create());
    const Lattice l = ffd::test::weighted_test_lattice({4, 3, 5});
    const Points c = weighted_points(l, 3000, 3u);
    ffd::PointsIn in{c.p.data(), c.n.data(), c.u.data(), c.v.data(), c.p.size(), c.origin};
    in.weights = c.w.data();
    Out g(c.p.size()), f(c.p.size());
    auto gs = gpu->deform(l, in, g.out());
    ASSERT_TRUE(gs) << gs.message();
    ASSERT_TRUE(ffd::deform(l, in, f.out(), ffd::Backend::fast));
    double ref_p = 0, ref_n = 0, ref_a = 0, cpu = 0, disp = 0;
    for (std::size_t i = 0; i < c.p.size(); ++i) {
        const glm::dvec3 x = c.origin + glm::dvec3(c.p[i]);
        const ffd::test::WeightedRef r = ffd::test::weighted_bernstein(l, x, double(c.w[i]));
        if (c.w[i] == 0.0f) {  // copied unchanged by the pass
            ASSERT_EQ(std::memcmp(&g.p[i], &c.p[i], sizeof(glm::vec3)), 0) << i;
            ASSERT_EQ(std::memcmp(&g.n[i], &c.n[i], sizeof(glm::vec3)), 0) << i;
            ASSERT_EQ(std::memcmp(&g.u[i], &c.u[i], sizeof(glm::vec3)), 0) << i;
            continue;
        }
        disp = std::max(disp, glm::length(r.position - x));
        ref_p = std::max(ref_p, glm::length(c.origin + glm::dvec3(g.p[i]) - r.position));
        ref_n = std::max(ref_n, glm::length(glm::dvec3(g.n[i]) -
                                            ffd::test::ref_cofactor_normal(r.jacobian, glm::dvec3(c.n[i]))));
        const glm::dvec3 au = r.jacobian * glm::dvec3(c.u[i]);
        ref_a = std::max(ref_a, glm::length(glm::dvec3(g.u[i]) - au) / glm::length(au));
        for (const auto* a : {&g.p, &g.n, &g.u, &g.v}) {
            const auto* b = a == &g.p ? &f.p : a == &g.n ? &f.n : a == &g.u ? &f.u : &f.v;
            cpu = std::max(cpu, double(glm::length((*a)[i] - (*b)[i])));
        }
    }
    EXPECT_GT(disp, 0.1);
    EXPECT_LT(ref_p, 1e-5);
    EXPECT_LT(ref_n, 2e-5);
    EXPECT_LT(ref_a, 2e-5);
    EXPECT_LT(cpu, 1e-5);  // CPU and GPU agree
}

// What residency_system does: the authored splats as the cloud's `rest` buffer.
void upload_rest(ecs::Registry& reg, ecs::Entity e, const Points& c) {
    auto& store = reg.set_resource<gfx::GpuSplatStore>();
    gfx::GpuSplats& s = store.clouds[e];
    std::vector<gpu::GpuSplat> packed(c.p.size());
    for (std::size_t i = 0; i < c.p.size(); ++i)
        packed[i] = {{c.p[i].x, c.p[i].y, c.p[i].z, 0},
                     {c.n[i].x, c.n[i].y, c.n[i].z, 1},
                     {c.u[i].x, c.u[i].y, c.u[i].z, 0},
                     {c.v[i].x, c.v[i].y, c.v[i].z, 0}};
    s.rest = gfx::Buffer::create("test.rest");
    glNamedBufferData(s.rest.id(), GLsizeiptr(packed.size() * sizeof(gpu::GpuSplat)), packed.data(),
                      GL_STATIC_DRAW);
    s.count = std::uint32_t(c.p.size());
    s.rest_version = reg.version<SplatCloud>(e);
}

std::vector<gpu::GpuSplat> read_deformed(const gfx::GpuSplats& s) {
    std::vector<gpu::GpuSplat> back(s.count);
    glGetNamedBufferSubData(s.deformed.id(), 0, GLsizeiptr(back.size() * sizeof(gpu::GpuSplat)), back.data());
    return back;
}

TEST_F(PointWeightsGl, SystemUploadsTheWeightColumnOnlyWhileTheCloudHasOne) {
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_gpu = true;
    const Lattice l = ffd::test::weighted_test_lattice({4, 3, 5});
    const Points c = weighted_points(l, 2500, 8u);
    const ecs::Entity le = reg.create();
    reg.emplace<Lattice>(le, l);
    const ecs::Entity e = reg.create();
    SplatCloud sc;
    sc.origin = c.origin, sc.positions = c.p, sc.normals = c.n, sc.axis_u = c.u, sc.axis_v = c.v;
    reg.emplace<SplatCloud>(e, std::move(sc));
    reg.emplace<Deformers>(e, Deformers{{le}});
    reg.emplace<PointWeights>(e, PointWeights{c.w});
    upload_rest(reg, e, c);
    ffd_system(reg, {});
    gfx::GpuSplats& s = reg.resource<gfx::GpuSplatStore>().clouds[e];
    ASSERT_EQ(s.state, gfx::Residency::deformed_gpu);
    EXPECT_TRUE(bool(s.weights));
    const std::vector<gpu::GpuSplat> weighted = read_deformed(s);
    double worst = 0;
    for (std::size_t i = 0; i < c.p.size(); ++i) {
        const ffd::test::WeightedRef r =
            ffd::test::weighted_bernstein(l, c.origin + glm::dvec3(c.p[i]), double(c.w[i]));
        worst = std::max(worst, glm::length(c.origin +
                                            glm::dvec3(weighted[i].center[0], weighted[i].center[1],
                                                       weighted[i].center[2]) -
                                            r.position));
    }
    EXPECT_LT(worst, 1e-5);
    // Without weights: no buffer, the unweighted program, the deformer's own bytes without weights.
    reg.remove<PointWeights>(e);
    ffd_system(reg, {});
    EXPECT_FALSE(bool(s.weights));
    const std::vector<gpu::GpuSplat> plain = read_deformed(s);
    std::optional<ffd::GpuDeformer> gpu;
    test::emplace_made(gpu, ffd::GpuDeformer::create());
    Out g(c.p.size());
    ASSERT_TRUE(
        gpu->deform(l, {c.p.data(), c.n.data(), c.u.data(), c.v.data(), c.p.size(), c.origin}, g.out()));
    for (std::size_t i = 0; i < c.p.size(); ++i)
        ASSERT_EQ(std::memcmp(plain[i].center, &g.p[i], sizeof(glm::vec3)), 0) << i;
    ffd_release_gpu(reg);
    reg.erase_resource<gfx::GpuSplatStore>();
}

}  // namespace
}  // namespace sffd
