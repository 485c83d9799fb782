// SOG writing (layout and quantisation in gaussian_sog.h), mirroring splat-transform's writer so its
// reader, the PlayCanvas engine and ours read the same Gaussians, except where it truncates: positions,
// rotation components and opacity are rounded to the nearest step here (the error bounds the header
// states are half a step). Gaussians keep the cloud's order (splat-transform sorts them along a Morton
// curve first): texel i is Gaussian i, so a sequence of frames written from one cloud lines up texel for
// texel.
#include <webp/encode.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "runtime/core/atomic_file.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_sog_quantize.h"
#include "runtime/assets/formats/archive/gaussian_zip_write.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

using json = nlohmann::ordered_json;
using sog_detail::Codebook;

struct Image {
    std::string name;
    int w = 0, h = 0;
    std::vector<std::uint8_t> rgba;
    std::string webp;
    bool ok = false;
    Image(std::string n, int width, int height)
        : name(std::move(n)), w(width), h(height), rgba(std::size_t(width) * std::size_t(height) * 4, 0) {}
    std::uint8_t* texel(std::size_t i) { return rgba.data() + i * 4; }
};

// Lossless and exact: the texels are indices and bit fields, so libwebp must not clean up the colour of
// transparent texels (sh0's alpha is the opacity: a Gaussian of opacity 0 keeps its colour indices).
bool encode(Image& im) {
    WebPConfig config;
    WebPPicture pic;
    if (!WebPConfigInit(&config) || !WebPPictureInit(&pic)) return false;
    config.lossless = 1, config.exact = 1, config.quality = 70, config.method = 4;
    pic.use_argb = 1, pic.width = im.w, pic.height = im.h;
    WebPMemoryWriter out;
    WebPMemoryWriterInit(&out);
    pic.writer = WebPMemoryWrite, pic.custom_ptr = &out;
    im.ok = WebPPictureImportRGBA(&pic, im.rgba.data(), im.w * 4) && WebPEncode(&config, &pic);
    WebPPictureFree(&pic);
    if (im.ok) im.webp.assign(reinterpret_cast<const char*>(out.mem), out.size);
    WebPMemoryWriterClear(&out);
    std::vector<std::uint8_t>().swap(im.rgba);
    return im.ok;
}

std::uint8_t byte(double v) { return std::uint8_t(std::clamp(std::lround(v), 0L, 255L)); }

double log_transform(double x) { return x < 0 ? -std::log1p(-x) : std::log1p(x); }

json book_json(const Codebook& c) {
    json a = json::array();
    for (const double v : c.values) a.push_back(v);
    return a;
}

struct Encoded {
    json meta;
    std::vector<Image> images;
};

