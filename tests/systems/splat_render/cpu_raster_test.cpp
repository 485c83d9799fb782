// The CPU preview rasteriser (cpu_raster.h) against geometry computed here: discs in view space, the ray
// of each pixel centre intersected with their planes in double precision; every check runs on every SIMD
// target this machine has, and the targets draw the same bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/cpu_raster.h"
#include "tests/test_util/simd_targets.h"

using namespace sffd;
using namespace sffd::render;

namespace {

constexpr int W = 80, H = 60;

// The packing splat_common.glsl documents: 10 bits of sqrt(linear) per channel, the 30 bits made a normal
// float by adding one to the exponent field.
float pack_color(glm::vec3 linear) {
    const glm::uvec3 q(glm::round(glm::sqrt(glm::clamp(linear, 0.0f, 1.0f)) * 1023.0f));
    const std::uint32_t bits = q.x | (q.y << 10) | (q.z << 20);
    const std::uint32_t stored = (bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23);
    float f;
    std::memcpy(&f, &stored, sizeof f);
    return f;
}

// pack_halves() of splat_common.glsl: two halves in one float, their lowest mantissa bits dropped.
float pack_halves(float a, float b) {
    const std::uint32_t bits =
        std::uint32_t(glm::packHalf1x16(a) >> 1) | (std::uint32_t(glm::packHalf1x16(b) >> 1) << 15);
    const std::uint32_t stored = (bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23);
    float f;
    std::memcpy(&f, &stored, sizeof f);
    return f;
}

glm::vec4 half4(std::uint64_t c) {
    return {glm::unpackHalf1x16(std::uint16_t(c)), glm::unpackHalf1x16(std::uint16_t(c >> 16)),
            glm::unpackHalf1x16(std::uint16_t(c >> 32)), glm::unpackHalf1x16(std::uint16_t(c >> 48))};
}

struct Disc {
    glm::dvec3 c, u, v;  // view space: centre and orthogonal axes
    glm::vec3 color;
};

class CpuRaster : public sffd::test::EverySimdTarget {
protected:
    glm::dmat4 projection = glm::perspective(glm::radians(45.0), double(W) / H, 0.1, 10.0);
    gpu::FrameBlock frame = camera_frame_block(glm::dmat4(1.0), projection, W, H, 1.0f, 64.0f, true);

    // The record the CPU cull writes for a disc (splat_record.h), with a square of `side` pixels around its
    // projected centre.
    SplatRecord record(const Disc& d, float side) const { return record(d, side, projection); }
    static SplatRecord record(const Disc& d, float side, const glm::dmat4& proj) {
        const glm::dvec3 n = glm::normalize(glm::cross(d.u, d.v));
        const glm::dvec3 du = d.u / glm::dot(d.u, d.u), dv = d.v / glm::dot(d.v, d.v);
        const glm::dvec4 clip = proj * glm::dvec4(d.c, 1.0);
        SplatRecord r{};
        r.center = glm::vec4(float(clip.x / clip.w), float(clip.y / clip.w), float(d.c.z), side);
        r.plane = glm::vec4(glm::vec3(n / glm::dot(d.c, n)), 0.0f);
        r.dual_u = glm::vec4(glm::vec3(du), float(glm::dot(du, d.c)));
        r.dual_v = glm::vec4(glm::vec3(dv), float(glm::dot(dv, d.c)));
        r.normal = glm::vec4(glm::vec3(n), pack_color(d.color));
        return r;
    }

