// What the SOG tests share: meta.json of a written archive or folder, and the check that a cloud read back
// from SOG is the original within the quantisation gaussian_sog.h states, every bound computed from the
// original and the file's own codebooks. `steps` is the rounding of the fixed-point fields: ½ for a writer
// that rounds (ours), 1 for one that truncates (splat-transform).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "systems/gaussian/components.h"
#include "runtime/assets/formats/archive/gaussian_zip.h"

namespace sffd::test::sog {

namespace fs = std::filesystem;
using json = nlohmann::json;

inline std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

// meta.json of a written archive or folder.
inline json meta_of(const fs::path& p) {
    if (p.extension() == ".json") return json::parse(slurp(p));
    const std::string s = slurp(p);
    const std::vector<unsigned char> bytes(s.begin(), s.end());
    auto z = gaussian::ZipArchive::open(bytes);
    EXPECT_TRUE(z) << z.message();
    auto m = z->read("meta.json");
    EXPECT_TRUE(m) << m.message();
    return json::parse(std::string(m->begin(), m->end()));
}

inline double log_transform(double x) { return x < 0 ? -std::log1p(-x) : std::log1p(x); }

inline double nearest(const json& book, double v) {
    double best = INFINITY;
    for (const json& c : book) best = std::min(best, std::abs(c.get<double>() - v));
    return best;
}

// `back` (read from the SOG written from `g`) against `g`, each bound computed from `g` and the file's
// codebooks. Returns the largest errors seen, for the report.
struct Errors {
    double position = 0, rotation = 0, opacity = 0, log_scale = 0, dc = 0, bands_rms = 0;
};
inline Errors expect_within_quantisation(const GaussianCloud& g, const GaussianCloud& back, const json& meta,
                                         double steps = 0.5) {
    Errors e;
    EXPECT_EQ(back.size(), g.size());
    EXPECT_EQ(back.sh_degree, g.sh_degree);
    if (back.size() != g.size() || back.sh_degree != g.sh_degree) return e;
    const std::size_t n = g.size();
    const int K = sh_coeffs(g.sh_degree);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const double v = log_transform(g.origin[a] + double(g.positions[i][a]));
            lo[a] = std::min(lo[a], v), hi[a] = std::max(hi[a], v);
        }
    const double step = 2 * steps / (255.0 * std::sqrt(2.0));  // of a rotation component
    double band_err = 0, band_sum = 0;
    for (std::size_t i = 0; i < n; ++i) {
        for (int a = 0; a < 3; ++a) {
            const double x = g.origin[a] + double(g.positions[i][a]);
            const double bound =
                steps * (hi[a] - lo[a]) / 65535.0 * (1 + std::abs(x)) * 1.001 + 1.2e-7 * std::abs(x);
            const double err = std::abs(double(back.origin[a] + double(back.positions[i][a])) - x);
            EXPECT_LE(err, bound) << "Gaussian " << i << " axis " << a;
            e.position = std::max(e.position, err / (1 + std::abs(x)));
            const double v = std::log(double(g.scales[i][a]));
            const double ls = std::abs(std::log(double(back.scales[i][a])) - v);
            EXPECT_LE(ls, nearest(meta["scales"]["codebook"], v) + 1e-6)
                << "Gaussian " << i << " scale " << a;
            e.log_scale = std::max(e.log_scale, ls);
            const double dc = g.sh[i * std::size_t(K) * 3 + std::size_t(a)];
            const double de = std::abs(double(back.sh[i * std::size_t(K) * 3 + std::size_t(a)]) - dc);
            EXPECT_LE(de, nearest(meta["sh0"]["codebook"], dc) + 1e-6) << "Gaussian " << i << " dc " << a;
            e.dc = std::max(e.dc, de);
        }
        const double oe = std::abs(double(back.opacities[i]) - double(g.opacities[i]));
        EXPECT_LE(oe, steps / 255.0 + 1e-6) << "Gaussian " << i;
        e.opacity = std::max(e.opacity, oe);
        // Rotations up to sign: the three smaller components within one step, the largest (recomputed
        // as √(1 − Σc²)) within what those steps move it.
        glm::dquat q(g.rotations[i]), r(back.rotations[i]);
        q = glm::normalize(q);
        const double qc[4] = {q.w, q.x, q.y, q.z};
        int largest = 0;
        for (int c = 1; c < 4; ++c)
            if (std::abs(qc[c]) > std::abs(qc[largest])) largest = c;
        const double sign = qc[largest] < 0 ? -1 : 1;
        const double rc[4] = {r.w, r.x, r.y, r.z};
        double sum_small = 0;
        for (int c = 0; c < 4; ++c)
            if (c != largest) sum_small += std::abs(qc[c]);
        for (int c = 0; c < 4; ++c) {
            const double bound = c == largest
                                     ? (2 * sum_small * step + 3 * step * step) / std::abs(qc[largest]) + 1e-6
                                     : step + 1e-6;
            const double err = std::abs(rc[c] - sign * qc[c]);
            EXPECT_LE(err, bound) << "Gaussian " << i << " rotation component " << c;
            e.rotation = std::max(e.rotation, err);
        }
        for (std::size_t k = 3; k < std::size_t(K) * 3; ++k) {
            const double d = back.sh[i * std::size_t(K) * 3 + k] - g.sh[i * std::size_t(K) * 3 + k];
            band_err += d * d, band_sum += std::pow(double(g.sh[i * std::size_t(K) * 3 + k]), 2);
        }
    }
    e.bands_rms = band_sum > 0 ? std::sqrt(band_err / band_sum) : 0;
    return e;
}

}  // namespace sffd::test::sog
