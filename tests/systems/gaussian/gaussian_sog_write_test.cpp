// The SOG writer (gaussian_sog.h write_sog) through our reader: every Gaussian back within the bounds the
// header states, computed here from the input (positions from its own log-space range, rotations from the
// smallest-three step, opacity 1/510, scales and DC colours within the distance to the nearest value of
// the file's own codebook); codebooks exact for up to 256 distinct values; the SH palette exact for up to
// its size of distinct band vectors; the quantiser alone (gaussian_sog_quantize.h) against brute force;
// refusals and failed writes that leave nothing behind.
#include <gtest/gtest.h>

#include <unistd.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <tuple>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_sog_quantize.h"
#include "tests/systems/gaussian/sog_bounds.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;
using json = nlohmann::json;
using test::sog::Errors;
using test::sog::expect_within_quantisation;
using test::sog::meta_of;
using test::sog::nearest;
using test::sog::slurp;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_sog_write_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

// A capture away from the origin (origin + positions spanning a few units), anisotropic scales over two
// decades, random rotations, opacities in [0, 1], SH of `degree`.
GaussianCloud cloud(std::size_t n, int degree, unsigned seed = 3, std::size_t prototypes = 0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.origin = {10.0, -3.0, 0.5};
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(4.0f * u(rng), 2.0f * u(rng), 6.0f * u(rng));
        g.scales.emplace_back(std::exp(2.3f * u(rng) - 3.0f), std::exp(2.3f * u(rng) - 3.0f),
                              0.02f + 0.01f * u(rng));
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.5f + 0.5f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(k < 3 ? 1.5f * u(rng) : 0.3f * u(rng));
    }
    // Captured bands are far from independent noise: when asked, each Gaussian's bands are one of a few
    // `prototypes` plus a little noise.
    if (prototypes > 0 && degree > 0) {
        const std::size_t rest = std::size_t(sh_coeffs(degree) * 3 - 3);
        std::vector<float> proto(prototypes * rest);
        for (float& x : proto) x = 0.3f * u(rng);
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t p = rng() % prototypes;
            for (std::size_t k = 0; k < rest; ++k)
                g.sh[i * (rest + 3) + 3 + k] = proto[p * rest + k] + 0.01f * u(rng);
        }
    }
    return g;
}

void round_trip(int degree, const std::string& name) {
    const GaussianCloud g = cloud(5000, degree, 3, 1500);
    fs::path p = temp(name);
    if (p.extension() != ".sog") fs::create_directories(p), p /= "meta.json";
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    const json meta = meta_of(p);
    const Errors e = expect_within_quantisation(g, *back, meta);
    std::printf(
        "  %s degree %d: position %.2e (relative to 1+|x|), rotation %.2e, opacity %.2e, log scale %.2e, "
        "dc %.2e, bands rms %.3f of the signal\n",
        name.c_str(), degree, e.position, e.rotation, e.opacity, e.log_scale, e.dc, e.bands_rms);
    if (degree > 0) {
        // 5000 Gaussians get a palette of 4096 entries for their 1500 prototypes: what clustering loses
        // stays a small part of the signal, and every decoded coefficient is a value of the file's SH
        // codebook.
        EXPECT_EQ(meta["shN"]["count"].get<int>(), 4096);
        EXPECT_EQ(meta["shN"]["bands"].get<int>(), degree);
        EXPECT_LT(e.bands_rms, 0.1);
        for (std::size_t i = 0; i < g.size(); i += 97)
            EXPECT_LT(nearest(meta["shN"]["codebook"], back->sh[i * std::size_t(sh_coeffs(degree)) * 3 + 3]),
                      1e-7)
                << i;
    } else {
        EXPECT_FALSE(meta.contains("shN"));
    }
}

TEST(SogWrite, Degree0ArchiveReadsBackWithinTheQuantisation) { round_trip(0, "d0.sog"); }
TEST(SogWrite, Degree0FolderReadsBackWithinTheQuantisation) { round_trip(0, "d0_folder"); }
TEST(SogWrite, Degree3ArchiveReadsBackWithinTheQuantisation) { round_trip(3, "d3.sog"); }
TEST(SogWrite, Degree3FolderReadsBackWithinTheQuantisation) { round_trip(3, "d3_folder"); }

