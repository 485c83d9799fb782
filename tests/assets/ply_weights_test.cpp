// A PLY vertex property `weight` read as PointWeights (runtime/assets/formats/surface/ply_weights.h): the
// column itself (binary through the mapping, ASCII through the reader), a weight outside [0, 1] refused
// naming the file and vertex, a mesh's weights ignored with a warning; and the clouds render and view load
// (load_scene: a surface PLY, a 3DGS PLY through the Gaussian loader) deformed by the engine's deformation
// phase as P' = P + w (FFD(P) - P): weights 0, 0.5, 1 give the rest point, half and all of the displacement.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/app/frame_loop.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/scene.h"
#include "runtime/core/log.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"

namespace fs = std::filesystem;

namespace sffd {
namespace {

const float kWeights[3] = {0.0f, 0.5f, 1.0f};
const glm::dvec3 kMove(0.2, -0.1, 0.05);  // every control point's displacement: the FFD moves all by it

fs::path temp_dir() {
    static const fs::path d = [] {
        const fs::path p = fs::temp_directory_path() / ("sffd_ply_weights_" + std::to_string(::getpid()));
        fs::remove_all(p);
        fs::create_directories(p);
        return p;
    }();
    return d;
}

glm::vec3 point(int i) { return {0.1f * float(i) - 0.1f, 0.05f * float(i), 0.02f}; }

// Three surface points (normals, axes) with weights 0, 0.5, 1 (any `weights` given), as ASCII or binary.
fs::path surface_ply(const std::string& name, ply::Format format,
                     std::vector<double> weights = {0.0, 0.5, 1.0}) {
    ply::Header h;
    h.format = format;
    ply::Element v{"vertex", weights.size(), {}};
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "axis_ux", "axis_uy", "axis_uz", "axis_vx",
                          "axis_vy", "axis_vz", "weight"})
        v.properties.push_back({p, ply::Type::float32});
    h.elements.push_back(v);
    const fs::path path = temp_dir() / name;
    auto w = ply::Writer::create(path, h);
    EXPECT_TRUE(w.ok()) << w.message();
    ply::Chunk c;
    c.reset(v);
    c.rows = weights.size();
    for (std::size_t r = 0; r < weights.size(); ++r) {
        const glm::vec3 p = point(int(r));
        const double row[13] = {p.x, p.y, p.z, 0, 0, 1, 0.01, 0, 0, 0, 0.01, 0, weights[r]};
        for (int k = 0; k < 13; ++k) c.columns[std::size_t(k)].values.push_back(row[k]);
    }
    EXPECT_TRUE(w->write_rows(c).ok());
    EXPECT_TRUE(w->finish().ok());
    return path;
}

// The same three points as a 3DGS PLY (SH degree 0) with a `weight` property.
fs::path gaussian_ply() {
    ply::Header h;
    ply::Element v{"vertex", 3, {}};
    const char* names[] = {"x",       "y",       "z",     "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0",
                           "scale_1", "scale_2", "rot_0", "rot_1",  "rot_2",  "rot_3",  "weight"};
    for (const char* p : names) v.properties.push_back({p, ply::Type::float32});
    h.elements.push_back(v);
    const fs::path path = temp_dir() / "gaussians.ply";
    auto w = ply::Writer::create(path, h);
    EXPECT_TRUE(w.ok()) << w.message();
    ply::Chunk c;
    c.reset(v);
    c.rows = 3;
    for (int r = 0; r < 3; ++r) {
        const glm::vec3 p = point(r);
        const double row[15] = {p.x, p.y, p.z, 0.1, 0.2, 0.3, 1.0, -4.0, -4.0, -4.0, 1, 0, 0, 0, kWeights[r]};
        for (int k = 0; k < 15; ++k) c.columns[std::size_t(k)].values.push_back(row[k]);
    }
    EXPECT_TRUE(w->write_rows(c).ok());
    EXPECT_TRUE(w->finish().ok());
    return path;
}

