// `splatffd deform`'s output rendered: a 2x stretch along x of the paper's sphere (59,650 splats) through
// the command, from a PLY with splat axes, a PLY with only normals and a radius, a PLY with only normals
// (radii estimated from neighbour spacing), and a GLB scene, must
// render closed (no pixel inside the stretched ellipsoid uncovered, no far-side pixel showing through),
// as the engine's own deformation path does (tests/systems/splat_render/coverage_test.cpp). Before the
// command deformed the axes, the stretched splats kept their rest radius and the render had holes.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/scene.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;
namespace fs = std::filesystem;

namespace {

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

int run(const std::string& args) {
    const int status = std::system((kTool + " " + args + " >/dev/null 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// x y z nx ny nz radius (no axes): the command must create the axes; without the radius (with_radius
// false) it estimates the radii from neighbour spacing first.
void save_radius_ply(const SplatCloud& c, const fs::path& path, bool with_radius = true) {
    ply::Header h;
    ply::Element e;
    e.name = "vertex";
    e.count = c.size();
    for (const char* n : {"x", "y", "z", "nx", "ny", "nz", "radius"})
        if (with_radius || std::string(n) != "radius") e.properties.push_back({n, ply::Type::float32});
    h.elements.push_back(e);
    auto w = ply::Writer::create(path, h);
    ASSERT_TRUE(w.ok());
    ply::Chunk ch;
    ch.reset(e);
    ch.rows = c.size();
    for (std::size_t i = 0; i < c.size(); ++i) {
        for (int a = 0; a < 3; ++a) ch.columns[std::size_t(a)].values.push_back(c.positions[i][a]);
        for (int a = 0; a < 3; ++a) ch.columns[std::size_t(3 + a)].values.push_back(c.normals[i][a]);
        if (with_radius) ch.columns[6].values.push_back(double(glm::length(c.axis_u[i])));
    }
    ASSERT_TRUE(w->write_rows(ch).ok());
    ASSERT_TRUE(w->finish().ok());
}

double mean_axis_u(const SplatCloud& c) {
    double s = 0.0;
    for (const glm::vec3& a : c.axis_u) s += double(glm::length(a));
    return c.axis_u.empty() ? 0.0 : s / double(c.axis_u.size());
}

class DeformOutputRender : public GlRenderTest {};

TEST_F(DeformOutputRender, TwiceStretchedSphereFromTheCommandHasNoHoles) {
    if (!fs::exists(kTool)) GTEST_SKIP() << kTool << " not built";
    const fs::path dir = fs::temp_directory_path() / ("sffd_deform_render_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const SplatCloud rest = fibonacci_sphere(59650);
    ASSERT_TRUE(assets::save_splat_ply(rest, dir / "axes.ply").ok());
    save_radius_ply(rest, dir / "radius.ply");
    save_radius_ply(rest, dir / "normals.ply", false);
    ASSERT_TRUE(assets::save_splat_cloud(rest, dir / "sphere.glb").ok());
    // x' = 2x inside [-1.2, 1.2]^3 (Bernstein reproduces the linear map exactly).
    Lattice lattice = ffd::make_lattice(glm::dvec3(-1.2),
                                        {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)},
                                        glm::ivec3(2, 2, 2));
    for (glm::dvec3& p : lattice.current) p.x *= 2.0;
    ASSERT_TRUE(ffd::save_lattice(dir / "stretch.json", lattice).ok());

    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    for (const std::string in : {"axes.ply", "radius.ply", "normals.ply", "sphere.glb"}) {
        const fs::path out =
            dir / ("out_" + fs::path(in).stem().string() + (in == "sphere.glb" ? ".glb" : ".ply"));
        ASSERT_EQ(run("deform " + (dir / in).string() + " " + out.string() + " --lattice " +
                      (dir / "stretch.json").string()),
                  0)
            << in;
        auto cloud = assets::import_splat_cloud(out);
        ASSERT_TRUE(cloud.ok()) << cloud.message();
        ASSERT_EQ(cloud->size(), rest.size());
        ASSERT_EQ(cloud->axis_u.size(), rest.size()) << in << ": no axes written";
        // The axes were deformed: circles became ellipses stretched along x (mean |axis_u| grows).
        EXPECT_GT(mean_axis_u(*cloud), 1.2 * mean_axis_u(rest))
            << in << " mean |axis_u| " << mean_axis_u(rest) << " -> " << mean_axis_u(*cloud);
        // Control (first input only): the same output with the rest axes put back, i.e. what the command
        // wrote before, must show holes, or this check could not see the difference.
        if (in == "axes.ply") {
            SplatCloud undeformed_axes = *cloud;
            undeformed_axes.axis_u = rest.axis_u, undeformed_axes.axis_v = rest.axis_v;
            const ecs::Entity c = add_cloud(std::move(undeformed_axes));
            const Coverage k =
                ellipsoid_coverage(render(Quality::hq, 512, 512), cam, glm::dvec3(2.0, 1.0, 1.0));
            EXPECT_GT(k.holes + k.far_side, k.inside / 50)
                << "control: holes " << k.holes << " far side " << k.far_side;
            reg.destroy(c);
        }
        const ecs::Entity e = add_cloud(std::move(*cloud));
        for (Quality q : {Quality::hq, Quality::preview}) {
            const FrameImage img = render(q, 512, 512);
            const Coverage c =
                ellipsoid_coverage(img, cam, glm::dvec3(2.0, 1.0, 1.0));  // the 2x1x1 ellipsoid
            const char* qn = q == Quality::hq ? "hq" : "preview";
            EXPECT_GT(c.inside, 40000) << in << " " << qn;
            EXPECT_EQ(c.holes, 0) << in << " " << qn;
            EXPECT_EQ(c.far_side, 0) << in << " " << qn;
        }
        reg.destroy(e);
    }
    fs::remove_all(dir);
}

}  // namespace
