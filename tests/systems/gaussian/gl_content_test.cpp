// The GL Gaussian renderer against the CPU reference on the test scenes converted to Gaussians by
// `splatffd convert --gaussians`: the built-in sphere (textured), the face and the
// dragon (tools/fetch_content.sh [--dragon]; skipped when absent), at rest and twisted by a lattice.
// Prints the PSNR of each; the bound is the suite's 40 dB, and the covered-pixel counts must agree.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/gfx/context.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/splat_render/gaussian_draw.h"
#include "tests/systems/gaussian/gl_renderer_fixture.h"
#include "systems/gaussian/reference_render.h"
#include "systems/splat_render/camera_math.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;
using test::GaussianHarness;
using test::render_gl;

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

fs::path source_of(const std::string& name) {
    if (name == "sphere") return "sphere";
    if (name == "face") return assets::face_cache_path();
    return assets::face_cache_path().parent_path() / "dragon.ply";
}

class GaussianGlContent
    : public sffd::test::GaussianGlRendererTest<sffd::test::HeadlessGlTestWithParam<const char*>> {};

void compare(GaussianHarness& r, const GaussianCloud& g, const Camera& cam, const ReferenceOptions& o,
             const std::string& what) {
    auto gl = render_gl(r, g, cam, o);
    ASSERT_TRUE(gl) << gl.message();
    const ReferenceImage ref = render_reference(g, cam, o);
    const double p = psnr(ref, *gl);
    std::size_t covered_ref = 0, covered_gl = 0;
    for (std::size_t k = 0; k < ref.transmittance.size(); ++k) {
        covered_ref += ref.transmittance[k] < 0.5f;
        covered_gl += gl->transmittance[k] < 0.5f;
    }
    std::printf(
        "%s (%zu Gaussians, %dx%d): GL vs CPU reference PSNR %.1f dB, covered pixels %zu (reference %zu)\n",
        what.c_str(), g.size(), o.width, o.height, p, covered_gl, covered_ref);
    EXPECT_GT(p, 40.0) << what;
    EXPECT_GT(covered_ref, ref.transmittance.size() / 20) << what;
    EXPECT_NEAR(double(covered_gl), double(covered_ref), 0.01 * double(covered_ref) + 5) << what;
}

TEST_P(GaussianGlContent, MatchesCpuReferenceAtRestAndTwisted) {
    const std::string name = GetParam();
    const fs::path src = source_of(name);
    if (name != "sphere" && !fs::exists(src))
        GTEST_SKIP() << src << " not fetched; run tools/fetch_content.sh --dragon";
    const fs::path dir = fs::temp_directory_path() / ("sffd_gl_content_" + std::to_string(getpid()));
    fs::create_directories(dir);
    const fs::path out = dir / (name + ".ply");
    const std::string cmd =
        kTool + " convert " + src.string() + " " + out.string() + " --gaussians >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    auto g = read_gaussians(out);
    fs::remove_all(dir);
    ASSERT_TRUE(g) << g.message();

    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : g->positions)
        lo = glm::min(lo, g->origin + glm::dvec3(p)), hi = glm::max(hi, g->origin + glm::dvec3(p));
    const glm::dvec3 centre = 0.5 * (lo + hi);
    const double radius = 0.5 * glm::length(hi - lo);
    ReferenceOptions o;
    o.width = 320, o.height = 240;
    const Camera cam = render::framing_camera(centre, radius, 320.0 / 240.0);
    o.near_plane = double(cam.near_plane);
    compare(*renderer, *g, cam, o, name + " at rest");

    // Twisted about the vertical axis through the centre, 0.8 rad per unit of height.
    const glm::dvec3 m = 0.05 * (hi - lo);
    Lattice l =
        ffd::make_lattice(lo - m,
                          {glm::dvec3(hi.x - lo.x + 2 * m.x, 0, 0), glm::dvec3(0, hi.y - lo.y + 2 * m.y, 0),
                           glm::dvec3(0, 0, hi.z - lo.z + 2 * m.z)},
                          {4, 4, 4});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.8 / radius, centre);
    GaussianCloud twisted;
    ASSERT_TRUE(deform(l, *g, twisted));
    compare(*renderer, twisted, cam, o, name + " twisted");
}

INSTANTIATE_TEST_SUITE_P(Content, GaussianGlContent, testing::Values("sphere", "face", "dragon"),
                         [](const auto& param_info) { return std::string(param_info.param); });

}  // namespace
