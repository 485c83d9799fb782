#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/lod_merge.h"
#include "runtime/assets/formats/lod/streamed_sog.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_lod_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }
std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

// Merge maths against a direct double-precision evaluation of the documented formulas.
TEST(LodMerge, MatchesDoublePrecisionMoments) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1), s(0.05, 0.6), o(0.1, 1.0);
    GaussianCloud in;
    in.origin = {100.0, -3.0, 2.0};
    in.sh_degree = 1;
    for (int i = 0; i < 5; ++i) {
        in.positions.push_back(glm::vec3(float(u(rng)), float(u(rng)), float(u(rng))));
        in.scales.push_back(glm::vec3(float(s(rng)), float(s(rng)), float(s(rng))));
        in.rotations.push_back(
            glm::normalize(glm::quat(float(u(rng)), float(u(rng)), float(u(rng)), float(u(rng)))));
        in.opacities.push_back(float(o(rng)));
        for (int k = 0; k < 12; ++k) in.sh.push_back(float(u(rng)));
    }
    const std::vector<std::uint32_t> members = {0, 1, 2, 3, 4};
    GaussianCloud out;
    out.origin = in.origin, out.sh_degree = 1;
    lod::merge_gaussians(in, members, out);
    ASSERT_EQ(out.size(), 1u);
    // Reference.
    double w[5], W = 0;
    for (int i = 0; i < 5; ++i) {
        double sc[3] = {in.scales[i].x, in.scales[i].y, in.scales[i].z};
        std::sort(sc, sc + 3);
        w[i] = in.opacities[i] * sc[1] * sc[2];
        W += w[i];
    }
    glm::dvec3 mu(0.0);
    for (int i = 0; i < 5; ++i) mu += w[i] / W * glm::dvec3(in.positions[i]);
    glm::dmat3 cov(0.0);
    for (int i = 0; i < 5; ++i) {
        const glm::dmat3 r = glm::mat3_cast(glm::dquat(in.rotations[i]));
        const glm::dvec3 sv(in.scales[i]);
        const glm::dmat3 S(sv.x * sv.x, 0, 0, 0, sv.y * sv.y, 0, 0, 0, sv.z * sv.z);
        const glm::dvec3 d = glm::dvec3(in.positions[i]) - mu;
        cov += w[i] / W * (r * S * glm::transpose(r) + glm::outerProduct(d, d));
    }
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(out.positions[0][a], mu[a], 1e-5);
    const glm::dmat3 r = glm::mat3_cast(glm::dquat(out.rotations[0]));
    const glm::dvec3 sv(out.scales[0]);
    const glm::dmat3 got =
        r * glm::dmat3(sv.x * sv.x, 0, 0, 0, sv.y * sv.y, 0, 0, 0, sv.z * sv.z) * glm::transpose(r);
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[c][k], cov[c][k], 1e-5) << c << "," << k;
    for (int k = 0; k < 12; ++k) {
        double ref = 0;
        for (int i = 0; i < 5; ++i) ref += w[i] / W * in.sh[std::size_t(i * 12 + k)];
        EXPECT_NEAR(out.sh[std::size_t(k)], ref, 1e-6);
    }
    double covered = 0;
    for (int i = 0; i < 5; ++i) {
        double sc[3] = {in.scales[i].x, in.scales[i].y, in.scales[i].z};
        std::sort(sc, sc + 3);
        covered += in.opacities[i] * sc[1] * sc[2];
    }
    double ps[3] = {sv.x, sv.y, sv.z};
    std::sort(ps, ps + 3);
    EXPECT_NEAR(out.opacities[0], std::min(1.0, covered / (ps[1] * ps[2])), 1e-5);
}