TEST(SogWrite, MortonOrderIsAPermutationAlongTheCurveAndSmaller) {
    const GaussianCloud g = cloud(5000, 0);
    const fs::path kept = temp("kept.sog"), morton = temp("morton.sog");
    ASSERT_TRUE(write_sog(kept, g));
    ASSERT_TRUE(write_sog(morton, g, {.morton_order = true}));
    auto a = read_gaussians(kept), b = read_gaussians(morton);
    ASSERT_TRUE(a && b);
    ASSERT_EQ(b->size(), g.size());
    // The same Gaussians, bit for bit (the codebooks do not depend on the order), in another order.
    const auto sorted = [](const GaussianCloud& c) {
        std::vector<std::tuple<float, float, float, float, float, float, float, float, float, float, float>>
            v;
        for (std::size_t i = 0; i < c.size(); ++i)
            v.emplace_back(c.positions[i].x, c.positions[i].y, c.positions[i].z, c.scales[i].x, c.scales[i].y,
                           c.scales[i].z, c.rotations[i].w, c.rotations[i].x, c.opacities[i], c.sh[i * 3],
                           c.sh[i * 3 + 2]);
        std::sort(v.begin(), v.end());
        return v;
    };
    EXPECT_EQ(sorted(*a), sorted(*b));
    std::size_t moved = 0;
    for (std::size_t i = 0; i < g.size(); ++i) moved += a->positions[i] != b->positions[i];
    EXPECT_GT(moved, g.size() / 2);
    // Along the texels, the Morton codes of the 16-bit centres (recovered from the file's bounds) never
    // decrease.
    const json m = meta_of(morton);
    std::uint64_t previous = 0;
    for (std::size_t i = 0; i < b->size(); ++i) {
        std::uint64_t code = 0;
        unsigned q[3];
        for (int ax = 0; ax < 3; ++ax) {
            const double lo = m["means"]["mins"][ax].get<double>(), hi = m["means"]["maxs"][ax].get<double>();
            const double v = test::sog::log_transform(double(b->positions[i][ax]));
            q[ax] = unsigned(std::lround((v - lo) / (hi - lo) * 65535.0));
        }
        for (int bit = 15; bit >= 0; --bit)
            for (int ax = 0; ax < 3; ++ax) code = code << 1 | ((q[ax] >> bit) & 1u);
        ASSERT_GE(code, previous) << "texel " << i;
        previous = code;
    }
    std::printf("  5000 Gaussians: %zu bytes in cloud order, %zu along the Morton curve\n",
                std::size_t(fs::file_size(kept)), std::size_t(fs::file_size(morton)));
    EXPECT_LT(fs::file_size(morton), fs::file_size(kept));
}

TEST(SogWrite, FolderHoldsMetaAndImagesBesideIt) {
    const fs::path dir = temp("layout");
    fs::create_directories(dir);
    ASSERT_TRUE(write_sog(dir / "meta.json", cloud(300, 1)));
    for (const char* f : {"meta.json", "means_l.webp", "means_u.webp", "quats.webp", "scales.webp",
                          "sh0.webp", "shN_centroids.webp", "shN_labels.webp"})
        EXPECT_TRUE(fs::is_regular_file(dir / f)) << f;
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().filename().string().find("sffd-tmp"), std::string::npos) << entry.path();
    const json m = meta_of(dir / "meta.json");
    EXPECT_EQ(m["version"], 2);
    EXPECT_EQ(m["count"], 300);
    EXPECT_EQ(m["shN"]["count"], 256);  // splat-transform's size: 2^⌊log2 n⌋ up to 65536
}

TEST(SogWrite, UpTo256DistinctScalesAndColoursComeBackExactly) {
    GaussianCloud g = cloud(3000, 0);
    std::mt19937 rng(9);
    std::vector<float> scales, dcs;
    for (int k = 0; k < 200; ++k) scales.push_back(std::exp(-6.0f + 0.037f * float(k)));
    for (int k = 0; k < 256; ++k) dcs.push_back(-1.7f + 0.0131f * float(k));
    for (std::size_t i = 0; i < g.size(); ++i)
        for (int a = 0; a < 3; ++a) {
            g.scales[i][a] = scales[rng() % scales.size()];
            g.sh[i * 3 + std::size_t(a)] = dcs[rng() % dcs.size()];
            g.opacities[i] = float(rng() % 256) / 255.0f;
        }
    const fs::path p = temp("exact.sog");
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    for (std::size_t i = 0; i < g.size(); ++i) {
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(back->scales[i][a], g.scales[i][a]) << i;
            EXPECT_EQ(back->sh[i * 3 + std::size_t(a)], g.sh[i * 3 + std::size_t(a)]) << i;
        }
        EXPECT_EQ(back->opacities[i], g.opacities[i]) << i;  // multiples of 1/255
    }
}

