// One frame of reference for clouds and lattices (systems/ffd/lattice_frame.h): a lattice deforms what
// lies inside it in the world, through both entities' Transforms. For surface splats and Gaussians, a
// moved cloud, a moved lattice and both moved (translation, rotation, non-uniform scale), each with the
// lattice at rest, stretched and twisted: the deformed world positions (and normals, axes, covariances)
// equal the double-precision reference run in the world on the world-space points with the world-space
// lattice (built here by hand, not by the code under test); every CPU backend agrees; moving either
// entity re-deforms; the world bounds hold every deformed splat; picking hits the deformed surface where
// it is; the editor's overlay shows the control points where the deformation uses them; a saved scene
// keeps both Transforms.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <optional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "runtime/app/frame_loop.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/picking/picking_system.h"
#include "tests/systems/ffd/test_util.h"

using namespace sffd;

namespace {

constexpr glm::dvec3 kOrigin{0.2, -0.1, 0.3};  // the cloud's SplatCloud::origin (points relative to it)

Transform make_transform(glm::dvec3 t, glm::dvec3 axis, double angle, glm::dvec3 s) {
    Transform x;
    x.translation = t;
    x.rotation = glm::angleAxis(angle, glm::normalize(axis));
    x.scale = s;
    return x;
}
// Small enough moves that the lattice still holds part of the cloud (the far case has its own test).
const Transform kCloudT = make_transform({0.6, -0.3, 0.4}, {1, 2, 3}, 0.7, {1.3, 0.8, 1.1});
const Transform kLatticeT = make_transform({-0.3, 0.5, 0.2}, {0, 1, 1}, -0.5, {0.9, 1.2, 1.05});

struct Placement {
    const char* name;
    std::optional<Transform> cloud, lattice;
};
const Placement kPlacements[] = {
    {"cloud moved", kCloudT, std::nullopt},
    {"lattice moved", std::nullopt, kLatticeT},
    {"both moved", kCloudT, kLatticeT},
};

enum class Edit { rest, stretch, twist };
const Edit kEdits[] = {Edit::rest, Edit::stretch, Edit::twist};
const char* edit_name(Edit e) { return e == Edit::rest ? "rest" : e == Edit::stretch ? "stretch" : "twist"; }

// A 3x3x3 lattice around the cloud's sphere (radius 1 about kOrigin), in the lattice entity's own frame.
Lattice edited_lattice(Edit edit, LatticeBasis basis = LatticeBasis::bernstein) {
    Lattice l =
        make_lattice(kOrigin - glm::dvec3(1.1),
                     {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {3, 3, 3}, basis);
    for (int i = 0; i <= 3; ++i)
        for (int j = 0; j <= 3; ++j)
            for (int k = 0; k <= 3; ++k) {
                glm::dvec3& p = l.current[l.index(i, j, k)];
                const glm::dvec3 d = p - kOrigin;
                if (edit == Edit::stretch && i == 3) p.x += 0.6;  // the +x layer pulled out
                if (edit == Edit::twist) {
                    const double a = 0.9 * (double(j) / 3.0 - 0.5);  // about y, growing with height
                    p = kOrigin + glm::dvec3(std::cos(a) * d.x + std::sin(a) * d.z, d.y,
                                             -std::sin(a) * d.x + std::cos(a) * d.z);
                }
            }
    return l;
}

SplatCloud sphere_cloud(std::size_t n = 1500) {
    const ffd::test::Cloud c = ffd::test::fibonacci_sphere(n, 1.0, 0.02);
    SplatCloud s;
    s.origin = kOrigin;
    s.positions = c.p, s.normals = c.n, s.axis_u = c.u, s.axis_v = c.v;
    return s;
}

// The reference's world lattice, by hand: origin and control points through the affine map, axes
// through its linear part.
Lattice world_lattice(const Lattice& l, const glm::dmat4& m) {
    Lattice w = l;
    auto pt = [&](const glm::dvec3& p) { return glm::dvec3(m * glm::dvec4(p, 1.0)); };
    w.origin = pt(l.origin);
    for (auto& a : w.axes) a = glm::dvec3(m * glm::dvec4(a, 0.0));
    for (auto& p : w.rest) p = pt(p);
    for (auto& p : w.current) p = pt(p);
    return w;
}

// The reference result of authored point (local, cloud frame incl. origin): its world position and its
// Jacobian in the cloud's frame, C⁻¹ J_world C.
struct Expected {
    glm::dvec3 world;
    glm::dmat3 jacobian_local;
};
Expected expected(const Lattice& world, const glm::dmat4& c, const glm::dvec3& local) {
    const ffd::ReferencePoint r = ffd::reference_point(world, glm::dvec3(c * glm::dvec4(local, 1.0)));
    const glm::dmat3 cl(c);
    return {r.position, glm::inverse(cl) * r.jacobian * cl};
}

struct Scene {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
};
template <class Cloud>
void build(Scene& s, Cloud cloud, const Placement& p, Edit edit,
           LatticeBasis basis = LatticeBasis::bernstein) {
    s.reg.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    s.cloud = s.reg.create();
    s.reg.emplace<Cloud>(s.cloud, std::move(cloud));
    if (p.cloud) s.reg.emplace<Transform>(s.cloud, *p.cloud);
    s.lattice = s.reg.create();
    s.reg.emplace<Lattice>(s.lattice, edited_lattice(edit, basis));
    if (p.lattice) s.reg.emplace<Transform>(s.lattice, *p.lattice);
    s.reg.emplace<Deformers>(s.cloud, Deformers{{s.lattice}});
}

void run(Scene& s) {
    ffd_system(s.reg, FrameContext{});
    gaussian_deform_system(s.reg, FrameContext{});
}

// Largest distance between the splats' world positions and the reference's, over the cloud's size.
void expect_splats_match_reference(const Scene& s, const std::string& what) {
    const SplatCloud& a = s.reg.get<SplatCloud>(s.cloud);
    const DeformedSplats& d = s.reg.get<DeformedSplats>(s.cloud);
    ASSERT_TRUE(d.cpu_valid) << what;
    ASSERT_EQ(d.positions.size(), a.size()) << what;
    const glm::dmat4 c = model_matrix(s.reg.try_get<Transform>(s.cloud));
    const Lattice world =
        world_lattice(s.reg.get<Lattice>(s.lattice), model_matrix(s.reg.try_get<Transform>(s.lattice)));
    double worst_p = 0, worst_n = 0, worst_u = 0;
    std::size_t moved = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Expected e = expected(world, c, a.origin + glm::dvec3(a.positions[i]));
        const glm::dvec3 got = glm::dvec3(c * glm::dvec4(d.origin + glm::dvec3(d.positions[i]), 1.0));
        worst_p = std::max(worst_p, glm::length(got - e.world));
        moved += glm::length(d.positions[i] - a.positions[i]) > 1e-3f;
        const glm::dvec3 n =
            glm::normalize(glm::transpose(glm::inverse(e.jacobian_local)) * glm::dvec3(a.normals[i]));
        worst_n = std::max(worst_n, glm::length(glm::dvec3(d.normals[i]) - n));
        const glm::dvec3 u = e.jacobian_local * glm::dvec3(a.axis_u[i]);
        worst_u = std::max(worst_u, glm::length(glm::dvec3(d.axis_u[i]) - u) / glm::length(u));
    }
    EXPECT_LT(worst_p, 2e-5) << what;
    EXPECT_LT(worst_n, 1e-4) << what;
    EXPECT_LT(worst_u, 1e-4) << what;
    // The world bounds (the renderer's screen rectangle reads them) hold every deformed splat.
    for (std::size_t i = 0; i < a.size(); ++i) {
        const glm::dvec3 w = glm::dvec3(c * glm::dvec4(d.origin + glm::dvec3(d.positions[i]), 1.0));
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(w, d.bounds_min - 1e-9)) &&
                    glm::all(glm::lessThanEqual(w, d.bounds_max + 1e-9)))
            << what << ": splat " << i << " outside the world bounds";
    }
    if (s.reg.get<Lattice>(s.lattice).current == s.reg.get<Lattice>(s.lattice).rest) {
        EXPECT_EQ(moved, 0u) << what;  // at rest: nothing moves
        for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_EQ(d.positions[i], a.positions[i]) << what << ": a lattice at rest moved splat " << i;
    } else {
        EXPECT_GT(moved, a.size() / 10) << what << ": the edit should move a good part of the cloud";
    }
}

