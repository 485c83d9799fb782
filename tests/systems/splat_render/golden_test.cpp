// Golden images (256x256, generated on llvmpipe and reviewed by eye) guard against regressions that the
// property tests miss. Tolerant comparison: at most 1% of pixels may differ by more than 12 levels in any
// channel, and the mean difference stays under 1 level. Candidates for review are written by
// tests/systems/splat_render/update_golden.sh (SFFD_GOLDEN_CANDIDATES=DIR); it also promotes them.
#include <cstdlib>
#include <filesystem>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

class Golden : public GlRenderTest {
protected:
    void compare(const std::string& name, const FrameImage& img) {
        const Rgba8Image actual = to_rgba8(img);
        if (const char* dir = std::getenv("SFFD_GOLDEN_CANDIDATES")) {
            fs::create_directories(dir);
            ASSERT_TRUE(write_png(fs::path(dir) / (name + ".png"), actual).ok());
            GTEST_SKIP() << "wrote candidate " << name << ".png";
        }
        const fs::path golden_path = fs::path(SFFD_TEST_DATA_DIR) / "golden" / (name + ".png");
        auto golden = read_png(golden_path);
        ASSERT_TRUE(golden.ok()) << golden.message() << " (run tests/systems/splat_render/update_golden.sh)";
        ASSERT_EQ(golden->width, actual.width);
        ASSERT_EQ(golden->height, actual.height);
        int bad = 0;
        double sum = 0;
        for (std::size_t i = 0; i < actual.pixels.size(); i += 4) {
            int worst = 0;
            for (int c = 0; c < 4; ++c)
                worst = std::max(worst, std::abs(int(actual.pixels[i + c]) - int(golden->pixels[i + c])));
            bad += worst > 12;
            sum += worst;
        }
        const double pixels = double(actual.pixels.size() / 4);
        if (bad > pixels * 0.01 || sum / pixels > 1.0) {
            const fs::path failed = fs::path(SFFD_BINARY_DIR) / "golden_failures" / (name + ".png");
            fs::create_directories(failed.parent_path());
            (void)write_png(failed, actual);
            ADD_FAILURE() << name << ": " << bad << " pixels differ by more than 12 levels, mean "
                          << sum / pixels << "; actual image: " << failed;
        }
    }
};

TEST_F(Golden, SphereHq) {
    add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.1f);
    add_cloud(fibonacci_sphere(59650, 1.0, 0.8, 0xffb4b4b4u));
    compare("sphere_hq", render(Quality::hq, 256, 256));
}

TEST_F(Golden, SpherePreview) {
    add_camera(3.0);
    add_light({-0.5f, -0.4f, -0.6f}, 0.1f);
    add_cloud(fibonacci_sphere(59650, 1.0, 0.8, 0xffb4b4b4u));
    compare("sphere_preview", render(Quality::preview, 256, 256));
}

TEST_F(Golden, TexturedSphereStretchedByALattice) {
    add_camera(6.5);
    add_light({-0.5f, -0.4f, -0.6f}, 0.2f);
    SplatCloud sphere = fibonacci_sphere(59650);
    const int tw = 64, th = 32;
    sphere.texture.width = tw, sphere.texture.height = th;
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
            const bool check = ((x / 8) + (y / 8)) % 2 == 0;
            const std::uint8_t r = check ? 230 : 40, g = std::uint8_t(40 + 6 * y), b = check ? 40 : 220;
            sphere.texture.rgba8.insert(sphere.texture.rgba8.end(), {r, g, b, 255});
        }
    Lattice lattice = ffd::make_lattice(glm::dvec3(-1.2),
                                        {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)},
                                        glm::ivec3(2, 2, 2));
    for (glm::dvec3& p : lattice.current) p.x *= 2.0, p.y += 0.12 * p.x * p.x - 0.3;  // stretch and bend
    SplatCloud out = sphere;
    auto st = ffd::deform(lattice,
                          {sphere.positions.data(), sphere.normals.data(), sphere.axis_u.data(),
                           sphere.axis_v.data(), sphere.size(), sphere.origin},
                          {out.positions.data(), out.normals.data(), out.axis_u.data(), out.axis_v.data()});
    ASSERT_TRUE(st.ok());
    add_cloud(std::move(out));
    compare("textured_sphere_stretched_hq", render(Quality::hq, 256, 256));
}