    // The ray through pixel (x, y) (lower-left origin) hits the disc: its view-axis depth t and squared
    // elliptical radius there.
    bool hit(const Disc& d, int x, int y, double& t, double& r2) const {
        const glm::dvec3 ray(((x + 0.5) / W * 2.0 - 1.0) / projection[0][0],
                             ((y + 0.5) / H * 2.0 - 1.0) / projection[1][1], -1.0);
        const glm::dvec3 n = glm::cross(d.u, d.v);
        if (glm::dot(n, ray) == 0.0) return false;
        t = glm::dot(n, d.c) / glm::dot(n, ray);
        if (t <= 0.0) return false;
        const glm::dvec3 p = t * ray - d.c;
        const double s = glm::dot(p, d.u) / glm::dot(d.u, d.u), q = glm::dot(p, d.v) / glm::dot(d.v, d.v);
        r2 = s * s + q * q;
        return true;
    }
    double window_depth(double t) const {
        return 0.5 * ((projection[2][2] * -t + projection[3][2]) / t) + 0.5;
    }

    CpuRasterImage draw(const std::vector<SplatRecord>& records, bool aux = false) const {
        CpuRasterImage img;
        const SpriteRun run{records.data(), records.size()};
        rasterize_sprites_cpu({&run, 1}, frame, W, H, background, {1.0f, 64.0f}, SpritePass::preview, aux,
                              img);
        return img;
    }
    static bool inside(const CpuRasterImage& img, int x, int y) {
        return x >= img.rect.x && x < img.rect.x + img.rect.z && y >= img.rect.y &&
               y < img.rect.y + img.rect.w;
    }
    static std::size_t at(const CpuRasterImage& img, int x, int y) {
        return std::size_t(y - img.rect.y) * std::size_t(img.rect.z) + std::size_t(x - img.rect.x);
    }
    // Outside the rectangle the frame keeps its clear colour: the background, as the RGBA16F target holds it.
    glm::vec4 color(const CpuRasterImage& img, int x, int y) const {
        return inside(img, x, y) ? half4(img.color[at(img, x, y)]) : background_half();
    }
    glm::vec4 background_half() const {
        return {glm::unpackHalf1x16(glm::packHalf1x16(background.x)),
                glm::unpackHalf1x16(glm::packHalf1x16(background.y)),
                glm::unpackHalf1x16(glm::packHalf1x16(background.z)),
                glm::unpackHalf1x16(glm::packHalf1x16(background.w))};
    }
    float depth(const CpuRasterImage& img, int x, int y) const {
        return inside(img, x, y) ? img.depth[at(img, x, y)] : 1.0f;
    }

    glm::vec4 background{0.1f, 0.2f, 0.3f, 0.0f};
};

TEST(CpuRasterColors, UnpacksColoursAsTheShaderDoes) {
    for (glm::vec3 c :
         {glm::vec3(0.0f), glm::vec3(1.0f), glm::vec3(0.25f, 0.5f, 0.75f), glm::vec3(0.01f, 0.9f, 0.3f)}) {
        const glm::vec3 expected = glm::pow(glm::round(glm::sqrt(c) * 1023.0f) / 1023.0f, glm::vec3(2.0f));
        const glm::vec3 got = unpack_color(pack_color(c));
        for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(got[k], expected[k]);
    }
}

// A tilted elliptical disc: the drawn pixels are those whose ray meets it (away from its rim by float
// rounding), each with the disc's colour, its window depth, and with aux outputs its normal and view depth.
TEST_P(CpuRaster, DrawsTheDiscEveryPixelRayMeets) {
    const Disc d{{0.1, -0.05, -3.0}, {0.5, 0.0, 0.25}, {0.0, 0.3, 0.0}, {0.9f, 0.4f, 0.1f}};
    const std::vector<SplatRecord> rec{record(d, 60.0f)};
    const CpuRasterImage img = draw(rec, true);
    EXPECT_EQ(img.sprites, 1u);
    const glm::vec3 expected = unpack_color(rec[0].normal.w);
    int drawn = 0, checked = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double t = 0, r2 = 2;
            const bool on = hit(d, x, y, t, r2) && r2 <= 1.0;
            const bool got = depth(img, x, y) < 1.0f;
            drawn += got;
            if (std::abs(r2 - 1.0) < 1e-4) continue;  // the rim: float rounding may go either way
            ++checked;
            ASSERT_EQ(got, on) << x << ", " << y << " r2 " << r2;
            const glm::vec4 c = color(img, x, y);
            if (!on) {
                EXPECT_EQ(c, background_half());
                continue;
            }
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[k], expected[k], 1e-3);
            EXPECT_EQ(c.w, 1.0f);
            EXPECT_NEAR(depth(img, x, y), window_depth(t), 2e-6);
            const glm::vec4 a = img.aux[at(img, x, y)];
            EXPECT_NEAR(a.w, t, 1e-4 * t);
            EXPECT_NEAR(a.y, 0.0, 1e-6);
            EXPECT_NEAR(glm::length(glm::vec3(a)), 1.0, 1e-5);
        }
    EXPECT_GT(drawn, 200);  // 282 with this camera
    EXPECT_GT(checked, W * H - 100);
    // The rectangle is the square's pixels: it holds every drawn pixel and no more than the square.
    EXPECT_LE(img.rect.z, 61);
    EXPECT_LE(img.rect.w, 61);
}