void expect_gaussians_match_reference(const Scene& s, const std::string& what) {
    const GaussianCloud& a = s.reg.get<GaussianCloud>(s.cloud);
    const DeformedGaussians& d = s.reg.get<DeformedGaussians>(s.cloud);
    ASSERT_FALSE(gaussian::output_on_gpu(s.reg, s.cloud)) << what;
    ASSERT_EQ(d.cloud.size(), a.size()) << what;
    const glm::dmat4 c = model_matrix(s.reg.try_get<Transform>(s.cloud));
    const Lattice world =
        world_lattice(s.reg.get<Lattice>(s.lattice), model_matrix(s.reg.try_get<Transform>(s.lattice)));
    double worst_p = 0, worst_cov = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Expected e = expected(world, c, a.origin + glm::dvec3(a.positions[i]));
        const glm::dvec3 got =
            glm::dvec3(c * glm::dvec4(d.cloud.origin + glm::dvec3(d.cloud.positions[i]), 1.0));
        worst_p = std::max(worst_p, glm::length(got - e.world));
        const glm::dmat3 sigma = gaussian::covariance(glm::dvec3(a.scales[i]), glm::dquat(a.rotations[i]));
        const glm::dmat3 want = e.jacobian_local * sigma * glm::transpose(e.jacobian_local);
        const glm::dmat3 have =
            gaussian::covariance(glm::dvec3(d.cloud.scales[i]), glm::dquat(d.cloud.rotations[i]));
        double err = 0, norm = 0;
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k)
                err = std::max(err, std::abs(have[r][k] - want[r][k])),
                norm = std::max(norm, std::abs(want[r][k]));
        worst_cov = std::max(worst_cov, err / norm);
    }
    EXPECT_LT(worst_p, 2e-5) << what;
    EXPECT_LT(worst_cov, 1e-4) << what;
}

}  // namespace