TEST(SogWrite, FewDistinctBandVectorsComeBackExactly) {
    // 40 distinct band vectors built from 200 distinct coefficient values, over 3000 Gaussians (palette
    // 2048): the palette and its codebook keep them exactly.
    GaussianCloud g = cloud(3000, 3);
    std::mt19937 rng(4);
    std::vector<float> values;
    for (int k = 0; k < 200; ++k) values.push_back(-0.5f + 0.005f * float(k));
    std::vector<std::vector<float>> vectors(40);
    for (auto& v : vectors)
        for (int k = 0; k < 45; ++k) v.push_back(values[rng() % values.size()]);
    for (std::size_t i = 0; i < g.size(); ++i) {
        const auto& v = vectors[rng() % vectors.size()];
        std::copy(v.begin(), v.end(), g.sh.begin() + std::ptrdiff_t(i * 48 + 3));
    }
    const fs::path p = temp("bands.sog");
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(meta_of(p)["shN"]["count"], 40);
    for (std::size_t i = 0; i < g.size(); ++i)
        for (std::size_t k = 3; k < 48; ++k)
            ASSERT_EQ(back->sh[i * 48 + k], g.sh[i * 48 + k]) << i << " " << k;
}

TEST(SogWrite, ATransparentGaussianKeepsItsColour) {
    // sh0's alpha is the opacity: an encoder that cleans transparent texels would zero the colour indices.
    GaussianCloud g = cloud(500, 0);
    for (std::size_t i = 0; i < g.size(); i += 2) g.opacities[i] = 0.0f;
    const fs::path p = temp("transparent.sog");
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    expect_within_quantisation(g, *back, meta_of(p));
}

TEST(SogWrite, AZeroScaleGetsItsOwnCodebookEntry) {
    GaussianCloud g = cloud(400, 0);
    g.scales[7].z = 0.0f;
    const fs::path p = temp("flat.sog");
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    const json m = meta_of(p);
    double smallest = INFINITY;
    for (std::size_t i = 0; i < g.size(); ++i)
        for (int a = 0; a < 3; ++a)
            if (g.scales[i][a] > 0) smallest = std::min(smallest, std::log(double(g.scales[i][a])));
    EXPECT_NEAR(m["scales"]["codebook"][0].get<double>(), smallest - 20.0, 1e-9);
    EXPECT_LT(back->scales[7].z, 1e-8 * std::exp(smallest));
    EXPECT_NEAR(std::log(back->scales[8].x), std::log(g.scales[8].x), 0.05);
}

TEST(SogWrite, SmallCloudsReadBackWithinTheQuantisation) {
    // Image sides and palette sizes at their edges: 1 and 2 Gaussians (a palette entry each), 3 (palette 2),
    // 17 (images 8×4, palette 16), 1025 (palette 1024).
    for (const std::size_t n : {1u, 2u, 3u, 17u, 1025u}) {
        SCOPED_TRACE(n);
        const GaussianCloud g = cloud(n, 3, unsigned(n));
        const fs::path p = temp("small_" + std::to_string(n) + ".sog");
        ASSERT_TRUE(write_sog(p, g, {.morton_order = false}));
        auto back = read_gaussians(p);
        ASSERT_TRUE(back) << back.message();
        const json m = meta_of(p);
        expect_within_quantisation(g, *back, m);
        EXPECT_EQ(m["shN"]["count"].get<std::size_t>(), std::bit_floor(n));
        if (std::bit_floor(n) ==
            n) {  // each band vector its own entry: only the SH codebook's rounding is left
            for (std::size_t k = 0; k < back->sh.size(); ++k)
                if (k % 48 >= 3) {
                    EXPECT_LE(std::abs(back->sh[k] - g.sh[k]), nearest(m["shN"]["codebook"], g.sh[k]) + 1e-6)
                        << k;
                }
        }
    }
}

