// Real files from a real pipeline (@playcanvas/splat-transform, label `slow`, skipped with the reason
// when node or the package is missing: tools/fetch_splat_transform.sh): its compressed PLY read by us
// and decoded by it must agree, ours decoded by it likewise; the infinities its decoder writes for
// fully opaque / transparent splats are read as limits; and one capture converted to every format we
// read renders the same image (CPU reference renderer).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/splat_transform_fixture.h"
#include "tests/systems/gaussian/test_math.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

namespace splat_transform = sffd::test::splat_transform;
using splat_transform::tool;

fs::path temp(const std::string& name) { return splat_transform::temp("sffd_st_formats", name); }
std::string run(const std::string& args) { return splat_transform::run("sffd_st_formats", "", args); }

class SplatTransformFormats : public splat_transform::Fixture {};
using splat_transform::capture;
using splat_transform::expect_close;

TEST_F(SplatTransformFormats, TheirCompressedPlyReadsLikeTheirDecode) {
    const GaussianCloud g = capture(1000, 0.2f);
    const fs::path ply = temp("c_ours.ply"), comp = temp("c_theirs.compressed.ply"),
                   decoded = temp("c_decoded.ply");
    ASSERT_TRUE(write_ply(ply, g));
    ASSERT_EQ(run(ply.string() + " " + comp.string()), "");
    ASSERT_EQ(run(comp.string() + " " + decoded.string()), "");
    auto mine = read_gaussians(comp);
    ASSERT_TRUE(mine) << mine.message();
    auto theirs = read_ply(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    expect_close(*mine, *theirs, 2e-5);  // their decode runs in float32, ours in double
}

TEST_F(SplatTransformFormats, OurCompressedPlyDecodesLikeOurs) {
    const GaussianCloud g = capture(1000, 0.2f);
    const fs::path comp = temp("o_ours.compressed.ply"), decoded = temp("o_decoded.ply");
    ASSERT_TRUE(write_compressed_ply(comp, g));
    ASSERT_EQ(run(comp.string() + " " + decoded.string()), "");
    auto mine = read_gaussians(comp);
    ASSERT_TRUE(mine) << mine.message();
    auto theirs = read_ply(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    expect_close(*mine, *theirs, 2e-5);
}

TEST_F(SplatTransformFormats, InfinitiesTheirDecoderWritesAreReadAsLimits) {
    // Fully opaque and fully transparent splats: their PLY writer stores logit(1) = +inf, logit(0) = -inf.
    GaussianCloud g = capture(300, 0.1f);
    for (std::size_t i = 0; i < g.size(); i += 3) g.opacities[i] = i % 2 ? 1.0f : 0.0f;
    const fs::path comp = temp("i.compressed.ply"), decoded = temp("i_decoded.ply");
    ASSERT_TRUE(write_compressed_ply(comp, g));
    ASSERT_EQ(run(comp.string() + " " + decoded.string()), "");
    log::ScopedLogCapture log;
    auto theirs = read_gaussians(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    for (std::size_t i = 0; i < g.size(); i += 3) EXPECT_EQ(theirs->opacities[i], i % 2 ? 1.0f : 0.0f) << i;
    EXPECT_TRUE(log.contains(decoded.string() + ": read 100 infinite values as limits (100 logit opacities"))
        << (log.entries().empty() ? "no log line" : log.entries()[0].message);
}

ReferenceImage render(const GaussianCloud& g) {
    Camera cam;
    cam.eye = {0.3, -0.4, -4.0};
    cam.target = {0.0, 0.0, 0.0};
    cam.up = {0.0, -1.0, 0.0};  // y down: the 3DGS PLY frame
    ReferenceOptions o;
    o.width = o.height = 160;
    return render_reference(g, cam, o);
}

TEST_F(SplatTransformFormats, OneCaptureRendersTheSameFromEveryFormat) {
    const GaussianCloud g = capture(3000, 0.15f);
    const fs::path ply = temp("r.ply");
    ASSERT_TRUE(write_ply(ply, g));
    const ReferenceImage ref = render(g);
    // .splat has no SH bands: it is held to the capture's view-independent part.
    GaussianCloud g0 = g;
    g0.sh_degree = 0;
    g0.sh.clear();
    for (std::size_t i = 0; i < g.size(); ++i)
        for (int c = 0; c < 3; ++c) g0.sh.push_back(g.sh[i * 48 + std::size_t(c)]);
    const ReferenceImage ref0 = render(g0);
    struct Case {
        std::string file;
        bool lossy;
        bool theirs;  // made by splat-transform from r.ply
        bool turn_x180 =
            false;  // splat-transform's SPZ is in its PLY frame, not SPZ's RUB (see gaussian_axes.h)
        bool turn_z180 = false;  // its GLB is its engine frame: the PLY frame turned about z
    };
    const std::vector<Case> cases = {
        {"their.ply", false, true},
        {"ours.glb", false, false},
        {"their.glb", false, true},  // glTF is turned into the PLY frame on reading, as they write it
        {"our.compressed.ply", true, false},
        {"their.compressed.ply", true, true},
        {"their.spz", true, true, true},
        {"their.splat", true, true},
        {"our.spz", true, false},
    };
    for (const Case& c : cases) {
        const fs::path f = temp(c.file);
        if (c.theirs) {
            ASSERT_EQ(
                run((c.file == "their.spz" ? "--spz-version 3 " : "") + ply.string() + " " + f.string()), "");
        } else if (c.file == "ours.glb") {
            ASSERT_TRUE(write_glb(f, g));
        } else if (c.file == "our.spz") {
            ASSERT_TRUE(write_spz(f, g));
        } else {
            ASSERT_TRUE(write_compressed_ply(f, g));
        }
        auto back = read_gaussians(f);
        ASSERT_TRUE(back) << back.message();
        if (c.turn_x180) turn_axes(*back, AxisTurn::x180);
        if (c.turn_z180) turn_axes(*back, AxisTurn::z180);
        const double db = psnr(back->sh_degree == 0 ? ref0 : ref, render(*back));
        std::printf("  %-22s PSNR %.1f dB\n", c.file.c_str(), db);
        EXPECT_GE(db, c.lossy ? 30.0 : 40.0) << c.file;
    }
}

TEST_F(SplatTransformFormats, SpzFromTheOfficialLibraryReadsInThePlyFrame) {
    // The official SPZ library (the WebAssembly build inside splat-transform), told its input is the 3DGS
    // PLY frame (RDF), stores RUB as the SPZ README says: (x, y, z) -> (x, -y, -z) with rotations and SH.
    // Our reader must give back the PLY-frame cloud (within SPZ's quantisation), not its mirror image.
    const GaussianCloud g = capture(300, 0.3f);
    const fs::path in = temp("niantic.json"), out = temp("niantic.spz");
    ASSERT_EQ(splat_transform::write_with_official_spz(g, in, out), 0);
    auto back = read_spz(out);
    ASSERT_TRUE(back) << back.message();
    splat_transform::expect_official_spz_reads_as(*back, g);
}

TEST_F(SplatTransformFormats, OurSpzDecodesLikeOursTurnedAboutX) {
    // splat-transform decodes SPZ without the RUB turn (gaussian_axes.h): its PLY of our SPZ is our
    // decoded cloud turned 180 degrees about x, and nothing else.
    const GaussianCloud g = capture(500, 0.3f);
    const fs::path spz = temp("w.spz"), decoded = temp("w_decoded.ply");
    ASSERT_TRUE(write_spz(spz, g));
    ASSERT_EQ(run(spz.string() + " " + decoded.string()), "");
    auto mine = read_gaussians(spz);
    ASSERT_TRUE(mine) << mine.message();
    auto theirs = read_ply(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    turn_axes(*theirs, AxisTurn::x180);
    expect_close(*mine, *theirs, 2e-5);
}

}  // namespace
