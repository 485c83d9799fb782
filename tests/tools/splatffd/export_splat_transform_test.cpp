// Every frame of every Gaussian format `splatffd export` writes that @playcanvas/splat-transform reads
// (3DGS PLY, compressed PLY, SOG, SPZ), decoded by splat-transform into a 3DGS PLY and compared with the
// exact frame, within the format's quantisation (label `slow`; skipped without node or the package:
// tools/fetch_splat_transform.sh).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "tests/systems/gaussian/splat_transform_fixture.h"
#include "tests/tools/splatffd/export_scenes.h"

namespace fs = std::filesystem;
namespace st = sffd::test::splat_transform;
using sffd::test::export_scenes::gaussian_scene;
using sffd::test::export_scenes::tool;

class ExportSplatTransform : public st::Fixture {};

TEST_F(ExportSplatTransform, ReadsEveryFrameOfEveryFormatWithinItsQuantisation) {
    const fs::path dir = st::temp("sffd_export_st", "frames");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path scene = gaussian_scene(dir);
    struct Format {
        std::string name, ext;
        double position, log_scale, opacity, dc;
    };
    // As export_test.cpp's read-back by our own readers: compressed PLY's 11/10-bit positions in chunk
    // bounds, SPZ's 12 fractional bits, SOG's 16-bit log-space positions and 256-entry codebooks.
    const Format formats[] = {
        {"ply", ".ply", 1e-6, 1e-6, 1e-6, 1e-6},
        {"compressed-ply", ".compressed.ply", 1.5 * 2.4 / 1023.0, 0.1, 1.0 / 255.0, 0.02},
        {"sog", ".sog", 2e-4, 0.1, 1.0 / 255.0, 0.05},
        {"spz", ".spz", 1.5 / 4096.0, 1.0 / 32.0 + 1e-4, 1.0 / 255.0, 0.04}};
    const fs::path exact_dir = dir / "ply";
    for (const Format& f : formats) {
        SCOPED_TRACE(f.name);
        const fs::path out = dir / f.name;
        const auto r = tool("export " + scene.string() + " --format " + f.name + " --frames 70:73 --out " +
                            out.string());
        ASSERT_EQ(r.code, 0) << r.out;
        for (long k = 70; k <= 73; ++k) {
            const std::string stem = "frame00" + std::to_string(k);
            const fs::path decoded = dir / (f.name + "_" + stem + "_decoded.ply");
            ASSERT_EQ(st::run("sffd_export_st", "", (out / (stem + f.ext)).string() + " " + decoded.string()),
                      "");
            auto theirs = sffd::gaussian::read_ply(decoded);
            auto exact = sffd::gaussian::read_ply(exact_dir / (stem + ".ply"));
            ASSERT_TRUE(theirs) << theirs.message();
            ASSERT_TRUE(exact) << exact.message();
            ASSERT_EQ(theirs->size(), exact->size());
            // splat-transform decodes SPZ as stored, without SPZ's RUB turn
            // (runtime/assets/formats/gaussian/gaussian_axes.h).
            if (f.name == "spz") sffd::gaussian::turn_axes(*theirs, sffd::gaussian::AxisTurn::x180);
            double pos = 0, scale = 0, opacity = 0, dc = 0;
            const std::size_t kt = std::size_t(sffd::sh_coeffs(theirs->sh_degree)) * 3,
                              ke = std::size_t(sffd::sh_coeffs(exact->sh_degree)) * 3;
            for (std::size_t i = 0; i < exact->size(); ++i) {
                pos = std::max(pos, glm::length((theirs->origin + glm::dvec3(theirs->positions[i])) -
                                                (exact->origin + glm::dvec3(exact->positions[i]))));
                for (int c = 0; c < 3; ++c) {
                    scale = std::max(scale, std::abs(std::log(double(theirs->scales[i][c])) -
                                                     std::log(double(exact->scales[i][c]))));
                    dc = std::max(dc, double(std::abs(theirs->sh[i * kt + std::size_t(c)] -
                                                      exact->sh[i * ke + std::size_t(c)])));
                }
                opacity = std::max(opacity, double(std::abs(theirs->opacities[i] - exact->opacities[i])));
            }
            EXPECT_LE(pos, f.position) << stem;
            EXPECT_LE(scale, f.log_scale) << stem;
            EXPECT_LE(opacity, f.opacity) << stem;
            EXPECT_LE(dc, f.dc) << stem;
        }
    }
}
