// Streamed SOG (lod-meta.json) against @playcanvas/splat-transform (label `slow`; skipped with the reason
// when node or the package is missing: tools/fetch_splat_transform.sh): their lod-meta.json of a capture
// (two levels) opens in our reader and each level is its input within SOG's quantisation (their writer
// truncates: a full step), and ours (lod_build.h, several levels, several units) opens in their tool,
// whose decode of each level equals ours.
#include <gtest/gtest.h>

#include <filesystem>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "systems/gaussian/gaussian_read.h"
#include "tests/systems/gaussian/sog_bounds.h"
#include "tests/systems/gaussian/splat_transform_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
namespace splat_transform = sffd::test::splat_transform;

fs::path temp(const std::string& name) { return splat_transform::temp("sffd_st_lod", name); }
std::string run(const std::string& args) { return splat_transform::run("sffd_st_lod", "-g cpu ", args); }

class SplatTransformLod : public splat_transform::Fixture {};

// `g` reordered to follow `ref`: each of ref's Gaussians gets g's one with the nearest centre (absolute).
GaussianCloud matched_to(const GaussianCloud& g, const GaussianCloud& ref) {
    EXPECT_EQ(g.size(), ref.size());
    GaussianCloud out = ref;
    out.origin = ref.origin;
    const std::size_t K3 = std::size_t(sh_coeffs(g.sh_degree)) * 3;
    out.sh_degree = g.sh_degree;
    out.sh.assign(ref.size() * K3, 0.0f);
    for (std::size_t i = 0; i < ref.size() && i < g.size(); ++i) {
        const glm::dvec3 p = ref.origin + glm::dvec3(ref.positions[i]);
        std::size_t best = 0;
        double d = INFINITY;
        for (std::size_t j = 0; j < g.size(); ++j)
            if (const double e = glm::length(g.origin + glm::dvec3(g.positions[j]) - p); e < d)
                d = e, best = j;
        out.positions[i] = glm::vec3(g.origin + glm::dvec3(g.positions[best]) - ref.origin);
        out.scales[i] = g.scales[best], out.rotations[i] = g.rotations[best];
        out.opacities[i] = g.opacities[best];
        std::copy_n(g.sh.begin() + std::ptrdiff_t(best * K3), K3, out.sh.begin() + std::ptrdiff_t(i * K3));
    }
    return out;
}

TEST_F(SplatTransformLod, TheirStreamedSogReadsAsTheCaptureWithinTheQuantisation) {
    // Two levels, as splat-transform builds them: each input tagged with its level (-l); level 1 here is
    // every other Gaussian of the capture.
    const GaussianCloud g = splat_transform::capture(2500, 0.15f);
    GaussianCloud half;
    half.sh_degree = g.sh_degree;
    for (std::size_t i = 0; i < g.size(); i += 2) {
        half.positions.push_back(g.positions[i]), half.scales.push_back(g.scales[i]);
        half.rotations.push_back(g.rotations[i]), half.opacities.push_back(g.opacities[i]);
        half.sh.insert(half.sh.end(), g.sh.begin() + std::ptrdiff_t(i * 48),
                       g.sh.begin() + std::ptrdiff_t(i * 48 + 48));
    }
    const fs::path ply = temp("c.ply"), ply1 = temp("c1.ply"), meta = temp("theirs") / "lod-meta.json";
    fs::create_directories(meta.parent_path());
    ASSERT_TRUE(gaussian::write_ply(ply, g));
    ASSERT_TRUE(gaussian::write_ply(ply1, half));
    ASSERT_EQ(run("--max-workers 0 " + ply.string() + " -l 0 " + ply1.string() + " -l 1 " + meta.string()),
              "");
    auto s = lod::open_streamed_sog(meta);
    ASSERT_TRUE(s) << s.message();
    std::printf("%s", lod::describe(*s).c_str());
    ASSERT_EQ(s->levels, 2);
    ASSERT_EQ(s->counts[0], g.size());
    ASSERT_EQ(s->counts[1], half.size());
    // One unit per level at this size: its codebooks and position range are the bounds' (sog_bounds.h).
    ASSERT_EQ(s->units.size(), 2u);
    for (int l = 0; l < 2; ++l) {
        SCOPED_TRACE("level " + std::to_string(l));
        const GaussianCloud& ref = l == 0 ? g : half;
        auto level = lod::read_level(*s, l);
        ASSERT_TRUE(level) << level.message();
        const lod::LodUnit& unit = s->units[0].level == l ? s->units[0] : s->units[1];
        const auto e = test::sog::expect_within_quantisation(ref, matched_to(*level, ref),
                                                             test::sog::meta_of(unit.path), 1.0);
        std::printf(
            "  their level %d: position %.2g (relative), log scale %.3g, opacity %.3g, SH bands rms "
            "%.3f\n",
            l, e.position, e.log_scale, e.opacity, e.bands_rms);
    }
    // read_gaussians and so every command read the same finest level.
    auto whole = gaussian::read_gaussians(meta);
    ASSERT_TRUE(whole) << whole.message();
    EXPECT_EQ(whole->size(), g.size());
}

TEST_F(SplatTransformLod, OurStreamedSogDecodesInTheirToolLikeOurs) {
    const GaussianCloud g = splat_transform::capture(3000, 0.15f, 12);
    const fs::path meta = temp("ours") / "lod-meta.json";
    lod::LodBuildOptions o;
    o.levels = 3, o.ratio = 4, o.chunk_count = 512;  // several leaves and units per level
    auto stats = lod::build_streamed_sog(lod::cloud_gaussian_source(g, "capture"), meta, o);
    ASSERT_TRUE(stats) << stats.message();
    auto s = lod::open_streamed_sog(meta);
    ASSERT_TRUE(s) << s.message();
    EXPECT_GT(s->units.size(), 3u);
    for (int l = 0; l < s->levels; ++l) {
        SCOPED_TRACE("level " + std::to_string(l));
        const fs::path decoded = temp("ours_level" + std::to_string(l) + ".ply");
        ASSERT_EQ(run("-L " + std::to_string(l) + " " + meta.string() + " " + decoded.string()), "");
        auto theirs = gaussian::read_ply(decoded);
        ASSERT_TRUE(theirs) << theirs.message();
        auto mine = lod::read_level(*s, l);
        ASSERT_TRUE(mine) << mine.message();
        ASSERT_EQ(theirs->size(), mine->size());
        ASSERT_EQ(theirs->size(), s->counts[std::size_t(l)]);
        // Their decode runs in float32 and clamps opacity through a logit at 1e-6.
        splat_transform::expect_close(matched_to(*theirs, *mine), *mine, 2e-5);
    }
    // The finest level is the capture within SOG's position quantisation (16 bits of a log-mapped range
    // per unit: a few 1e-5 over this 2-unit box).
    auto level0 = lod::read_level(*s, 0);
    ASSERT_TRUE(level0) << level0.message();
    const GaussianCloud back = matched_to(*level0, g);
    double worst = 0;
    for (std::size_t i = 0; i < g.size(); ++i)
        worst =
            std::max(worst, double(glm::length(glm::dvec3(back.positions[i]) - glm::dvec3(g.positions[i]))));
    std::printf("  our level 0: worst centre error %.3g (box of the capture: 2)\n", worst);
    EXPECT_LT(worst, 2e-3);
}

}  // namespace