TEST(SogWrite, AnEmptyCloudIsAValidFile) {
    GaussianCloud g;
    g.sh_degree = 3;
    const fs::path p = temp("empty.sog");
    ASSERT_TRUE(write_sog(p, g));
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->size(), 0u);
    EXPECT_EQ(meta_of(p)["count"], 0);
}

TEST(SogWrite, RefusesWhatItCannotWriteAndLeavesNothingBehind) {
    const fs::path dir = temp("refusals");
    fs::create_directories(dir);
    const fs::path p = dir / "bad.sog";
    GaussianCloud frames = cloud(10, 0);
    frames.sh_frames.assign(10, glm::mat3(1.0f));
    Status s = write_sog(p, frames);
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message().rfind(p.string() + ": ", 0), 0u) << s.message();
    EXPECT_NE(s.message().find("SH frames"), std::string::npos) << s.message();

    GaussianCloud nan = cloud(10, 0);
    nan.positions[4].y = NAN;
    s = write_sog(p, nan);
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message().rfind(p.string() + ": Gaussian 4", 0), 0u) << s.message();
    GaussianCloud inf_sh = cloud(10, 2);
    inf_sh.sh[5 * 27 + 9] = INFINITY;
    s = write_sog(dir / "meta.json", inf_sh);
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("Gaussian 5"), std::string::npos) << s.message();

    s = write_sog(dir / "cloud.webp", cloud(10, 0));
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find(".sog archive or as a folder's meta.json"), std::string::npos) << s.message();

    const fs::path missing = dir / "no_such_folder" / "x.sog";
    s = write_sog(missing, cloud(10, 0));
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find(missing.string()), std::string::npos) << s.message();
    s = write_sog(dir / "no_such_folder" / "meta.json", cloud(10, 0));
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find((dir / "no_such_folder").string()), std::string::npos) << s.message();

    // Nothing was created by the refusals, and a good file is not replaced by a failed write.
    for (const auto& entry : fs::directory_iterator(dir)) ADD_FAILURE() << "left behind: " << entry.path();
    ASSERT_TRUE(write_sog(p, cloud(10, 0)));
    const std::string before = slurp(p);
    ASSERT_FALSE(write_sog(p, nan));
    EXPECT_EQ(slurp(p), before);
    ASSERT_TRUE(write_sog(dir / "meta.json", cloud(10, 0)));
    const std::string meta_before = slurp(dir / "meta.json"), means_before = slurp(dir / "means_l.webp");
    ASSERT_FALSE(write_sog(dir / "meta.json", inf_sh));
    EXPECT_EQ(slurp(dir / "meta.json"), meta_before);
    EXPECT_EQ(slurp(dir / "means_l.webp"), means_before);
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().filename().string().find("sffd-tmp"), std::string::npos) << entry.path();
}

TEST(SogWrite, AnUnwritableFolderIsRefusedByName) {
    if (getuid() == 0) GTEST_SKIP() << "root writes anywhere";
    const fs::path dir = temp("readonly");
    fs::create_directories(dir);
    fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec);
    const Status a = write_sog(dir / "x.sog", cloud(10, 0));
    const Status b = write_sog(dir / "meta.json", cloud(10, 0));
    fs::permissions(dir, fs::perms::owner_all);
    ASSERT_FALSE(a);
    EXPECT_NE(a.message().find((dir / "x.sog").string()), std::string::npos) << a.message();
    ASSERT_FALSE(b);
    EXPECT_NE(b.message().find(dir.string()), std::string::npos) << b.message();
    EXPECT_TRUE(fs::is_empty(dir));
}

// ---- the quantiser alone -------------------------------------------------------------------------------

