// SOG and SPZ version 4 from a real pipeline (@playcanvas/splat-transform and the official SPZ library it
// bundles; label `slow`, skipped with the reason when node or the package is missing): their files read
// by us must equal their own decode of the same file, ours (SPZ 4 and SOG, write_sog) must decode in their
// tool like ours, their SOG and ours of one capture must both be it within the quantisation, and a capture
// through each renders like the original (CPU reference renderer).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/sog_bounds.h"
#include "tests/systems/gaussian/splat_transform_fixture.h"
#include "tests/systems/gaussian/test_math.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

namespace splat_transform = sffd::test::splat_transform;
using splat_transform::tool;

fs::path temp(const std::string& name) { return splat_transform::temp("sffd_st_sog", name); }
std::string run(const std::string& args) { return splat_transform::run("sffd_st_sog", "-g cpu ", args); }

class SplatTransformSog : public splat_transform::Fixture {};
using splat_transform::capture;
using splat_transform::expect_close;

ReferenceImage render(const GaussianCloud& g) {
    Camera cam;
    cam.eye = {0.3, -0.4, -4.0};
    cam.target = {0.0, 0.0, 0.0};
    cam.up = {0.0, -1.0, 0.0};  // y down: the 3DGS PLY frame
    ReferenceOptions o;
    o.width = o.height = 160;
    return render_reference(g, cam, o);
}

TEST_F(SplatTransformSog, TheirSogReadsLikeTheirDecodeAndRendersLikeTheCapture) {
    const GaussianCloud g = capture(2000, 0.15f);
    const fs::path ply = temp("s.ply"), sog = temp("s.sog"), decoded = temp("s_decoded.ply");
    const fs::path folder = temp("s_folder") / "meta.json", folder_decoded = temp("s_folder_decoded.ply");
    fs::create_directories(folder.parent_path());
    ASSERT_TRUE(write_ply(ply, g));
    ASSERT_EQ(run("--max-workers 0 " + ply.string() + " " + sog.string()), "");
    ASSERT_EQ(run(sog.string() + " " + decoded.string()), "");
    ASSERT_EQ(run("--max-workers 0 " + ply.string() + " " + folder.string()), "");
    ASSERT_EQ(run(folder.string() + " " + folder_decoded.string()), "");
    const double ref_db = 30.0;  // lossy: codebooks and a palette for the SH bands
    for (const auto& [file, dec] : {std::pair{sog, decoded}, std::pair{folder, folder_decoded}}) {
        auto mine = read_gaussians(file);
        ASSERT_TRUE(mine) << mine.message();
        auto theirs = read_ply(dec);
        ASSERT_TRUE(theirs) << theirs.message();
        // Their decode runs in float32 and clamps opacity through a logit at 1e-6.
        expect_close(*mine, *theirs, 2e-5);
        const double db = psnr(render(g), render(*mine));
        std::printf("  %-12s PSNR %.1f dB against the capture\n", file.filename().c_str(), db);
        EXPECT_GE(db, ref_db) << file;
    }
}

// A degree-0 copy of a capture, moved off the origin (SOG stores absolute positions).
GaussianCloud degree0_off_origin(const GaussianCloud& g) {
    GaussianCloud d = g;
    d.origin = {4.0, -2.5, 1.0};
    d.sh_degree = 0;
    d.sh.clear();
    for (std::size_t i = 0; i < g.size(); ++i)
        for (int c = 0; c < 3; ++c) d.sh.push_back(g.sh[i * 48 + std::size_t(c)]);
    return d;
}

TEST_F(SplatTransformSog, OurSogDecodesInTheirToolLikeOurs) {
    const GaussianCloud d3 = capture(2000, 0.15f);
    const GaussianCloud d0 = degree0_off_origin(d3);
    const fs::path folder = temp("ours_folder") / "meta.json";
    fs::create_directories(folder.parent_path());
    for (const auto& [g, file] :
         {std::pair{&d3, temp("ours3.sog")}, std::pair{&d0, temp("ours0.sog")}, std::pair{&d3, folder}}) {
        SCOPED_TRACE(file.string());
        const fs::path decoded =
            temp(file.parent_path().filename().string() + file.stem().string() + "_dec.ply");
        ASSERT_TRUE(write_sog(file, *g, {.morton_order = g == &d0}));  // texel order is the file's
        ASSERT_EQ(run(file.string() + " " + decoded.string()), "");
        auto mine = read_gaussians(file);
        ASSERT_TRUE(mine) << mine.message();
        auto theirs = read_ply(decoded);
        ASSERT_TRUE(theirs) << theirs.message();
        // Their decode runs in float32 and clamps opacity through a logit at 1e-6.
        expect_close(*mine, *theirs, 2e-5);
        if (g == &d3) {
            const double db = psnr(render(*g), render(*mine));
            std::printf("  our %-10s PSNR %.1f dB against the capture\n", file.filename().c_str(), db);
            EXPECT_GE(db, 30.0);
        }
    }
}