TEST(TransformFrame, SplatsDeformInTheWorldThroughBothTransformsForEveryPlacementAndEdit) {
    for (const Placement& p : kPlacements)
        for (Edit edit : kEdits) {
            Scene s;
            build(s, sphere_cloud(), p, edit);
            run(s);
            expect_splats_match_reference(s, std::string(p.name) + ", " + edit_name(edit));
        }
}

TEST(TransformFrame, BSplineLatticeDeformsInTheWorldToo) {
    for (Edit edit : {Edit::stretch, Edit::twist}) {
        Scene s;
        build(s, sphere_cloud(), kPlacements[2], edit, LatticeBasis::bspline);
        run(s);
        expect_splats_match_reference(s, std::string("bspline, both moved, ") + edit_name(edit));
    }
}

TEST(TransformFrame, GaussiansDeformInTheWorldThroughBothTransformsForEveryPlacementAndEdit) {
    for (const Placement& p : kPlacements)
        for (Edit edit : kEdits) {
            Scene s;
            build(s, gaussian::gaussians_from_splats(sphere_cloud()), p, edit);
            run(s);
            expect_gaussians_match_reference(s, std::string(p.name) + ", " + edit_name(edit));
        }
}

// The review's case: the cloud moved 3 units along x, the stretched lattice left at the origin holds none
// of it: the cloud is not deformed (it used to be stretched anyway, 3 units away from the lattice).
TEST(TransformFrame, ALatticeFarFromTheMovedCloudLeavesItUnchanged) {
    const Placement far{"cloud moved away", make_transform({3, 0, 0}, {0, 1, 0}, 0.0, {1, 1, 1}),
                        std::nullopt};
    Scene s;
    build(s, sphere_cloud(), far, Edit::stretch);
    run(s);
    const DeformedSplats& d = s.reg.get<DeformedSplats>(s.cloud);
    EXPECT_EQ(d.positions, s.reg.get<SplatCloud>(s.cloud).positions);
    EXPECT_NEAR(d.bounds_min.x, 3.0 + kOrigin.x - 1.0, 1e-3);  // the box is where the cloud is drawn
    EXPECT_NEAR(d.bounds_max.x, 3.0 + kOrigin.x + 1.0, 1e-3);
    Scene g;
    build(g, gaussian::gaussians_from_splats(sphere_cloud()), far, Edit::stretch);
    run(g);
    EXPECT_EQ(g.reg.get<DeformedGaussians>(g.cloud).cloud.positions,
              g.reg.get<GaussianCloud>(g.cloud).positions);
}

