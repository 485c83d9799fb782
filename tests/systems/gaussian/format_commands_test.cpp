// deform of a compressed PLY, SPZ, SOG or KHR glb equals deform of the same cloud as a 3DGS PLY (the
// built binary), and deform writes every Gaussian format. The table of every command on every format is
// format_table_test.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/systems/gaussian/format_files.h"

namespace {

using namespace sffd;
using namespace sffd::test::formats;

double quat_distance(const glm::quat& a, const glm::quat& b) {
    return 1.0 - std::abs(double(glm::dot(a, b)));
}

// A Gaussian's covariance R S² Rᵀ: what rendering sees (a rotation and scales are one of its
// factorisations; two files may store different ones of the same ellipsoid).
glm::dmat3 covariance(const glm::quat& q, const glm::vec3& s) {
    const glm::dmat3 r = glm::mat3_cast(q);
    const glm::dmat3 s2(glm::dvec3(s.x * s.x, 0, 0), glm::dvec3(0, s.y * s.y, 0),
                        glm::dvec3(0, 0, s.z * s.z));
    return r * s2 * glm::transpose(r);
}
double relative_difference(const glm::dmat3& a, const glm::dmat3& b) {
    double d = 0, n = 0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) d += (a[c][r] - b[c][r]) * (a[c][r] - b[c][r]), n += b[c][r] * b[c][r];
    return std::sqrt(d / n);
}

// deform IN (each lossy format) equals deform of the same cloud (IN as read back) written as a 3DGS PLY,
// which the command streams: the same Gaussians to float rounding. Against the cloud before the format
// quantised it, within that format's quantisation, moved by the lattice.
TEST(FormatCommands, DeformOfEachFormatEqualsDeformOfItsCloudAsPly) {
    const GaussianCloud g = shell(2000);
    const fs::path lat = temp("bent.json");
    const Lattice l = save_bent_lattice(lat);
    GaussianCloud exact;
    ASSERT_TRUE(gaussian::deform(l, g, exact));
    gaussian::bake_sh_frames(exact);
    struct Case {
        std::string name;
        double position, covariance;  // tolerances against the unquantised cloud, deformed
    };
    // Positions: compressed PLY 11/10-bit per 256-row chunk bounds, SPZ 2^-12, SOG 16-bit log-mapped;
    // scales are stored as logs (compressed PLY 10/11 bits, SPZ 1/16, SOG a 256-entry codebook) and
    // rotations in 8-10 bits a component: the covariance within a few per cent, about twice the scales'.
    const std::vector<Case> cases = {
        {"g.compressed.ply", 4e-3, 0.1}, {"g.spz", 1e-3, 0.15}, {"g.sog", 4e-3, 0.15}, {"g.glb", 1e-5, 1e-4}};
    write_every_format(g);
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path in = temp(c.name), out = temp("deformed_" + c.name + ".ply");
        const fs::path as_ply = temp("as_ply_" + c.name + ".ply"), ply_out = temp("deformed_as_ply.ply");
        auto decoded = gaussian::read_gaussians(in);
        ASSERT_TRUE(decoded) << decoded.message();
        ASSERT_TRUE(gaussian::write_ply(as_ply, *decoded));
        RunResult r = run("deform", in.string() + " " + out.string() + " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        r = run("deform", as_ply.string() + " " + ply_out.string() + " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        auto got = gaussian::read_ply(out);
        auto want = gaussian::read_ply(ply_out);
        ASSERT_TRUE(got && want);
        ASSERT_EQ(got->size(), g.size());
        ASSERT_EQ(want->size(), g.size());
        double dp = 0, ds = 0, dq = 0, dq_exact = 0, dsh = 0;
        for (std::size_t i = 0; i < g.size(); ++i) {
            dp = std::max(dp, double(glm::length(got->positions[i] - want->positions[i])));
            ds = std::max(ds, double(glm::length(got->scales[i] - want->scales[i])) /
                                  double(glm::length(want->scales[i])));
            dq = std::max(dq, quat_distance(got->rotations[i], want->rotations[i]));
            EXPECT_NEAR(got->opacities[i], want->opacities[i], 1e-6f);
            const double pe = glm::length(got->positions[i] - exact.positions[i]);
            EXPECT_LT(pe, c.position) << "Gaussian " << i;
            dq_exact =
                std::max(dq_exact, relative_difference(covariance(got->rotations[i], got->scales[i]),
                                                       covariance(exact.rotations[i], exact.scales[i])));
        }
        for (std::size_t k = 0; k < got->sh.size() && k < want->sh.size(); ++k)
            dsh = std::max(dsh, double(std::abs(got->sh[k] - want->sh[k])));
        EXPECT_LT(dp, 1e-5) << "positions against the PLY path";
        EXPECT_LT(ds, 1e-5) << "scales against the PLY path";
        EXPECT_LT(dq, 1e-6) << "rotations against the PLY path";
        EXPECT_LT(dsh, 1e-5) << "SH against the PLY path";
        EXPECT_LT(dq_exact, c.covariance) << "covariances against the unquantised cloud";
    }
}

TEST(FormatCommands, DeformWritesEveryGaussianFormat) {
    const GaussianCloud g = shell(500);
    const fs::path lat = temp("bent_out.json");
    const Lattice l = save_bent_lattice(lat);
    ASSERT_TRUE(gaussian::write_compressed_ply(temp("src.compressed.ply"), g));
    GaussianCloud want;
    ASSERT_TRUE(gaussian::deform(l, *gaussian::read_gaussians(temp("src.compressed.ply")), want));
    fs::create_directories(temp("out_sog"));
    for (const fs::path& out : {temp("o.ply"), temp("o.compressed.ply"), temp("o.spz"), temp("o.sog"),
                                temp("o.glb"), temp("out_sog") / "meta.json"}) {
        SCOPED_TRACE(out.string());
        const RunResult r = run("deform", temp("src.compressed.ply").string() + " " + out.string() +
                                              " --lattice " + lat.string());
        ASSERT_EQ(r.code, 0) << r.err;
        auto got = gaussian::read_gaussians(out);
        ASSERT_TRUE(got) << got.message();
        ASSERT_EQ(got->size(), want.size());
        for (std::size_t i = 0; i < want.size(); ++i)
            ASSERT_LT(glm::length(got->positions[i] - want.positions[i]), 5e-3) << i;
    }
    // The stream's own options are refused with the reason, not ignored.
    RunResult r = run("deform", temp("src.compressed.ply").string() + " " + temp("x.ply").string() +
                                    " --lattice " + lat.string() + " --backend gpu");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("deformed on the CPU"), std::string::npos) << r.err;
    r = run("deform", temp("src.compressed.ply").string() + " " + temp("x.xyz").string() + " --lattice " +
                          lat.string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("Gaussians also .compressed.ply, .spz, .sog or meta.json"), std::string::npos)
        << r.err;
}

}  // namespace