// A 1x1x1 lattice around the points with every control point moved by kMove (the FFD moves all by it).
Lattice moved_lattice() {
    Lattice l =
        make_lattice(glm::dvec3(-1.0), {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                     glm::ivec3(1, 1, 1));
    for (glm::dvec3& c : l.current) c += kMove;
    return l;
}

TEST(PlyWeights, TheColumnIsReadFromBinaryAndAsciiFiles) {
    for (const ply::Format f :
         {ply::Format::binary_little_endian, ply::Format::ascii, ply::Format::binary_big_endian}) {
        const fs::path p = surface_ply("w" + std::to_string(int(f)) + ".ply", f);
        auto w = assets::read_ply_weights(p);
        ASSERT_TRUE(w.ok()) << w.message();
        EXPECT_EQ(w->values, std::vector<float>(std::begin(kWeights), std::end(kWeights))) << int(f);
    }
}

TEST(PlyWeights, AWeightOutsideZeroToOneIsRefusedNamingTheVertex) {
    for (const ply::Format f : {ply::Format::binary_little_endian, ply::Format::ascii}) {
        const fs::path p = surface_ply("bad" + std::to_string(int(f)) + ".ply", f, {0.0, 1.5, 1.0});
        auto w = assets::read_ply_weights(p);
        ASSERT_FALSE(w.ok());
        EXPECT_EQ(w.message(), p.string() + ": vertex 1: weight 1.500000 is not in [0, 1]");
        ecs::Registry r;
        use_engine_scene_hooks(r);
        const Status s = load_scene(r, p.string());
        EXPECT_FALSE(s.ok());
        EXPECT_EQ(s.message(), p.string() + ": vertex 1: weight 1.500000 is not in [0, 1]");
    }
}

TEST(PlyWeights, AMeshesWeightsAreNotUsedAndSaySo) {
    const fs::path p = temp_dir() / "mesh.ply";
    std::ofstream(p)
        << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
           "z\nproperty float weight\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0 0\n1 0 0 0.5\n0 1 0 1\n3 0 1 2\n";
    log::ScopedLogCapture logs;
    auto w = assets::cloud_weights_of_file(p, 20000);
    ASSERT_TRUE(w.ok()) << w.message();
    EXPECT_TRUE(w->values.empty());
    EXPECT_TRUE(logs.contains(p.string() + ": the vertex property 'weight' is not used"));
}

TEST(PlyWeights, ASurfacePlyLoadedAsRenderLoadsItDeformsByItsWeights) {
    ecs::Registry r;
    use_engine_scene_hooks(r);
    r.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    ASSERT_TRUE(load_scene(r, surface_ply("surface.ply", ply::Format::binary_little_endian).string()).ok());
    ecs::Entity cloud;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<SplatCloud>(e)) cloud = e;
    });
    ASSERT_TRUE(r.valid(cloud));
    const PointWeights* w = r.try_get<PointWeights>(cloud);
    ASSERT_TRUE(w);
    EXPECT_EQ(w->values, std::vector<float>(std::begin(kWeights), std::end(kWeights)));
    const ecs::Entity lattice = r.create();
    r.emplace<Lattice>(lattice, moved_lattice());
    r.emplace<Deformers>(cloud, Deformers{{lattice}});
    ffd_system(r, FrameContext{});
    const DeformedSplats* d = r.try_get<DeformedSplats>(cloud);
    ASSERT_TRUE(d && d->cpu_valid);
    const SplatCloud& rest = r.get<SplatCloud>(cloud);
    for (int i = 0; i < 3; ++i) {
        const glm::dvec3 moved = d->origin + glm::dvec3(d->positions[std::size_t(i)]) - rest.origin -
                                 glm::dvec3(rest.positions[std::size_t(i)]);
        for (int a = 0; a < 3; ++a)
            EXPECT_NEAR(moved[a], double(kWeights[i]) * kMove[a], 1e-6) << i << " " << a;
    }
}

TEST(PlyWeights, A3dgsPlyLoadedAsRenderLoadsItDeformsByItsWeights) {
    ecs::Registry r;
    use_engine_scene_hooks(r);
    r.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    ASSERT_TRUE(load_scene(r, gaussian_ply().string()).ok());
    ecs::Entity cloud;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<GaussianCloud>(e)) cloud = e;
    });
    ASSERT_TRUE(r.valid(cloud));
    const PointWeights* w = r.try_get<PointWeights>(cloud);
    ASSERT_TRUE(w);
    EXPECT_EQ(w->values, std::vector<float>(std::begin(kWeights), std::end(kWeights)));
    // The lattice in the cloud's frame: it shares the cloud's Transform (the capture's turn to y up).
    const ecs::Entity lattice = r.create();
    r.emplace<Lattice>(lattice, moved_lattice());
    if (const Transform* t = r.try_get<Transform>(cloud)) r.emplace<Transform>(lattice, *t);
    r.emplace<Deformers>(cloud, Deformers{{lattice}});
    gaussian_deform_system(r, FrameContext{});
    const DeformedGaussians* d = r.try_get<DeformedGaussians>(cloud);
    ASSERT_TRUE(d);
    ASSERT_EQ(d->cloud.size(), 3u);
    const GaussianCloud& rest = r.get<GaussianCloud>(cloud);
    for (int i = 0; i < 3; ++i) {
        const glm::dvec3 moved = d->cloud.origin + glm::dvec3(d->cloud.positions[std::size_t(i)]) -
                                 rest.origin - glm::dvec3(rest.positions[std::size_t(i)]);
        for (int a = 0; a < 3; ++a)
            EXPECT_NEAR(moved[a], double(kWeights[i]) * kMove[a], 1e-5) << i << " " << a;
    }
}

}  // namespace
}  // namespace sffd