// The HQ visibility pass: depth only, each hit pushed back by the record's eps (plane.w) along the unit
// view ray (visibility.frag), so that splats within eps of the surface pass the attribute pass's test.
TEST_P(CpuRaster, VisibilityPassWritesTheHitPushedBackByEps) {
    const Disc d{{0.1, -0.05, -3.0}, {0.5, 0.0, 0.25}, {0.0, 0.3, 0.0}, {0.9f, 0.4f, 0.1f}};
    SplatRecord rec = record(d, 60.0f);
    const float eps = 0.02f;
    rec.plane.w = eps;
    CpuRasterImage img;
    const SpriteRun run{&rec, 1};
    rasterize_sprites_cpu({&run, 1}, frame, W, H, background, {1.0f, 64.0f}, SpritePass::visibility, true,
                          img);
    EXPECT_TRUE(img.color.empty());
    EXPECT_TRUE(img.aux.empty());
    int drawn = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double t = 0, r2 = 2;
            const bool on = hit(d, x, y, t, r2) && r2 <= 1.0;
            if (std::abs(r2 - 1.0) < 1e-4) continue;
            ASSERT_EQ(depth(img, x, y) < 1.0f, on) << x << ", " << y;
            if (!on) continue;
            ++drawn;
            const glm::dvec3 ray(((x + 0.5) / W * 2.0 - 1.0) / projection[0][0],
                                 ((y + 0.5) / H * 2.0 - 1.0) / projection[1][1], -1.0);
            EXPECT_NEAR(depth(img, x, y), window_depth(t + double(eps) / glm::length(ray)), 2e-6)
                << x << ", " << y;
            EXPECT_GT(depth(img, x, y), window_depth(t) + 1e-6);  // behind the hit itself
        }
    EXPECT_GT(drawn, 200);
}