// Both entities moved by the same T, with an edited lattice: the deformed cloud is T applied to the
// deformed cloud of the unmoved scene (in the cloud's frame the outputs are the same, bit for bit).
TEST(TransformFrame, MovingCloudAndLatticeTogetherMovesTheDeformedCloudRigidly) {
    for (Edit edit : {Edit::stretch, Edit::twist}) {
        Scene still, moved;
        build(still, sphere_cloud(), {"still", std::nullopt, std::nullopt}, edit);
        build(moved, sphere_cloud(), {"together", kCloudT, kCloudT}, edit);
        run(still), run(moved);
        const DeformedSplats& a = still.reg.get<DeformedSplats>(still.cloud);
        const DeformedSplats& b = moved.reg.get<DeformedSplats>(moved.cloud);
        EXPECT_EQ(a.positions, b.positions) << edit_name(edit);
        EXPECT_EQ(a.normals, b.normals) << edit_name(edit);
        const glm::dmat4 t = model_matrix(&kCloudT);
        double worst = 0;
        for (std::size_t i = 0; i < a.positions.size(); ++i) {
            const glm::dvec3 want = glm::dvec3(t * glm::dvec4(a.origin + glm::dvec3(a.positions[i]), 1.0));
            const glm::dvec3 got = glm::dvec3(model_matrix(moved.reg.try_get<Transform>(moved.cloud)) *
                                              glm::dvec4(b.origin + glm::dvec3(b.positions[i]), 1.0));
            worst = std::max(worst, glm::length(got - want));
        }
        EXPECT_LT(worst, 1e-12) << edit_name(edit);
        Scene gs, gm;
        build(gs, gaussian::gaussians_from_splats(sphere_cloud()), {"still", std::nullopt, std::nullopt},
              edit);
        build(gm, gaussian::gaussians_from_splats(sphere_cloud()), {"together", kCloudT, kCloudT}, edit);
        run(gs), run(gm);
        EXPECT_EQ(gs.reg.get<DeformedGaussians>(gs.cloud).cloud.positions,
                  gm.reg.get<DeformedGaussians>(gm.cloud).cloud.positions);
        EXPECT_EQ(gs.reg.get<DeformedGaussians>(gs.cloud).cloud.scales,
                  gm.reg.get<DeformedGaussians>(gm.cloud).cloud.scales);
    }
}