Encoded encode_cloud(const GaussianCloud& g, const SogWriteOptions& options) {
    const std::size_t n = g.size();
    const int K = sh_coeffs(g.sh_degree);
    // splat-transform's sizes: a near-square, both sides multiples of 4 (4×4 for an empty cloud).
    const std::size_t side = std::size_t(std::ceil(std::sqrt(double(n))));
    const int w = int(std::max<std::size_t>(4, (side + 3) / 4 * 4));
    const int h = int(std::max<std::size_t>(4, (n + 4 * std::size_t(w) - 1) / (4 * std::size_t(w)) * 4));
    Encoded e;
    auto& im = e.images;
    im.reserve(7);
    for (const char* name : {"means_l.webp", "means_u.webp", "quats.webp", "scales.webp", "sh0.webp"})
        im.emplace_back(name, w, h);
    Image &lo = im[0], &hi = im[1], &quats = im[2], &scales = im[3], &sh0 = im[4];

    // Means: 16 bits per axis of v = sign(x)·ln(1 + |x|) over the per-axis range of the absolute positions.
    double mins[3] = {INFINITY, INFINITY, INFINITY}, maxs[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const double v = log_transform(g.origin[a] + double(g.positions[i][a]));
            mins[a] = std::min(mins[a], v), maxs[a] = std::max(maxs[a], v);
        }
    if (n == 0) std::fill(mins, mins + 3, 0.0), std::fill(maxs, maxs + 3, 0.0);

    // The codebooks and the palette, side by side.
    Codebook scale_book, dc_book;
    sog_detail::Palette pal;
    const std::size_t dims = std::size_t(3 * (K - 1));
    const std::size_t palette_size = n == 0 ? 0 : std::min<std::size_t>(65536, std::bit_floor(n));
    tbb::parallel_invoke(
        [&] {
            std::vector<double> v(n * 3);
            for (int c = 0; c < 3; ++c)
                for (std::size_t i = 0; i < n; ++i)
                    v[std::size_t(c) * n + i] =
                        g.scales[i][c] > 0 ? std::log(double(g.scales[i][c])) : -double(INFINITY);
            scale_book = sog_detail::codebook_1d(v);
        },
        [&] {
            std::vector<double> v(n * 3);
            for (int c = 0; c < 3; ++c)
                for (std::size_t i = 0; i < n; ++i)
                    v[std::size_t(c) * n + i] = g.sh[i * std::size_t(K) * 3 + std::size_t(c)];
            dc_book = sog_detail::codebook_1d(v);
        },
        [&] {
            if (K > 1) pal = sog_detail::palette(g.sh.data() + 3, n, std::size_t(K) * 3, dims, palette_size);
        });

    // The 16-bit centres, and where each Gaussian goes: texel i, or its place along the Morton curve of
    // those centres (48-bit codes, ties in cloud order).
    std::vector<std::uint16_t> q16(n * 3);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                for (int a = 0; a < 3; ++a) {
                    const double range = maxs[a] - mins[a];
                    const double v = log_transform(g.origin[a] + double(g.positions[i][a]));
                    q16[i * 3 + std::size_t(a)] = std::uint16_t(
                        range > 0 ? std::clamp(std::lround((v - mins[a]) / range * 65535.0), 0L, 65535L)
                                  : 0L);
                }
        });
    std::vector<std::uint32_t> slot;
    if (options.morton_order) {
        std::vector<std::pair<std::uint64_t, std::uint32_t>> codes(n);
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
            std::uint64_t code = 0;
            for (int bit = 15; bit >= 0; --bit)
                for (int a = 0; a < 3; ++a) code = code << 1 | ((q16[i * 3 + std::size_t(a)] >> bit) & 1u);
            codes[i] = {code, std::uint32_t(i)};
        });
        tbb::parallel_sort(codes.begin(), codes.end());
        slot.resize(n);
        for (std::size_t t = 0; t < n; ++t) slot[codes[t].second] = std::uint32_t(t);
    }
    const auto texel_of = [&](std::size_t i) { return slot.empty() ? i : std::size_t(slot[i]); };

    static const int kOthers[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::size_t t = texel_of(i);
                for (int a = 0; a < 3; ++a) {
                    const unsigned q = q16[i * 3 + std::size_t(a)];
                    lo.texel(t)[a] = std::uint8_t(q & 0xff), hi.texel(t)[a] = std::uint8_t(q >> 8);
                    scales.texel(t)[a] = scale_book.labels[std::size_t(a) * n + i];
                    sh0.texel(t)[a] = dc_book.labels[std::size_t(a) * n + i];
                }
                lo.texel(t)[3] = hi.texel(t)[3] = scales.texel(t)[3] = 255;
                sh0.texel(t)[3] = byte(double(g.opacities[i]) * 255.0);
                // Smallest three: the largest component (w x y z order) made positive and dropped.
                const glm::quat& q = g.rotations[i];
                double wxyz[4] = {q.w, q.x, q.y, q.z};
                const double len =
                    std::sqrt(wxyz[0] * wxyz[0] + wxyz[1] * wxyz[1] + wxyz[2] * wxyz[2] + wxyz[3] * wxyz[3]);
                int largest = 0;
                for (int c = 1; c < 4; ++c)
                    if (std::abs(wxyz[c]) > std::abs(wxyz[largest])) largest = c;
                const double s = (wxyz[largest] < 0 ? -1.0 : 1.0) * std::sqrt(2.0) / len;
                for (int k = 0; k < 3; ++k)
                    quats.texel(t)[k] = byte((wxyz[kOthers[largest][k]] * s * 0.5 + 0.5) * 255.0);
                quats.texel(t)[3] = std::uint8_t(252 + largest);
            }
        });

    json& m = e.meta;
    m["version"] = 2;
    m["asset"] = {{"generator", "splatffd"}};
    m["count"] = n;
    m["means"] = {{"mins", {mins[0], mins[1], mins[2]}},
                  {"maxs", {maxs[0], maxs[1], maxs[2]}},
                  {"files", {"means_l.webp", "means_u.webp"}}};
    m["scales"] = {{"codebook", book_json(scale_book)}, {"files", {"scales.webp"}}};
    m["quats"] = {{"files", {"quats.webp"}}};
    m["sh0"] = {{"codebook", book_json(dc_book)}, {"files", {"sh0.webp"}}};
    if (K > 1) {
        // The palette's coefficients through one more codebook; entry e at texel (e mod 64)·(K − 1) + j of
        // row e / 64 holds coefficient j + 1.
        std::vector<double> v(pal.centroids.begin(), pal.centroids.end());
        const Codebook sh_book = sog_detail::codebook_1d(v);
        const int cw = 64 * (K - 1), ch = int(std::max<std::size_t>(1, (pal.count + 63) / 64));
        Image& cent = im.emplace_back("shN_centroids.webp", cw, ch);
        for (std::size_t p = 0; p < pal.count; ++p)
            for (int j = 0; j < K - 1; ++j) {
                std::uint8_t* t =
                    cent.texel((p / 64) * std::size_t(cw) + (p % 64) * std::size_t(K - 1) + std::size_t(j));
                for (int c = 0; c < 3; ++c)
                    t[c] = sh_book.labels[p * dims + std::size_t(j) * 3 + std::size_t(c)];
                t[3] = 255;
            }
        Image& labels = im.emplace_back("shN_labels.webp", w, h);
        for (std::size_t i = 0; i < n; ++i) {
            std::uint8_t* t = labels.texel(texel_of(i));
            t[0] = std::uint8_t(pal.labels[i] & 0xff), t[1] = std::uint8_t(pal.labels[i] >> 8), t[3] = 255;
        }
        m["shN"] = {{"count", pal.count},
                    {"bands", g.sh_degree},
                    {"codebook", book_json(sh_book)},
                    {"files", {"shN_centroids.webp", "shN_labels.webp"}}};
    }
    tbb::parallel_for(
        std::size_t(0), im.size(), [&](std::size_t i) { encode(im[i]); }, tbb::simple_partitioner());
    return e;
}

}  // namespace