// HQ: the visibility pass, then the attribute sums of every hit within eps of the visible depth: a disc
// just behind the front one (within eps) adds to the sums, one further back does not.
TEST_P(CpuRaster, HqSumsTheHitsWithinEpsOfTheVisibleSurface) {
    const Disc front{{0.0, 0.0, -3.0}, {0.4, 0.0, 0.0}, {0.0, 0.4, 0.0}, {1.0f, 0.0f, 0.0f}};
    Disc near = front, far = front;
    near.c.z = -3.01, near.color = {0.0f, 1.0f, 0.0f};
    far.c.z = -3.2, far.color = {0.0f, 0.0f, 1.0f};
    std::vector<SplatRecord> recs{record(front, 40.0f), record(near, 40.0f), record(far, 40.0f)};
    for (SplatRecord& r : recs) r.plane.w = 0.05f;  // eps, view units
    CpuRasterImage img;
    const SpriteRun run{recs.data(), recs.size()};
    rasterize_sprites_cpu({&run, 1}, frame, W, H, background, {1.0f, 64.0f}, SpritePass::hq, false, img);
    ASSERT_EQ(img.accum_color.size(), img.depth.size());
    int checked = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double t[3], r2[3] = {2, 2, 2};
            const bool on[3] = {hit(front, x, y, t[0], r2[0]) && r2[0] < 0.999,
                                hit(near, x, y, t[1], r2[1]) && r2[1] < 0.999,
                                hit(far, x, y, t[2], r2[2]) && r2[2] < 0.999};
            if (!on[0] || !on[1] || !on[2]) continue;
            ++checked;
            const glm::vec4 c = img.accum_color[at(img, x, y)], n = img.accum_normal[at(img, x, y)];
            const double w0 = (1.0 - r2[0]) * (1.0 - r2[0]) + 1e-6, w1 = (1.0 - r2[1]) * (1.0 - r2[1]) + 1e-6;
            EXPECT_NEAR(c.x, w0, 1e-4) << x << ", " << y;  // red: the front disc
            EXPECT_NEAR(c.y, w1, 1e-4) << x << ", " << y;  // green: within eps behind it
            EXPECT_EQ(c.z, 0.0f) << x << ", " << y;        // blue: too far behind
            EXPECT_NEAR(c.w, w0 + w1, 1e-4);
            EXPECT_NEAR(n.z, w0 + w1, 1e-4);  // both face the camera: normal (0, 0, 1)
            EXPECT_NEAR(n.w, w0 * t[0] + w1 * t[1], 1e-3);
        }
    EXPECT_GT(checked, 100);
}

// GL_LESS in draw order: the nearer disc wins wherever both are; at an exact tie the first drawn stays.
TEST_P(CpuRaster, NearerWinsAndTheFirstDrawnKeepsATie) {
    const Disc back{{0.0, 0.0, -3.0}, {0.4, 0.0, 0.0}, {0.0, 0.4, 0.0}, {1.0f, 0.0f, 0.0f}};
    Disc front = back;
    front.c.z = -2.9, front.color = {0.0f, 1.0f, 0.0f};
    Disc twin = back;
    twin.color = {0.0f, 0.0f, 1.0f};
    const CpuRasterImage a = draw({record(back, 40.0f), record(front, 40.0f)});
    const CpuRasterImage b = draw({record(front, 40.0f), record(back, 40.0f)});
    const CpuRasterImage tie = draw({record(back, 40.0f), record(twin, 40.0f)});
    int front_pixels = 0, tie_pixels = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double t, r2 = 2, tb, rb = 2;
            const bool in_front = hit(front, x, y, t, r2) && r2 < 0.999;
            const bool in_back = hit(back, x, y, tb, rb) && rb < 0.999;
            if (in_front) {
                ++front_pixels;
                EXPECT_EQ(color(a, x, y).y, 1.0f) << x << ", " << y;
                EXPECT_EQ(color(b, x, y).y, 1.0f) << x << ", " << y;
            }
            if (in_back) {
                ++tie_pixels;
                EXPECT_EQ(color(tie, x, y).x, 1.0f) << x << ", " << y;
                EXPECT_EQ(color(tie, x, y).z, 0.0f) << x << ", " << y;
            }
        }
    EXPECT_GT(front_pixels, 100);
    EXPECT_GT(tie_pixels, 100);
}