TEST(SogQuantise, ACodebookLabelsEveryValueWithItsNearestEntry) {
    std::mt19937 rng(1);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<double> v;
    for (int i = 0; i < 20000; ++i) v.push_back(normal(rng) * (i % 10 == 0 ? 8.0 : 1.0));  // long tails
    const auto cb = sog_detail::codebook_1d(v);
    ASSERT_EQ(cb.values.size(), 256u);
    EXPECT_TRUE(std::is_sorted(cb.values.begin(), cb.values.end()));
    double worst = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const double err = std::abs(cb.values[cb.labels[i]] - v[i]);
        double best = INFINITY;
        for (const double c : cb.values) best = std::min(best, std::abs(c - v[i]));
        ASSERT_LE(err, best + 1e-12) << i;
        worst = std::max(worst, err);
    }
    // Better than 256 evenly spaced values over the range (what the dense centre would get without
    // clustering), in mean squared error.
    const double lo = *std::min_element(v.begin(), v.end()), hi = *std::max_element(v.begin(), v.end());
    double mse = 0, mse_uniform = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const double x = v[i];
        mse += std::pow(cb.values[cb.labels[i]] - x, 2);
        const double step = (hi - lo) / 255.0;
        mse_uniform += std::pow(lo + std::round((x - lo) / step) * step - x, 2);
    }
    std::printf("  codebook rms %.4f, evenly spaced %.4f, worst %.3f\n", std::sqrt(mse / double(v.size())),
                std::sqrt(mse_uniform / double(v.size())), worst);
    EXPECT_LT(mse, 0.5 * mse_uniform);
    std::set<double> distinct(cb.values.begin(), cb.values.end());
    EXPECT_GT(distinct.size(), 200u);
}

TEST(SogQuantise, ACodebookKeepsUpTo256DistinctValuesAndNegativeInfinity) {
    std::vector<double> v;
    for (int i = 0; i < 1000; ++i) v.push_back(std::ldexp(double(i % 255), -3) - 7.0);
    v.push_back(-INFINITY);
    const auto cb = sog_detail::codebook_1d(v);
    EXPECT_EQ(cb.values[0], -7.0 - 20.0);
    for (std::size_t i = 0; i < v.size(); ++i)
        EXPECT_EQ(cb.values[cb.labels[i]], i < 1000 ? v[i] : -27.0) << i;
}

TEST(SogQuantise, APaletteLabelsPointsWithTheirNearestCentroid) {
    // Flat k-means (n·k small): every label is the nearest centroid, every centroid is used.
    std::mt19937 rng(2);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    const std::size_t n = 3000, d = 9;
    std::vector<float> pts(n * d);
    for (float& x : pts) x = normal(rng);
    const auto pal = sog_detail::palette(pts.data(), n, d, d, 512);
    ASSERT_EQ(pal.count, 512u);
    ASSERT_EQ(pal.labels.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto dist = [&](std::size_t c) {
            double s = 0;
            for (std::size_t j = 0; j < d; ++j)
                s += std::pow(double(pts[i * d + j]) - double(pal.centroids[c * d + j]), 2);
            return s;
        };
        double best = INFINITY;
        for (std::size_t c = 0; c < pal.count; ++c) best = std::min(best, dist(c));
        ASSERT_LE(dist(pal.labels[i]), best * (1 + 1e-5) + 1e-9) << i;
    }
}

TEST(SogQuantise, ALargePaletteIsBuiltInTwoLevelsAndFitsTheData) {
    // n·k beyond one flat k-means: coarse clusters share the 8192 entries. Clustered data (2000 centres,
    // small noise) must come out near its centres, far better than the spread of the data.
    std::mt19937 rng(3);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    const std::size_t n = 40000, d = 24, centres = 2000;
    std::vector<float> c(centres * d), pts(n * d);
    for (float& x : c) x = normal(rng);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < d; ++j) pts[i * d + j] = c[(i % centres) * d + j] + 0.01f * normal(rng);
    const auto pal = sog_detail::palette(pts.data(), n, d, d, 8192);
    EXPECT_EQ(pal.count, 8192u);
    double err = 0;
    for (std::size_t i = 0; i < n; ++i) {
        ASSERT_LT(pal.labels[i], pal.count);
        for (std::size_t j = 0; j < d; ++j)
            err += std::pow(double(pts[i * d + j]) - double(pal.centroids[pal.labels[i] * d + j]), 2);
    }
    const double rms = std::sqrt(err / double(n * d));
    std::printf("  two-level palette rms %.4f (data spread 1, noise 0.01)\n", rms);
    EXPECT_LT(rms, 0.1);
}

}  // namespace
