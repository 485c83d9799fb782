#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/assets/formats/gaussian/gaussian_infinity.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kRows = 1 << 16;
constexpr std::uint64_t kSplatsPerChunk = 256;

double unorm(std::uint32_t v, int bits) {
    const std::uint32_t t = (1u << bits) - 1u;
    return double(v & t) / double(t);
}

// a·(1 − t) + b·t, exact at the ends so an infinite bound (a -inf log scale) stays itself at its own
// end instead of turning into inf·0 = NaN at the other.
double lerp(double a, double b, double t) {
    if (t <= 0.0) return a;
    if (t >= 1.0) return b;
    return a * (1.0 - t) + b * t;
}

// Column index of a scalar property, or -1 with the name added to `missing`.
int need(const ply::Element& e, const std::string& prop, std::string& missing) {
    const int at = e.find(prop);
    if (at < 0 || e.properties[std::size_t(at)].is_list) {
        missing += (missing.empty() ? "" : ", ") + e.name + "." + prop;
        return -1;
    }
    return at;
}

}  // namespace

bool is_compressed_ply(const ply::Header& h) {
    const int v = h.find("vertex");
    return h.find("chunk") >= 0 && v >= 0 && h.elements[std::size_t(v)].find("packed_position") >= 0;
}

Result<GaussianCloud> read_compressed_ply(const fs::path& path) {
    const std::string name = path.string();
    auto fail = [&](const std::string& why) { return make_error(name + ": " + why); };
    auto reader = ply::Reader::open(path);  // refuses declared counts the file size cannot hold
    if (!reader) return reader.error();
    const ply::Header& h = reader->header();
    const int ci = h.find("chunk"), vi = h.find("vertex"), si = h.find("sh");
    if (ci < 0 || vi < 0) return fail("not a compressed PLY (needs chunk and vertex elements)");
    const ply::Element& ce = h.elements[std::size_t(ci)];
    const ply::Element& ve = h.elements[std::size_t(vi)];
    const std::uint64_t n = ve.count;

    std::string missing;
    static const char* kBounds[12] = {"min_x",       "min_y",       "min_z",       "max_x",
                                      "max_y",       "max_z",       "min_scale_x", "min_scale_y",
                                      "min_scale_z", "max_scale_x", "max_scale_y", "max_scale_z"};
    int bound[12];
    for (int i = 0; i < 12; ++i) bound[i] = need(ce, kBounds[i], missing);
    static const char* kColour[6] = {"min_r", "min_g", "min_b", "max_r", "max_g", "max_b"};
    const bool colour_bounds = ce.find("min_r") >= 0;
    int cbound[6] = {-1, -1, -1, -1, -1, -1};
    if (colour_bounds)
        for (int i = 0; i < 6; ++i) cbound[i] = need(ce, kColour[i], missing);
    const int pp = need(ve, "packed_position", missing), pr = need(ve, "packed_rotation", missing);
    const int ps = need(ve, "packed_scale", missing), pc = need(ve, "packed_color", missing);
    if (!missing.empty()) return fail("compressed PLY lacks " + missing);
    if (ce.count != (n + kSplatsPerChunk - 1) / kSplatsPerChunk)
        return fail("compressed PLY has " + std::to_string(ce.count) + " chunks for " + std::to_string(n) +
                    " splats (expected " + std::to_string((n + kSplatsPerChunk - 1) / kSplatsPerChunk) +
                    ", one per 256)");

    int degree = 0;
    std::vector<int> rest;
    if (si >= 0) {
        const ply::Element& se = h.elements[std::size_t(si)];
        if (se.count != n)
            return fail("sh element has " + std::to_string(se.count) + " rows for " + std::to_string(n) +
                        " splats");
        const std::size_t count = se.properties.size();
        degree = -1;
        for (int d = 1; d <= 3; ++d)
            if (count == std::size_t(3 * (sh_coeffs(d) - 1))) degree = d;
        if (degree < 0)
            return fail("sh element has " + std::to_string(count) +
                        " properties: expected 9, 24 or 45 (SH degree 1, 2 or 3)");
        for (std::size_t i = 0; i < count; ++i)
            rest.push_back(need(se, "f_rest_" + std::to_string(i), missing));
        if (!missing.empty()) return fail("compressed PLY lacks " + missing);
    }

    // The chunk bounds: small (1/256 of the splats), read whole first.
    std::vector<double> bounds(std::size_t(ce.count) * 18, 0.0);
    if (auto s = reader->seek_element("chunk"); !s) return s.error();
    ply::Chunk rows;
    for (std::uint64_t at = 0; at < ce.count;) {
        auto got = reader->read_rows(kRows, rows);
        if (!got) return got.error();
        if (*got == 0) return fail("truncated chunk element");
        for (std::size_t r = 0; r < *got; ++r) {
            double* b = &bounds[std::size_t(at + r) * 18];
            for (int i = 0; i < 12; ++i) b[i] = rows.columns[std::size_t(bound[i])].values[r];
            for (int i = 0; i < 6; ++i)
                b[12 + i] = colour_bounds ? rows.columns[std::size_t(cbound[i])].values[r] : double(i / 3);
            for (int i : {0, 1, 2, 3, 4, 5, 12, 13, 14, 15, 16, 17})
                if (!std::isfinite(b[i]))
                    return fail("chunk " + std::to_string(at + r) + ": non-finite '" +
                                (i < 12 ? kBounds[i] : kColour[i - 12]) + "'");
            for (int i = 6; i < 12; ++i)
                if (std::isnan(b[i]) || (std::isinf(b[i]) && b[i] > 0))
                    return fail("chunk " + std::to_string(at + r) + ": '" + kBounds[i] + "' is NaN or +inf");
        }
        at += *got;
    }

    GaussianCloud g;
    g.sh_degree = degree;
    const int K = sh_coeffs(degree);
    g.positions.reserve(n), g.scales.reserve(n), g.rotations.reserve(n), g.opacities.reserve(n);
    g.sh.assign(std::size_t(n) * std::size_t(K) * 3, 0.0f);
    InfinityCount mapped;
    if (auto s = reader->seek_element("vertex"); !s) return s.error();
    for (std::uint64_t at = 0; at < n;) {
        auto got = reader->read_rows(kRows, rows);
        if (!got) return got.error();
        if (*got == 0) return fail("truncated vertex element");
        for (std::size_t r = 0; r < *got; ++r) {
            const std::uint64_t i = at + r;
            const double* b = &bounds[std::size_t(i / kSplatsPerChunk) * 18];
            std::uint32_t words[4];
            const int cols[4] = {pp, pr, ps, pc};
            for (int k = 0; k < 4; ++k) {
                const double v = rows.columns[std::size_t(cols[k])].values[r];
                // A float column could hold anything: only 32-bit unsigned integers are packed words.
                if (!(v >= 0.0 && v < 4294967296.0) || v != std::floor(v))
                    return fail("splat " + std::to_string(i) + ": '" +
                                ve.properties[std::size_t(cols[k])].name +
                                "' is not a 32-bit unsigned integer");
                words[k] = std::uint32_t(v);
            }
            const std::uint32_t p = words[0], q = words[1], s = words[2], c = words[3];
            g.positions.emplace_back(float(lerp(b[0], b[3], unorm(p >> 21, 11))),
                                     float(lerp(b[1], b[4], unorm(p >> 11, 10))),
                                     float(lerp(b[2], b[5], unorm(p, 11))));
            const double t[3] = {unorm(s >> 21, 11), unorm(s >> 11, 10), unorm(s, 11)};
            glm::vec3 scale;
            for (int k = 0; k < 3; ++k)
                if (!scale_from_log(lerp(b[6 + k], b[9 + k], t[k]), scale[k], mapped))
                    return fail("splat " + std::to_string(i) + ": scale overflows (log scale too large)");
            g.scales.push_back(scale);
            const double norm = std::sqrt(2.0);  // the three smaller components lie in [-1/√2, 1/√2]
            const double a = (unorm(q >> 20, 10) - 0.5) * norm, bb = (unorm(q >> 10, 10) - 0.5) * norm,
                         cc = (unorm(q, 10) - 0.5) * norm;
            const double m = std::sqrt(std::max(0.0, 1.0 - (a * a + bb * bb + cc * cc)));
            double wxyz[4];
            switch (q >> 30) {
                case 0: wxyz[0] = m, wxyz[1] = a, wxyz[2] = bb, wxyz[3] = cc; break;
                case 1: wxyz[0] = a, wxyz[1] = m, wxyz[2] = bb, wxyz[3] = cc; break;
                case 2: wxyz[0] = a, wxyz[1] = bb, wxyz[2] = m, wxyz[3] = cc; break;
                default: wxyz[0] = a, wxyz[1] = bb, wxyz[2] = cc, wxyz[3] = m; break;
            }
            const double len =
                std::sqrt(wxyz[0] * wxyz[0] + wxyz[1] * wxyz[1] + wxyz[2] * wxyz[2] + wxyz[3] * wxyz[3]);
            g.rotations.emplace_back(float(wxyz[0] / len), float(wxyz[1] / len), float(wxyz[2] / len),
                                     float(wxyz[3] / len));
            g.opacities.push_back(float(unorm(c, 8)));
            const double rgb[3] = {unorm(c >> 24, 8), unorm(c >> 16, 8), unorm(c >> 8, 8)};
            for (int k = 0; k < 3; ++k)
                g.sh[std::size_t(i) * std::size_t(K) * 3 + std::size_t(k)] =
                    float((lerp(b[12 + k], b[15 + k], rgb[k]) - 0.5) / kShDc);
        }
        at += *got;
    }
    if (si >= 0) {
        if (auto s = reader->seek_element("sh"); !s) return s.error();
        for (std::uint64_t at = 0; at < n;) {
            auto got = reader->read_rows(kRows, rows);
            if (!got) return got.error();
            if (*got == 0) return fail("truncated sh element");
            for (std::size_t r = 0; r < *got; ++r)
                for (int ch = 0; ch < 3; ++ch)
                    for (int k = 1; k < K; ++k) {
                        const double byte =
                            rows.columns[std::size_t(rest[std::size_t(ch * (K - 1) + (k - 1))])].values[r];
                        if (!std::isfinite(byte))
                            return fail("sh row " + std::to_string(at + r) + ": non-finite value");
                        const double unit = byte <= 0.0 ? 0.0 : byte >= 255.0 ? 1.0 : (byte + 0.5) / 256.0;
                        g.sh[(std::size_t(at + r) * std::size_t(K) + std::size_t(k)) * 3 + std::size_t(ch)] =
                            float((unit - 0.5) * 8.0);
                    }
            at += *got;
        }
    }
    report_infinities(name, mapped);
    return g;
}