// Every CPU backend, fed the lattice in the cloud's frame, gives the reference's result.
TEST(TransformFrame, EveryCpuBackendAgreesInTheCloudsFrame) {
    for (Edit edit : {Edit::stretch, Edit::twist}) {
        Scene s;
        build(s, sphere_cloud(), kPlacements[2], edit);
        const SplatCloud& a = s.reg.get<SplatCloud>(s.cloud);
        const ffd::CloudLattices framed = ffd::cloud_lattices(s.reg, s.cloud, std::vector{s.lattice});
        ASSERT_EQ(framed.lattices.size(), 1u);
        const glm::dmat4 c = model_matrix(s.reg.try_get<Transform>(s.cloud));
        const Lattice world =
            world_lattice(s.reg.get<Lattice>(s.lattice), model_matrix(s.reg.try_get<Transform>(s.lattice)));
        for (ffd::Backend b :
             {ffd::Backend::reference, ffd::Backend::fast, ffd::Backend::sparse, ffd::Backend::automatic}) {
            std::vector<glm::vec3> pos(a.size()), nrm(a.size());
            const ffd::PointsIn in{a.positions.data(), a.normals.data(), nullptr, nullptr,
                                   a.size(),           a.origin};
            ASSERT_TRUE(
                ffd::deform(*framed.lattices[0], in, {pos.data(), nrm.data(), nullptr, nullptr}, b).ok());
            double worst = 0;
            for (std::size_t i = 0; i < a.size(); ++i) {
                const Expected e = expected(world, c, a.origin + glm::dvec3(a.positions[i]));
                worst = std::max(
                    worst,
                    glm::length(glm::dvec3(c * glm::dvec4(a.origin + glm::dvec3(pos[i]), 1.0)) - e.world));
            }
            EXPECT_LT(worst, 2e-5) << ffd::backend_name(b) << ", " << edit_name(edit);
        }
    }
}

// A Transform change of either entity marks the deformation stale: the next frame re-deforms, and the
// result is the reference's for the new placement.
TEST(TransformFrame, MovingEitherEntityReDeforms) {
    Scene s;
    build(s, sphere_cloud(), {"still", std::nullopt, std::nullopt}, Edit::twist);
    s.reg.emplace<Transform>(s.cloud);
    s.reg.emplace<Transform>(s.lattice);
    run(s);
    const std::uint64_t v0 = s.reg.get<DeformedSplats>(s.cloud).version;
    run(s);
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).version, v0);  // nothing moved: nothing ran
    s.reg.patch<Transform>(s.cloud) = kCloudT;
    run(s);
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).version, v0 + 1);
    expect_splats_match_reference(s, "after moving the cloud");
    s.reg.patch<Transform>(s.lattice) = kLatticeT;
    run(s);
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).version, v0 + 2);
    expect_splats_match_reference(s, "after moving the lattice");

    Scene g;
    build(g, gaussian::gaussians_from_splats(sphere_cloud()), {"still", std::nullopt, std::nullopt},
          Edit::twist);
    g.reg.emplace<Transform>(g.cloud);
    g.reg.emplace<Transform>(g.lattice);
    run(g);
    g.reg.patch<Transform>(g.lattice) = kLatticeT;
    run(g);
    expect_gaussians_match_reference(g, "Gaussians after moving the lattice");
    g.reg.patch<Transform>(g.cloud) = kCloudT;
    run(g);
    expect_gaussians_match_reference(g, "Gaussians after moving the cloud");
}