TEST_F(SplatTransformSog, TheirSogAndOursAreBothTheCaptureWithinTheQuantisation) {
    // Both of one input: ours rounds the fixed-point fields (half a step), theirs truncates (a step); the
    // codebooks are each file's own. The SH bands: ours within a quarter more error than theirs.
    const GaussianCloud g = capture(3000, 0.15f, 8);
    const fs::path ply = temp("both.ply"), theirs_sog = temp("both_theirs.sog"),
                   ours_sog = temp("both_ours.sog");
    ASSERT_TRUE(write_ply(ply, g));
    ASSERT_EQ(run("--max-workers 0 " + ply.string() + " " + theirs_sog.string()), "");
    ASSERT_TRUE(write_sog(ours_sog, g));
    auto theirs = read_gaussians(theirs_sog);
    ASSERT_TRUE(theirs) << theirs.message();
    auto ours = read_gaussians(ours_sog);
    ASSERT_TRUE(ours) << ours.message();
    // Their file is in Morton order: match their Gaussians to ours by nearest centre first.
    ASSERT_EQ(theirs->size(), g.size());
    GaussianCloud matched = *theirs;
    std::vector<std::size_t> order(g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
        std::size_t best = 0;
        float d = INFINITY;
        for (std::size_t j = 0; j < theirs->size(); ++j)
            if (const float e = glm::length(theirs->positions[j] - g.positions[i]); e < d) d = e, best = j;
        order[i] = best;
    }
    for (std::size_t i = 0; i < g.size(); ++i) {
        const std::size_t j = order[i];
        matched.positions[i] = theirs->positions[j], matched.scales[i] = theirs->scales[j];
        matched.rotations[i] = theirs->rotations[j], matched.opacities[i] = theirs->opacities[j];
        std::copy_n(theirs->sh.begin() + std::ptrdiff_t(j * 48), 48,
                    matched.sh.begin() + std::ptrdiff_t(i * 48));
    }
    const auto e_theirs =
        test::sog::expect_within_quantisation(g, matched, test::sog::meta_of(theirs_sog), 1.0);
    const auto e_ours = test::sog::expect_within_quantisation(g, *ours, test::sog::meta_of(ours_sog), 0.5);
    std::printf("  SH bands rms error (of the signal): theirs %.3f, ours %.3f\n", e_theirs.bands_rms,
                e_ours.bands_rms);
    EXPECT_LT(e_ours.bands_rms, 1.25 * e_theirs.bands_rms + 0.01);
    const double db_theirs = psnr(render(g), render(*theirs)), db_ours = psnr(render(g), render(*ours));
    std::printf("  PSNR against the capture: theirs %.1f dB, ours %.1f dB\n", db_theirs, db_ours);
    EXPECT_GE(db_ours, db_theirs - 1.0);
}

TEST_F(SplatTransformSog, TheyReadOurEmptySog) {
    // An empty cloud is a valid SOG (4x4 images, count 0): their tool reads it and then refuses, as for
    // every empty input, to write no Gaussians.
    GaussianCloud empty;
    const fs::path sog = temp("empty.sog");
    ASSERT_TRUE(write_sog(sog, empty));
    const std::string out = run(sog.string() + " " + temp("empty_dec.ply").string());
    EXPECT_NE(out.find("No Gaussians to write"), std::string::npos) << out;
}

TEST_F(SplatTransformSog, TheirSpzVersion4ReadsLikeTheirDecodeTurnedAboutX) {
    // splat-transform 3.7.0 writes version 4 by default, in its PLY space without SPZ's RUB turn
    // (gaussian_axes.h): our read, turned back, equals its own decode.
    const GaussianCloud g = capture(800, 0.3f);
    const fs::path ply = temp("v.ply"), spz = temp("v.spz"), decoded = temp("v_decoded.ply");
    ASSERT_TRUE(write_ply(ply, g));
    ASSERT_EQ(run("--spz-version 4 " + ply.string() + " " + spz.string()), "");
    std::ifstream f(spz, std::ios::binary);
    char head[5] = {};
    f.read(head, 5);
    ASSERT_EQ(std::string(head, 4), "NGSP");
    ASSERT_EQ(head[4], 4) << "expected a version 4 file";
    ASSERT_EQ(run(spz.string() + " " + decoded.string()), "");
    auto mine = read_gaussians(spz);
    ASSERT_TRUE(mine) << mine.message();
    auto theirs = read_ply(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    turn_axes(*mine, AxisTurn::x180);
    expect_close(*mine, *theirs, 2e-5);
    const double db = psnr(render(g), render(*mine));
    std::printf("  their v4 .spz PSNR %.1f dB against the capture\n", db);
    EXPECT_GE(db, 30.0);
}

TEST_F(SplatTransformSog, OurSpzVersion4DecodesInTheirToolLikeOurs) {
    const GaussianCloud g = capture(800, 0.3f);
    const fs::path spz = temp("o.spz"), decoded = temp("o_decoded.ply");
    ASSERT_TRUE(write_spz(spz, g, 4));
    ASSERT_EQ(run(spz.string() + " " + decoded.string()), "");
    auto mine = read_gaussians(spz);
    ASSERT_TRUE(mine) << mine.message();
    auto theirs = read_ply(decoded);
    ASSERT_TRUE(theirs) << theirs.message();
    turn_axes(*theirs, AxisTurn::x180);
    expect_close(*mine, *theirs, 2e-5);
    const double db = psnr(render(g), render(*mine));
    std::printf("  our v4 .spz PSNR %.1f dB against the capture\n", db);
    EXPECT_GE(db, 30.0);
}

TEST_F(SplatTransformSog, SpzVersion4FromTheOfficialLibraryReadsInThePlyFrame) {
    // The official library (WebAssembly, inside splat-transform) writes version 4 from a PLY-frame cloud
    // (niantic_spz.mjs, told RDF): we must read back the cloud, not its mirror image.
    const GaussianCloud g = capture(300, 0.3f);
    const fs::path in = temp("niantic4.json"), out = temp("niantic4.spz");
    ASSERT_EQ(splat_transform::write_with_official_spz(g, in, out, "4"), 0);
    std::ifstream f(out, std::ios::binary);
    char head[5] = {};
    f.read(head, 5);
    ASSERT_EQ(std::string(head, 4), "NGSP") << "the library wrote no plain version 4 header";
    EXPECT_EQ(head[4], 4);
    auto back = read_gaussians(out);
    ASSERT_TRUE(back) << back.message();
    splat_transform::expect_official_spz_reads_as(*back, g);
}

}  // namespace