// A sprite covers the pixels whose centres lie in its square: a square smaller than the disc clips it,
// and a side under GL's smallest point size is drawn at that size.
TEST_P(CpuRaster, SpritesCoverTheirSquaresOnly) {
    const Disc d{{0.0, 0.0, -3.0}, {0.6, 0.0, 0.0}, {0.0, 0.6, 0.0}, {1.0f, 1.0f, 1.0f}};
    SplatRecord r = record(d, 10.0f);
    const CpuRasterImage img = draw({r});
    const double cx = (double(r.center.x) + 1.0) * 0.5 * W, cy = (double(r.center.y) + 1.0) * 0.5 * H;
    int drawn = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const bool in_square = std::abs(x + 0.5 - cx) < 4.99 && std::abs(y + 0.5 - cy) < 4.99;
            const bool out_square = std::abs(x + 0.5 - cx) > 5.01 || std::abs(y + 0.5 - cy) > 5.01;
            const bool got = depth(img, x, y) < 1.0f;
            drawn += got;
            if (in_square) {
                EXPECT_TRUE(got) << x << ", " << y;  // the whole square lies inside the disc
            }
            if (out_square) {
                EXPECT_FALSE(got) << x << ", " << y;
            }
        }
    EXPECT_EQ(drawn, 100);

    // A 0.2 px side drawn with a smallest point size of 3: the 3x3 pixels around the centre.
    r.center.x = float((40.0 + 0.5) / W * 2.0 - 1.0), r.center.y = float((30.0 + 0.5) / H * 2.0 - 1.0);
    r.center.w = 0.2f;
    CpuRasterImage small;
    const SpriteRun run{&r, 1};
    rasterize_sprites_cpu({&run, 1}, frame, W, H, background, {3.0f, 64.0f}, SpritePass::preview, false,
                          small);
    EXPECT_EQ(small.rect, glm::ivec4(39, 29, 3, 3));
}

// The hidden mark (plane 0: back-facing, kept with culling off) draws nothing, and sprites outside the
// frame leave it untouched: no rectangle to upload.
TEST_P(CpuRaster, HiddenAndOffFrameSpritesDrawNothing) {
    const Disc d{{0.0, 0.0, -3.0}, {0.4, 0.0, 0.0}, {0.0, 0.4, 0.0}, {1.0f, 1.0f, 1.0f}};
    SplatRecord hidden = record(d, 40.0f);
    hidden.plane = glm::vec4(0.0f);
    SplatRecord outside = record(d, 10.0f);
    outside.center.x = 1.5f;
    const CpuRasterImage img = draw({hidden, outside});
    EXPECT_EQ(img.sprites, 0u);
    EXPECT_EQ(img.rect.z * img.rect.w, 0);
    EXPECT_TRUE(img.color.empty());
}

// Many sprites across every band boundary (16 rows): the image is the same as each band drawn alone would
// give, i.e. every sprite is found by each band it reaches. Compared against drawing the sprites one by
// one and keeping the nearest per pixel.
TEST_P(CpuRaster, SpritesAcrossBandsMatchOneByOne) {
    std::vector<SplatRecord> recs;
    std::vector<Disc> discs;
    for (int i = 0; i < 60; ++i) {
        const double a = i * 0.7, z = -3.0 - 0.01 * i;
        discs.push_back({{0.9 * std::cos(a), 0.6 * std::sin(1.3 * a), z},
                         {0.15, 0.05, 0.0},
                         {-0.05, 0.15, 0.02},
                         {float(i % 3 == 0), float(i % 3 == 1), float(i % 3 == 2)}});
        recs.push_back(record(discs.back(), 24.0f));
    }
    const CpuRasterImage all = draw(recs);
    std::vector<float> best(std::size_t(W * H), 1.0f);
    std::vector<glm::vec4> best_color(std::size_t(W * H), background_half());
    for (const SplatRecord& r : recs) {
        const CpuRasterImage one = draw({r});
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const float d = depth(one, x, y);
                if (d < best[std::size_t(y * W + x)])
                    best[std::size_t(y * W + x)] = d, best_color[std::size_t(y * W + x)] = color(one, x, y);
            }
    }
    int drawn = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            EXPECT_EQ(depth(all, x, y), best[std::size_t(y * W + x)]) << x << ", " << y;
            EXPECT_EQ(color(all, x, y), best_color[std::size_t(y * W + x)]) << x << ", " << y;
            drawn += depth(all, x, y) < 1.0f;
        }
    EXPECT_GT(drawn, 1000);
}