// Build out of core (a budget that forces several cells), read back: level 0 is the input within SOG's
// quantisation, levels shrink by the ratio, the ledger stays within the budget.
TEST(StreamedSog, BuildReadRoundTripWithinBudget) {
    const fs::path d = fresh_dir("round");
    lod::LodBuildOptions o;
    o.levels = 3, o.ratio = 4, o.chunk_count = 4096,
    o.memory_budget = 16u << 20;  // above one input chunk (65,536 rows)
    const std::uint64_t n = 200000;
    auto stats = lod::build_streamed_sog(lod::synthetic_gaussian_source(n), d / "lod-meta.json", o);
    ASSERT_TRUE(stats) << stats.message();
    EXPECT_GT(stats->cells, 1u);
    EXPECT_LE(stats->peak_bytes, o.memory_budget);
    auto s = lod::open_streamed_sog(d / "lod-meta.json");
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(s->levels, 3);
    EXPECT_EQ(s->counts[0], n);
    // Median splits stop once a group holds at most `ratio`: groups of 2 to 4 (a part of 5 splits 2 + 3).
    EXPECT_GE(s->counts[1], n / 4);
    EXPECT_LE(s->counts[1], n / 2);
    EXPECT_GE(s->counts[2], s->counts[1] / 4);
    EXPECT_LE(s->counts[2], s->counts[1] / 2);
    auto leaves = lod::read_level(*s, 0);
    ASSERT_TRUE(leaves) << leaves.message();
    ASSERT_EQ(leaves->size(), n);
    // Every input centre has a leaf within the 16-bit log-space step (nearest by a sort on x).
    GaussianCloud ref;
    ASSERT_TRUE(lod::synthetic_gaussian_source(n).scan([&](const GaussianCloud& g) -> Status {
        ref.positions.insert(ref.positions.end(), g.positions.begin(), g.positions.end());
        return {};
    }));
    auto key = [](const glm::vec3& p) {
        return std::make_tuple(std::lround(p.x * 200), std::lround(p.y * 200), std::lround(p.z * 200));
    };
    std::multiset<std::tuple<long, long, long>> got;
    for (std::size_t i = 0; i < leaves->size(); ++i)
        got.insert(key(glm::vec3(leaves->origin + glm::dvec3(leaves->positions[i]))));
    std::size_t matched = 0;
    for (const glm::vec3& p : ref.positions) matched += got.count(key(p)) > 0;
    EXPECT_GT(double(matched), 0.95 * double(n));  // rounding at a key's edge misses a few
    auto coarse = lod::read_level(*s, 2);
    ASSERT_TRUE(coarse) << coarse.message();
    EXPECT_EQ(coarse->size(), s->counts[2]);
}

TEST(StreamedSog, HostileAndTruncatedManifestsAreRefused) {
    const fs::path d = fresh_dir("hostile");
    lod::LodBuildOptions o;
    o.levels = 2, o.chunk_count = 2048;
    ASSERT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(5000), d / "lod-meta.json", o));
    const std::string good = read_text(d / "lod-meta.json");
    ASSERT_TRUE(lod::open_streamed_sog(d / "lod-meta.json"));
    const auto refused = [&](const std::string& text, const std::string& needle) {
        write_text(d / "lod-meta.json", text);
        auto s = lod::open_streamed_sog(d / "lod-meta.json");
        ASSERT_FALSE(s) << needle;
        EXPECT_NE(s.message().find("lod-meta.json"), std::string::npos) << s.message();
        EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
    };
    for (std::size_t cut : {std::size_t(0), good.size() / 2, good.size() - 1})
        refused(good.substr(0, cut), "JSON");
    auto replace = [&](const std::string& from, const std::string& to) {
        std::string t = good;
        const auto at = t.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return at == std::string::npos ? t : t.replace(at, from.size(), to);
    };
    refused(replace("\"offset\":0", "\"offset\":9007199254740000"), "0_0/meta.json");
    refused(replace("\"counts\":[", "\"counts\":[900000000000,"), "counts");
    refused(replace("\"0_0/meta.json\"", "\"../0_0/meta.json\""), "relative path");
    refused(replace("\"lodLevels\":2", "\"lodLevels\":4000000000"), "lodLevels");
    // A unit's meta.json truncated: named.
    write_text(d / "lod-meta.json", good);
    const std::string unit = read_text(d / "0_0" / "meta.json");
    write_text(d / "0_0" / "meta.json", unit.substr(0, unit.size() / 2));
    auto s = lod::open_streamed_sog(d / "lod-meta.json");
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("0_0/meta.json"), std::string::npos) << s.message();
    write_text(d / "0_0" / "meta.json", unit);
    // A truncated image is refused when its unit is decoded, naming the image.
    const fs::path img = d / "0_0" / "means_l.webp";
    const std::string bytes = read_text(img);
    write_text(img, bytes.substr(0, bytes.size() / 2));
    auto opened = lod::open_streamed_sog(d / "lod-meta.json");
    ASSERT_TRUE(opened) << opened.message();
    auto level = lod::read_level(*opened, 0);
    ASSERT_FALSE(level);
    EXPECT_NE(level.message().find("means_l.webp"), std::string::npos) << level.message();
}

}  // namespace
