// CPU parts of the renderer: image files, sRGB, splat packing, camera matrices.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_pack.h"
#include "tests/systems/splat_render/test_scenes.h"

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::render;

namespace {

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_render_cpu_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

FrameImage gradient(int w, int h) {
    FrameImage img;
    img.width = w, img.height = h;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool bg = x == 0 && y == 0;
            img.color.push_back(bg ? glm::vec4(0) : glm::vec4(float(x) / float(w), float(y) / float(h), 0.25f, 1.0f));
            img.depth.push_back(bg ? std::numeric_limits<float>::infinity() : 1.0f + float(x) * 0.01f + float(y));
            img.normal.push_back(bg ? glm::vec3(0) : glm::normalize(glm::vec3(float(x) - 3.5f, float(y) - 2.5f, 4.0f)));
        }
    return img;
}

}  // namespace

TEST(RenderSrgb, MatchesTheStandardCurve) {
    EXPECT_NEAR(linear_to_srgb(0.0f), 0.0f, 1e-7);
    EXPECT_NEAR(linear_to_srgb(1.0f), 1.0f, 1e-6);
    EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.0031308f * 12.92f, 1e-6);
    EXPECT_NEAR(linear_to_srgb(0.5f), 0.735357f, 1e-5);  // IEC 61966-2-1
    EXPECT_EQ(encode_srgb8(0.2158605f), 128);
    for (float v = 0.0f; v <= 1.0f; v += 0.01f) EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-5);
}

TEST(RenderImageIo, PngRoundTripKeepsSrgbBytesAndAlpha) {
    const FrameImage img = gradient(8, 6);
    const Rgba8Image rgba = to_rgba8(img);
    EXPECT_EQ(rgba.at(0, 0)[3], 0);    // background stays transparent
    EXPECT_EQ(rgba.at(5, 3)[3], 255);
    EXPECT_EQ(rgba.at(5, 3)[0], encode_srgb8(5.0f / 8.0f));
    const fs::path path = temp_dir() / "round.png";
    ASSERT_TRUE(write_png(path, rgba).ok());
    auto back = read_png(path);
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(back->width, 8);
    EXPECT_EQ(back->height, 6);
    EXPECT_EQ(back->pixels, rgba.pixels);
}

TEST(RenderImageIo, BackgroundFillsTransparentPixels) {
    const Rgba8Image rgba = to_rgba8(gradient(4, 4), glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(rgba.at(0, 0)[0], 255);
    EXPECT_EQ(rgba.at(0, 0)[1], 0);
    EXPECT_EQ(rgba.at(0, 0)[3], 255);
}

TEST(RenderImageIo, ExrHoldsHalfRgbaFloatZAndNormals) {
    const FrameImage img = gradient(8, 6);
    const fs::path path = temp_dir() / "round.exr";
    ASSERT_TRUE(write_exr(path, img).ok());
    auto back = read_exr(path);
    ASSERT_TRUE(back.ok()) << back.message();
    ASSERT_EQ(back->width, 8);
    ASSERT_EQ(back->height, 6);
    ASSERT_EQ(back->depth.size(), img.depth.size());
    ASSERT_EQ(back->normal.size(), img.normal.size());
    for (std::size_t i = 0; i < img.color.size(); ++i) {
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(back->color[i][c], img.color[i][c], 1e-3);  // half
        EXPECT_EQ(back->depth[i], img.depth[i]);                                            // float: exact
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(back->normal[i][c], img.normal[i][c], 1e-3);
    }
    EXPECT_TRUE(std::isinf(back->depth[0]));
}

TEST(RenderImageIo, BadFilesAreNamedInTheError) {
    const fs::path path = temp_dir() / "garbage.png";
    std::ofstream(path) << "not an image";
    auto png = read_png(path);
    ASSERT_FALSE(png.ok());
    EXPECT_NE(png.message().find(path.string()), std::string::npos);
    auto exr = read_exr(path);
    ASSERT_FALSE(exr.ok());
    EXPECT_NE(exr.message().find(path.string()), std::string::npos);
    Rgba8Image empty;
    auto st = write_png(temp_dir() / "empty.png", empty);
    EXPECT_FALSE(st.ok());
    auto missing_dir = write_png(temp_dir() / "no" / "such" / "dir.png", to_rgba8(gradient(2, 2)));
    EXPECT_FALSE(missing_dir.ok());
}

TEST(RenderPack, GpuSplatLayoutCarriesEveryAttribute) {
    SplatCloud c = test::fibonacci_sphere(10);
    c.colors[3] = 0x80402010u;
    const auto packed = pack_splats(c);
    ASSERT_EQ(packed.size(), 10u);
    const auto& s = packed[3];
    EXPECT_EQ(s.center[0], c.positions[3].x);
    EXPECT_EQ(s.center[2], c.positions[3].z);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(s.center[3]), 0x80402010u);
    EXPECT_EQ(s.normal[1], c.normals[3].y);
    EXPECT_EQ(s.normal[3], 1.0f);
    EXPECT_EQ(s.axis_u[0], c.axis_u[3].x);
    EXPECT_EQ(s.axis_v[2], c.axis_v[3].z);
    EXPECT_EQ(s.axis_u[3], c.uvs[3].x);
    EXPECT_EQ(s.axis_v[3], c.uvs[3].y);
}

TEST(RenderPack, BaseColourWhenTheCloudHasNoColours) {
    SplatCloud c = test::fibonacci_sphere(4);
    c.colors.clear();
    c.material.base_color = glm::vec4(1.0f, 0.0f, 0.2158605f, 1.0f);
    const auto packed = pack_splats(c);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(packed[0].center[3]), 0xff8000ffu);
}

TEST(RenderCamera, FramingCameraSeesTheWholeSphere) {
    const glm::dvec3 center(5.0, -2.0, 1.0);
    const double radius = 3.0, aspect = 16.0 / 9.0;
    const Camera cam = framing_camera(center, radius, aspect);
    const glm::dmat4 vp = projection_matrix(cam, aspect) * view_matrix(cam);
    for (const glm::dvec3& d : {glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, -1, 0),
                                glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1)}) {
        const glm::dvec4 clip = vp * glm::dvec4(center + d * radius, 1.0);
        EXPECT_LT(std::abs(clip.x / clip.w), 1.0);
        EXPECT_LT(std::abs(clip.y / clip.w), 1.0);
        EXPECT_GT(clip.z / clip.w, -1.0);
        EXPECT_LT(clip.z / clip.w, 1.0);
    }
    EXPECT_NEAR(view_depth(cam, center), glm::length(cam.eye - center), 1e-9);
}

TEST(RenderCamera, ModelMatrixAppliesOriginThenTransform) {
    Transform t;
    t.translation = glm::dvec3(1, 2, 3);
    t.scale = glm::dvec3(2.0);
    const glm::dmat4 m = model_matrix(&t, glm::dvec3(1e6, 0, 0));
    const glm::dvec3 p = glm::dvec3(m * glm::dvec4(0.5, 0, 0, 1));
    EXPECT_NEAR(p.x, 1.0 + 2.0 * (1e6 + 0.5), 1e-6);
    EXPECT_NEAR(p.y, 2.0, 1e-12);
}

TEST(RenderPack, BoundingSphereContainsEverySplat) {
    const SplatCloud c = test::fibonacci_sphere(1000, 2.0);
    const BoundingSphere b = bounding_sphere(c);
    EXPECT_NEAR(glm::length(b.center), 0.0, 0.01);
    EXPECT_GE(b.radius, 2.0);
    EXPECT_LT(b.radius, 2.3);
}