// Records no ray can hit: a NaN in the elliptical coordinates (its radius is NaN) and a disc seen exactly
// edge-on (its plane 0/0 and ±inf) draw nothing over a disc drawn before them, in every pass; nor does a
// NaN eps in the visibility pass (a NaN depth fails the depth test).
TEST_P(CpuRaster, RecordsWithNaNsDrawNothing) {
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    const SplatRecord base =
        record({{0.1, -0.05, -3.0}, {0.5, 0.0, 0.25}, {0.0, 0.3, 0.0}, {0.9f, 0.4f, 0.1f}}, 60.0f);
    const Disc front{{0.0, 0.0, -2.0}, {0.4, 0.0, 0.0}, {0.0, 0.4, 0.0}, {1.0f, 1.0f, 1.0f}};
    SplatRecord nan_dual = record(front, 50.0f), nan_eps = record(front, 50.0f);
    nan_dual.dual_u.x = nan;
    nan_eps.plane.w = nan;
    const SplatRecord edge_on =
        record({{0.0, 0.0, -2.0}, {0.4, 0.0, 0.0}, {0.0, 0.0, 0.4}, {1.0f, 1.0f, 1.0f}}, 50.0f);
    ASSERT_TRUE(std::isnan(edge_on.plane.x) && std::isinf(edge_on.plane.y));
    for (SpritePass pass : {SpritePass::preview, SpritePass::visibility, SpritePass::hq}) {
        const auto drawn = [&](std::vector<SplatRecord> recs) {
            CpuRasterImage img;
            const SpriteRun run{recs.data(), recs.size()};
            rasterize_sprites_cpu({&run, 1}, frame, W, H, background, {1.0f, 64.0f}, pass, false, img);
            return img;
        };
        const CpuRasterImage alone = drawn({base});
        std::vector<SplatRecord> others{nan_dual, edge_on};
        if (pass == SpritePass::visibility) others.push_back(nan_eps);
        for (std::size_t k = 0; k < others.size(); ++k) {
            SCOPED_TRACE("pass " + std::to_string(int(pass)) + ", record " + std::to_string(k));
            const CpuRasterImage both = drawn({base, others[k]});
            // The rectangle grows to the other sprite's square; inside it only the first disc is drawn.
            int drawn_pixels = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    ASSERT_EQ(depth(both, x, y), depth(alone, x, y)) << x << ", " << y;
                    drawn_pixels += depth(both, x, y) < 1.0f;
                    if (pass == SpritePass::preview) {
                        ASSERT_EQ(color(both, x, y), color(alone, x, y)) << x << ", " << y;
                    }
                    if (pass == SpritePass::hq && inside(both, x, y)) {
                        const glm::vec4 a =
                            inside(alone, x, y) ? alone.accum_color[at(alone, x, y)] : glm::vec4(0.0f);
                        ASSERT_EQ(both.accum_color[at(both, x, y)], a) << x << ", " << y;
                    }
                }
            EXPECT_GT(drawn_pixels, 200);
        }
    }
}

// Every image a scene draws, as bytes.
struct Drawn {
    std::vector<CpuRasterImage> images;  // preview, preview with aux, visibility, hq
};

std::string bytes_diff(const CpuRasterImage& a, const CpuRasterImage& b) {
    std::string out;
    if (a.rect != b.rect) out += " rect";
    if (a.sprites != b.sprites) out += " sprites";
    const auto differ = [&](const char* name, const auto& x, const auto& y) {
        if (x.size() != y.size()) return out += std::string(" ") + name + " size", void();
        std::size_t n = 0, first = x.size();
        for (std::size_t i = 0; i < x.size(); ++i)
            if (std::memcmp(&x[i], &y[i], sizeof x[i]) != 0) first = std::min(first, i), ++n;
        if (n == 0) return;
        const int w = std::max(a.rect.z, 1);
        out += std::string(" ") + name + ": " + std::to_string(n) + " pixels, first at (" +
               std::to_string(a.rect.x + int(first) % w) + ", " + std::to_string(a.rect.y + int(first) / w) +
               ")";
    };
    differ("depth", a.depth, b.depth);
    differ("color", a.color, b.color);
    differ("aux", a.aux, b.aux);
    differ("accum_color", a.accum_color, b.accum_color);
    differ("accum_normal", a.accum_normal, b.accum_normal);
    return out;
}