Status write_sog(const fs::path& path, const GaussianCloud& cloud, const SogWriteOptions& options) {
    const std::string name = path.string();
    const bool archive = path.extension() == ".sog", folder = path.filename() == "meta.json";
    if (!archive && !folder)
        return make_error(name + ": SOG is written as a .sog archive or as a folder's meta.json");
    if (cloud.size() > kMaxGaussians)
        return make_error(name + ": " + std::to_string(cloud.size()) + " Gaussians, more than the " +
                          std::to_string(kMaxGaussians) + " limit");
    if (Status s = validate(cloud, name); !s) return s;
    Encoded e = encode_cloud(cloud, options);
    for (const Image& im : e.images)
        if (!im.ok) return make_error(name + ": " + im.name + ": WebP encoding failed");
    const std::string meta = e.meta.dump();
    if (archive) {
        std::vector<ZipEntryData> entries;
        for (const Image& im : e.images) entries.push_back({im.name, im.webp});
        entries.push_back({"meta.json", meta});  // last, as splat-transform writes it
        return write_file_atomic(path, [&](std::FILE* f) { return write_zip_stored(f, entries, name); });
    }
    // A folder: every file to its temporary first, then renamed one by one, meta.json last, so a failed
    // write leaves the old files as they were (only a failing rename, after all were written, can leave
    // new images beside the old meta.json).
    const fs::path dir = path.parent_path();
    std::vector<AtomicFile> files;
    const auto stage = [&](const fs::path& p, std::string_view bytes) -> Status {
        auto f = AtomicFile::create(p);
        if (!f) return f.error();
        if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f->file()) != bytes.size())
            return make_error(p.string() + ": write failed: " + std::strerror(errno));
        files.push_back(std::move(*f));
        return {};
    };
    for (const Image& im : e.images)
        if (Status s = stage(dir / im.name, im.webp); !s) return s;
    if (Status s = stage(path, meta); !s) return s;
    for (AtomicFile& f : files)
        if (Status s = f.commit(); !s) return s;
    return {};
}

}  // namespace sffd::gaussian