// Picking a moved, deformed cloud: a sphere (radius 1) moved to c = (3, 0.5, 0) and turned about y, its
// lattice placed at c unturned and stretched 1.5 times along the world's x about c. The world surface is
// the ellipsoid with semi-axes (1.5, 1, 1) about c: a ray down -x meets it at x = c.x + 1.5, one down -z
// at z = 1. Picked from the deformer's output and from picking's own deformation.
TEST(TransformFrame, PickingHitsTheDeformedSurfaceOfAMovedCloud) {
    const glm::dvec3 c(3.0, 0.5, 0.0);
    for (bool deformer_ran : {true, false}) {
        ecs::Registry reg;
        reg.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
        const ecs::Entity cloud = reg.create();
        SplatCloud sc = sphere_cloud(20000);
        sc.origin = glm::dvec3(0.0);
        reg.emplace<SplatCloud>(cloud, std::move(sc));
        reg.emplace<Transform>(cloud, make_transform(c, {0, 1, 0}, 0.6, {1, 1, 1}));
        const ecs::Entity le = reg.create();
        Lattice l =
            make_lattice(glm::dvec3(-1.1),
                         {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {2, 2, 2});
        for (glm::dvec3& p : l.current) p.x *= 1.5;  // linear: the sphere becomes the ellipsoid exactly
        reg.emplace<Lattice>(le, std::move(l));
        reg.emplace<Transform>(le, make_transform(c, {0, 1, 0}, 0.0, {1, 1, 1}));
        reg.emplace<Deformers>(cloud, Deformers{{le}});
        if (deformer_ran) ffd_system(reg, FrameContext{});
        picking::PickingState state;
        auto ray = [&](glm::dvec3 from, glm::dvec3 dir) {
            picking::PickQuery q = picking::query_from_ray({from, dir});
            q.control_points = false;
            return picking::pick(reg, state, q);
        };
        const picking::PickHit side = ray(c + glm::dvec3(10, 0, 0), {-1, 0, 0});
        ASSERT_EQ(side.kind, picking::PickKind::surface) << deformer_ran;
        EXPECT_EQ(side.entity, cloud);
        EXPECT_NEAR(side.position.x, c.x + 1.5, 0.01) << deformer_ran;
        const picking::PickHit front = ray(c + glm::dvec3(0, 0, 10), {0, 0, -1});
        ASSERT_EQ(front.kind, picking::PickKind::surface) << deformer_ran;
        EXPECT_NEAR(front.position.z, c.z + 1.0, 0.01) << deformer_ran;
        // Just past the rest sphere along x: only the stretched surface is there.
        EXPECT_EQ(ray(c + glm::dvec3(1.3, 0, 10), {0, 0, -1}).kind, picking::PickKind::surface)
            << deformer_ran;
    }
}

// The editor's overlay draws each control point where the deformation uses it: the overlay's world
// position of point i is the cloud's model matrix applied to the lattice as the kernels read it.
TEST(TransformFrame, OverlayShowsTheControlPointsWhereTheDeformationUsesThem) {
    for (const Placement& p : kPlacements) {
        Scene s;
        build(s, sphere_cloud(200), p, Edit::twist);
        s.reg.emplace<Camera>(s.reg.create());
        editor::EditorState& state = editor::setup_editor(s.reg, Viewport{320, 240});
        const editor::OverlayGeometry g = editor::build_lattice_overlay(s.reg, state, s.lattice);
        const ffd::CloudLattices framed = ffd::cloud_lattices(s.reg, s.cloud, std::vector{s.lattice});
        const Lattice& used = *framed.lattices[0];
        ASSERT_EQ(g.points.size(), used.current.size());
        const glm::dmat4 c = model_matrix(s.reg.try_get<Transform>(s.cloud));
        double worst = 0;
        for (std::size_t i = 0; i < used.current.size(); ++i) {
            const glm::dvec3 shown = g.anchor + glm::dvec3(g.points[i].position);
            worst = std::max(worst, glm::length(shown - glm::dvec3(c * glm::dvec4(used.current[i], 1.0))));
        }
        EXPECT_LT(worst, 1e-5) << p.name;
    }
}

// Saving and loading a scene keeps both Transforms, so the deformation after the round trip is the one
// before it.
TEST(TransformFrame, ASavedSceneKeepsBothTransformsAndItsDeformation) {
    Scene s;
    build(s, sphere_cloud(), kPlacements[2], Edit::twist);
    run(s);
    const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                       ("sffd_transform_frame_" + std::to_string(::getpid()) + ".glb");
    s.reg.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(save_scene(s.reg, path).ok());
    ecs::Registry loaded;
    loaded.set_resource<SceneHooks>();  // assets' own formats only
    const Status st = load_scene(loaded, path.string());
    std::filesystem::remove(path);
    ASSERT_TRUE(st.ok()) << st.message();
    ecs::Entity cloud{}, lattice{};
    loaded.each_entity([&](ecs::Entity e) {
        if (loaded.has<SplatCloud>(e)) cloud = e;
        if (loaded.has<Lattice>(e)) lattice = e;
    });
    ASSERT_TRUE(loaded.valid(cloud) && loaded.valid(lattice));
    auto same = [](const Transform& a, const Transform& b) {
        return glm::length(a.translation - b.translation) < 1e-9 && glm::length(a.scale - b.scale) < 1e-9 &&
               std::abs(std::abs(glm::dot(a.rotation, b.rotation)) - 1.0) < 1e-9;
    };
    ASSERT_TRUE(loaded.has<Transform>(cloud) && loaded.has<Transform>(lattice));
    EXPECT_TRUE(same(loaded.get<Transform>(cloud), kCloudT));
    EXPECT_TRUE(same(loaded.get<Transform>(lattice), kLatticeT));
    loaded.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    ffd_system(loaded, FrameContext{});
    const DeformedSplats& a = s.reg.get<DeformedSplats>(s.cloud);
    const DeformedSplats& b = loaded.get<DeformedSplats>(cloud);
    ASSERT_EQ(a.positions.size(), b.positions.size());
    double worst = 0;
    for (std::size_t i = 0; i < a.positions.size(); ++i)
        worst = std::max(worst, double(glm::length(a.positions[i] - b.positions[i])));
    EXPECT_LT(worst, 1e-5);
}

// The editor's "apply as rest" bakes each cloud by the lattice where the deformation uses it: the baked
// cloud is the deformed one, and with the lattice now at rest it stays so.
TEST(TransformFrame, ApplyAsRestBakesTheCloudWhereItWasDrawn) {
    Scene s;
    build(s, sphere_cloud(), kPlacements[2], Edit::twist);
    run(s);
    const std::vector<glm::vec3> deformed = s.reg.get<DeformedSplats>(s.cloud).positions;
    s.reg.emplace<Camera>(s.reg.create());
    editor::EditorState& state = editor::setup_editor(s.reg, Viewport{320, 240});
    state.active_lattice = s.lattice;
    ASSERT_TRUE(editor::apply_lattice_as_rest(s.reg, state));
    const SplatCloud& baked = s.reg.get<SplatCloud>(s.cloud);
    double worst = 0;
    for (std::size_t i = 0; i < deformed.size(); ++i)
        worst = std::max(worst, double(glm::length(baked.positions[i] - deformed[i])));
    EXPECT_LT(worst, 1e-5);
    EXPECT_EQ(s.reg.get<Lattice>(s.lattice).rest, s.reg.get<Lattice>(s.lattice).current);
    run(s);
    EXPECT_EQ(s.reg.get<DeformedSplats>(s.cloud).positions, baked.positions);  // at rest: nothing moves
}

// The editor's "fit to object" fits the lattice around the cloud where it is drawn: the fitted box, placed
// by the lattice's Transform, holds every splat of the moved cloud.
TEST(TransformFrame, FitToObjectFitsTheLatticeAroundTheCloudWhereItIsDrawn) {
    Scene s;
    build(s, sphere_cloud(), kPlacements[2], Edit::rest);
    s.reg.emplace<Camera>(s.reg.create());
    editor::EditorState& state = editor::setup_editor(s.reg, Viewport{320, 240});
    state.active_lattice = s.lattice;
    ASSERT_TRUE(editor::fit_lattice_to(s.reg, state, false));
    const ffd::CloudLattices framed = ffd::cloud_lattices(s.reg, s.cloud, std::vector{s.lattice});
    const SplatCloud& c = s.reg.get<SplatCloud>(s.cloud);
    std::size_t outside = 0;
    for (const glm::vec3& p : c.positions)
        outside += !ffd::inside(ffd::local_coords(*framed.lattices[0], c.origin + glm::dvec3(p)));
    EXPECT_EQ(outside, 0u);
}