// A frame whose rows are not whole vectors (157 x 101) with about a hundred overlapping discs of many
// square sizes (1 to 64 px: every tail length), ties at equal depth, discs tilted so far that part of
// their square's rays meet the plane behind the eye, nearly and exactly edge-on discs, back faces (normal
// away from the eye) and hidden marks, flat and textured, drawn in every pass: the pinned target draws
// the same bytes as the portable one (one lane: no lane order, no tails).
TEST_P(CpuRaster, DrawsTheSameBytesAsThePortableTarget) {
    constexpr int w = 157, h = 101;
    const glm::dmat4 proj = glm::perspective(glm::radians(50.0), double(w) / h, 0.1, 10.0);
    const gpu::FrameBlock wide = camera_frame_block(glm::dmat4(1.0), proj, w, h, 1.0f, 64.0f, true);
    const float sides[] = {1.0f, 2.5f, 7.0f, 15.0f, 16.0f, 17.0f, 31.0f, 32.0f, 33.0f, 47.0f, 63.5f, 64.0f};
    std::vector<SplatRecord> flat, textured;
    for (int i = 0; i < 96; ++i) {
        const double a = i * 0.77, tilt = 0.35 * std::sin(i * 1.3), z = -2.2 - 1.8 * std::fmod(i * 0.37, 1.0);
        const Disc d{
            {1.1 * std::cos(a) * (0.3 + 0.7 * std::fmod(i * 0.21, 1.0)), 0.75 * std::sin(1.7 * a), z},
            {0.18, 0.0, 0.18 * tilt},
            {0.03 * tilt, 0.14, 0.1},
            {float(i % 5) / 4.0f, float(i % 3) / 2.0f, float(i % 7) / 6.0f}};
        SplatRecord r = record(d, sides[i % 12], proj);
        r.plane.w = 0.02f + 0.001f * float(i % 4);                               // eps of the HQ passes
        if (i % 9 == 4) r.normal = glm::vec4(-glm::vec3(r.normal), r.normal.w);  // back face
        if (i % 4 == 3) {
            r.center.z = float(i % 3);  // mip level
            r.uv = glm::vec4(0.1f * float(i % 10), 0.37f, pack_halves(0.6f, -0.2f), pack_halves(0.1f, 0.45f));
            r.plane.w = pack_color(glm::vec3(0.1f, 0.2f, 0.05f));  // the preview's specular factor
            textured.push_back(r);
        } else {
            flat.push_back(r);
        }
        if (i % 11 == 5) flat.push_back(flat.back());  // a twin: equal depths, the first drawn stays
    }
    // A disc whose square straddles its plane's horizon: on one side the rays meet the plane behind the
    // eye (inv_t <= 0 lanes next to hits in one vector).
    const SplatRecord straddling =
        record({{0.25, 0.0, -2.0}, {0.05, 0.0, -0.5}, {0.0, 0.3, 0.0}, {0.2f, 0.9f, 0.4f}}, 64.0f, proj);
    const auto inv_t = [&](const SplatRecord& r, float px) {
        const float cy = (r.center.y + 1.0f) * 0.5f * float(h);
        return r.plane.x * (px * wide.ray_map.x + wide.ray_map.z) +
               r.plane.y * (cy * wide.ray_map.y + wide.ray_map.w) - r.plane.z;
    };
    const float cx = (straddling.center.x + 1.0f) * 0.5f * float(w);
    ASSERT_LT(inv_t(straddling, cx - 20.0f) * inv_t(straddling, cx + 20.0f), 0.0f);
    flat.push_back(straddling);
    // Nearly edge-on (its plane far from the origin: huge plane coefficients) and exactly edge-on (the eye
    // in its plane: 0/0 and ±inf).
    flat.push_back(
        record({{-0.4, 0.0, -1.5}, {0.6, 0.0, 0.0}, {0.0, 0.0005, 0.6}, {0.7f, 0.7f, 0.1f}}, 48.0f, proj));
    flat.push_back(
        record({{0.2, 0.0, -2.0}, {0.6, 0.0, 0.0}, {0.0, 0.0, 0.6}, {0.1f, 0.1f, 0.9f}}, 40.0f, proj));
    ASSERT_TRUE(std::isinf(flat.back().plane.y));
    SplatRecord hidden =
        record({{0.0, 0.0, -2.0}, {0.4, 0.0, 0.0}, {0.0, 0.4, 0.0}, {1.0f, 1.0f, 1.0f}}, 40.0f, proj);
    hidden.plane = glm::vec4(0.0f);  // the hidden mark
    flat.push_back(hidden);
    // An 8 x 8 texture of distinct colours, so that a wrong uv or lane shows.
    std::vector<std::uint8_t> texels;
    for (int k = 0; k < 64; ++k)
        texels.insert(texels.end(),
                      {std::uint8_t(k * 4), std::uint8_t(255 - k * 3), std::uint8_t(k * 37), 255});
    const TexelView texture{texels.data(), 8, 8};
    // The flat runs, then the textured records flat-coloured or textured, then the first flat sprites again
    // (exact ties with themselves).
    const SpriteRun untextured[] = {
        {flat.data(), flat.size()}, {textured.data(), textured.size()}, {flat.data(), 5}};
    const SpriteRun with_texture[] = {
        untextured[0], {textured.data(), textured.size(), &texture}, untextured[2]};
    const auto draw_all = [&](std::span<const SpriteRun> runs) {
        Drawn out;
        for (int k = 0; k < 4; ++k) {
            const SpritePass pass = k < 2    ? SpritePass::preview
                                    : k == 2 ? SpritePass::visibility
                                             : SpritePass::hq;
            CpuRasterImage img;
            rasterize_sprites_cpu(runs, wide, w, h, background, {1.0f, 64.0f}, pass, k == 1, img);
            out.images.push_back(std::move(img));
        }
        return out;
    };
    const Drawn here = draw_all(untextured), here_textured = draw_all(with_texture);
    Drawn portable, portable_textured;
    {
        const simd::ScopedTarget pin(simd::runnable().back());
        portable = draw_all(untextured), portable_textured = draw_all(with_texture);
    }
    const char* names[] = {"preview", "preview with aux", "visibility", "hq"};
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(bytes_diff(here.images[k], portable.images[k]), "") << names[k];
        EXPECT_EQ(bytes_diff(here_textured.images[k], portable_textured.images[k]), "")
            << names[k] << ", textured";
    }
    // The scene is not empty: a fifth of the frame drawn or more (3,870 pixels), textured pixels among them,
    // HQ sums written.
    const CpuRasterImage& p = here_textured.images[0];
    int drawn = 0, lit = 0;
    for (std::size_t i = 0; i < p.depth.size(); ++i) {
        drawn += p.depth[i] < 1.0f;
        const glm::vec4 c = half4(p.color[i]);
        lit += c.w == 1.0f && c.y > 0.0f && c != half4(here.images[0].color[i]);
    }
    EXPECT_GT(drawn, w * h / 5);
    EXPECT_GT(lit, 300);
    int summed = 0;
    for (const glm::vec4& c : here_textured.images[3].accum_color) summed += c.w > 0.0f;
    EXPECT_GT(summed, w * h / 5);
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(CpuRaster);

}  // namespace