namespace {

// Round-to-nearest quantisation of t in [0, 1] to `bits`.
std::uint32_t quantise(double t, int bits) {
    const double top = double((1u << bits) - 1u);
    return std::uint32_t(std::lround(std::clamp(t, 0.0, 1.0) * top));
}

// Position of v within [lo, hi] (0 when the range is empty).
double unit_in(double v, double lo, double hi) { return hi > lo ? (v - lo) / (hi - lo) : 0.0; }

ply::Element element(const std::string& name, std::uint64_t count, std::initializer_list<const char*> props,
                     ply::Type type) {
    ply::Element e;
    e.name = name;
    e.count = count;
    for (const char* p : props) e.properties.push_back({p, type, false, ply::Type::uint8});
    return e;
}

}  // namespace

Status write_compressed_ply(const fs::path& path, const GaussianCloud& g) {
    if (auto s = validate(g, path.string()); !s) return s;
    const std::size_t n = g.size();
    const std::size_t chunks = (n + kSplatsPerChunk - 1) / kSplatsPerChunk;
    const int K = sh_coeffs(g.sh_degree);
    ply::Header h;
    h.format = ply::Format::binary_little_endian;
    h.comments.push_back("compressed 3D Gaussian splats (PlayCanvas layout) written by splatffd");
    h.elements.push_back(element(
        "chunk", chunks,
        {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z", "min_scale_x", "min_scale_y", "min_scale_z",
         "max_scale_x", "max_scale_y", "max_scale_z", "min_r", "min_g", "min_b", "max_r", "max_g", "max_b"},
        ply::Type::float32));
    h.elements.push_back(element("vertex", n,
                                 {"packed_position", "packed_rotation", "packed_scale", "packed_color"},
                                 ply::Type::uint32));
    if (g.sh_degree > 0) {
        ply::Element e;
        e.name = "sh";
        e.count = n;
        for (int i = 0; i < 3 * (K - 1); ++i)
            e.properties.push_back(
                {"f_rest_" + std::to_string(i), ply::Type::uint8, false, ply::Type::uint8});
        h.elements.push_back(e);
    }
    auto writer = ply::Writer::create(path, h);
    if (!writer) return writer.error();

    // Per splat in file units: centre, log scale, colour (0.5 + C0 f_dc).
    auto centre = [&](std::size_t i) { return g.origin + glm::dvec3(g.positions[i]); };
    auto log_scale = [&](std::size_t i, int c) { return std::log(std::max(double(g.scales[i][c]), 1e-30)); };
    auto colour = [&](std::size_t i, int c) {
        return 0.5 + kShDc * double(g.sh[i * std::size_t(K) * 3 + std::size_t(c)]);
    };
    // The bounds as the file stores them (float), so quantising against them matches what a reader sees.
    std::vector<double> bounds(chunks * 18);
    ply::Chunk rows;
    rows.reset(h.elements[0]);
    rows.rows = chunks;
    for (ply::Column& c : rows.columns) c.values.resize(chunks);
    for (std::size_t k = 0; k < chunks; ++k) {
        double lo[9], hi[9];
        std::fill(lo, lo + 9, INFINITY), std::fill(hi, hi + 9, -INFINITY);
        for (std::size_t i = k * kSplatsPerChunk; i < std::min(n, (k + 1) * kSplatsPerChunk); ++i)
            for (int c = 0; c < 3; ++c) {
                const double v[3] = {centre(i)[c], log_scale(i, c), colour(i, c)};
                for (int a = 0; a < 3; ++a)
                    lo[a * 3 + c] = std::min(lo[a * 3 + c], v[a]),
                               hi[a * 3 + c] = std::max(hi[a * 3 + c], v[a]);
            }
        double* b = &bounds[k * 18];
        for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c) {
                // Round outwards to float so every value stays inside the stored range.
                float flo = float(lo[a * 3 + c]), fhi = float(hi[a * 3 + c]);
                if (double(flo) > lo[a * 3 + c]) flo = std::nextafter(flo, -INFINITY);
                if (double(fhi) < hi[a * 3 + c]) fhi = std::nextafter(fhi, INFINITY);
                b[a * 6 + c] = flo, b[a * 6 + 3 + c] = fhi;
            }
        for (int j = 0; j < 18; ++j) rows.columns[std::size_t(j)].values[k] = b[j];
    }
    if (auto s = writer->write_rows(rows); !s) return s;

    for (std::size_t first = 0; first < n; first += kRows) {
        const std::size_t count = std::min<std::size_t>(kRows, n - first);
        rows.reset(h.elements[1]);
        rows.rows = count;
        for (ply::Column& c : rows.columns) c.values.resize(count);
        for (std::size_t r = 0; r < count; ++r) {
            const std::size_t i = first + r;
            const double* b = &bounds[(i / kSplatsPerChunk) * 18];
            const glm::dvec3 p = centre(i);
            const std::uint32_t pp = quantise(unit_in(p.x, b[0], b[3]), 11) << 21 |
                                     quantise(unit_in(p.y, b[1], b[4]), 10) << 11 |
                                     quantise(unit_in(p.z, b[2], b[5]), 11);
            const std::uint32_t ps = quantise(unit_in(log_scale(i, 0), b[6], b[9]), 11) << 21 |
                                     quantise(unit_in(log_scale(i, 1), b[7], b[10]), 10) << 11 |
                                     quantise(unit_in(log_scale(i, 2), b[8], b[11]), 11);
            const glm::quat q = g.rotations[i];
            double wxyz[4] = {q.w, q.x, q.y, q.z};
            int largest = 0;
            for (int c = 1; c < 4; ++c)
                if (std::abs(wxyz[c]) > std::abs(wxyz[largest])) largest = c;
            if (wxyz[largest] < 0)  // q and -q are the same rotation: make the dropped component positive
                for (double& c : wxyz) c = -c;
            std::uint32_t pr = std::uint32_t(largest) << 30;
            int shift = 20;
            for (int c = 0; c < 4; ++c)
                if (c != largest) pr |= quantise(wxyz[c] / std::sqrt(2.0) + 0.5, 10) << shift, shift -= 10;
            const std::uint32_t pc = quantise(unit_in(colour(i, 0), b[12], b[15]), 8) << 24 |
                                     quantise(unit_in(colour(i, 1), b[13], b[16]), 8) << 16 |
                                     quantise(unit_in(colour(i, 2), b[14], b[17]), 8) << 8 |
                                     quantise(g.opacities[i], 8);
            rows.columns[0].values[r] = pp, rows.columns[1].values[r] = pr, rows.columns[2].values[r] = ps,
            rows.columns[3].values[r] = pc;
        }
        if (auto s = writer->write_rows(rows); !s) return s;
    }
    if (g.sh_degree > 0) {
        for (std::size_t first = 0; first < n; first += kRows) {
            const std::size_t count = std::min<std::size_t>(kRows, n - first);
            rows.reset(h.elements[2]);
            rows.rows = count;
            for (ply::Column& c : rows.columns) c.values.resize(count);
            for (std::size_t r = 0; r < count; ++r)
                for (int ch = 0; ch < 3; ++ch)
                    for (int k = 1; k < K; ++k) {
                        // Inverse of the reader's (b + 0.5)/256 decode: b = 32 v + 127.5, rounded.
                        const double v =
                            g.sh[((first + r) * std::size_t(K) + std::size_t(k)) * 3 + std::size_t(ch)];
                        rows.columns[std::size_t(ch * (K - 1) + (k - 1))].values[r] =
                            std::clamp(std::round(32.0 * v + 127.5), 0.0, 255.0);
                    }
            if (auto s = writer->write_rows(rows); !s) return s;
        }
    }
    return writer->finish();
}

}  // namespace sffd::gaussian
