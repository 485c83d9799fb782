#include "runtime/assets/formats/gaussian/gaussian_sog.h"

#include <webp/decode.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/core/file_io.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/archive/gaussian_zip.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

using json = nlohmann::json;

constexpr std::uint64_t kMaxSogFileBytes = std::uint64_t(2) << 30;

Result<std::vector<unsigned char>> slurp(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        return make_error(fs::exists(path, ec) ? "not a regular file" : "no such file");
    const std::uint64_t size = fs::file_size(path, ec);
    if (ec) return make_error("cannot stat: " + ec.message());
    if (size > kMaxSogFileBytes)
        return make_error(std::to_string(size) + " bytes, more than the " + std::to_string(kMaxSogFileBytes) +
                          "-byte limit");
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!f) return make_error(std::string("cannot open: ") + std::strerror(errno));
    std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
    if (size > 0 && std::fread(bytes.data(), 1, bytes.size(), f.get()) != bytes.size())
        return make_error("read error");
    return bytes;
}

// Where the images come from: the archive, or the folder of meta.json.
struct Source {
    std::optional<ZipArchive> zip;
    fs::path dir;
    Result<std::vector<unsigned char>> get(const std::string& name) const {
        if (zip) return zip->read(name);
        auto r = slurp(dir / name);
        if (!r) return make_error((dir / name).string() + ": " + r.message());
        return r;
    }
};

// A decoded image, kept in libwebp's buffer (no copy of what may be hundreds of megabytes).
struct Image {
    int w = 0, h = 0;
    std::unique_ptr<std::uint8_t, void (*)(void*)> rgba{nullptr, WebPFree};
    const unsigned char* texel(std::size_t i) const { return rgba.get() + i * 4; }
};

// A member of a JSON object, or null: const operator[] must not be used on a missing key.
const json& member(const json& o, const char* key) {
    static const json null;
    if (!o.is_object()) return null;
    auto it = o.find(key);
    return it == o.end() ? null : *it;
}

// Reads meta.json's number arrays; false when a value is missing, not a number or not finite.
bool numbers(const json& j, std::size_t n, double* out) {
    if (!j.is_array() || j.size() != n) return false;
    for (std::size_t i = 0; i < n; ++i) {
        if (!j[i].is_number()) return false;
        out[i] = j[i].get<double>();
        if (!std::isfinite(out[i])) return false;
    }
    return true;
}

class Reader {
public:
    Reader(std::string name, Source src) : name_(std::move(name)), src_(std::move(src)) {}

    Result<GaussianCloud> read(const std::vector<unsigned char>& meta_bytes) {
        const std::string_view text(reinterpret_cast<const char*>(meta_bytes.data()), meta_bytes.size());
        if (auto d = check_json_depth(text, name_ + ": meta.json"); !d) return make_error(d.message());
        const json m = json::parse(text, nullptr, false);
        if (m.is_discarded() || !m.is_object()) return fail("meta.json is not a JSON object");
        if (!m.contains("version")) {
            if (!member(member(m, "means"), "shape").is_null())
                return fail(
                    "SOG version 1 (meta.json without \"version\") is not read: re-encode it with "
                    "splat-transform in/meta.json out.sog");
            return fail("meta.json has no \"version\"");
        }
        const json& version = member(m, "version");
        if (!version.is_number_integer() || version.get<long long>() != 2)
            return fail("SOG version " + version.dump() + " is not read (version 2 is)");
        const json& count_j = member(m, "count");
        if (!count_j.is_number_unsigned())
            return fail("meta.json: \"count\" is missing or not a whole number");
        const std::uint64_t count = count_j.get<std::uint64_t>();
        if (count > kMaxGaussians)
            return fail("declares " + std::to_string(count) + " Gaussians, more than the " +
                        std::to_string(kMaxGaussians) + " limit");
        n_ = std::size_t(count);

        double mins[3], maxs[3], scale_book[256], dc_book[256];
        const json* means = section(m, "means", 2);
        if (!means) return error();
        if (!numbers(member(*means, "mins"), 3, mins) || !numbers(member(*means, "maxs"), 3, maxs))
            return fail("meta.json: means.mins and means.maxs must be 3 finite numbers each");
        const json* scales = section(m, "scales", 1);
        const json* quats = section(m, "quats", 1);
        const json* sh0 = section(m, "sh0", 1);
        if (!scales || !quats || !sh0) return error();
        if (!numbers(member(*scales, "codebook"), 256, scale_book))
            return fail("meta.json: scales.codebook must be 256 finite numbers");
        if (!numbers(member(*sh0, "codebook"), 256, dc_book))
            return fail("meta.json: sh0.codebook must be 256 finite numbers");
        int bands = 0;
        std::uint64_t palette = 0;
        double sh_book[256];
        const json* shn = nullptr;
        if (!member(m, "shN").is_null()) {
            shn = section(m, "shN", 2);
            if (!shn) return error();
            const json& b = member(*shn, "bands");
            if (!b.is_number_integer() || b.get<long long>() < 1 || b.get<long long>() > 3)
                return fail("meta.json: shN.bands must be 1, 2 or 3");
            bands = int(b.get<long long>());
            const json& p = member(*shn, "count");
            if (!p.is_number_unsigned() || p.get<std::uint64_t>() > 65536)
                return fail("meta.json: shN.count must be a whole number up to 65536 (16-bit labels)");
            palette = p.get<std::uint64_t>();
            if (!numbers(member(*shn, "codebook"), 256, sh_book))
                return fail("meta.json: shN.codebook must be 256 finite numbers");
        }

        // The images, each checked by its header before it is decoded.
        Image lo, hi, q, s, c;
        if (!image(member(*means, "files")[0], lo) || !image(member(*means, "files")[1], hi) ||
            !image(member(*quats, "files")[0], q) || !image(member(*scales, "files")[0], s) ||
            !image(member(*sh0, "files")[0], c))
            return error();
        const int K = (bands + 1) * (bands + 1);
        Image centroids, labels;
        if (shn) {
            if (!image(member(*shn, "files")[1], labels) ||
                !image(member(*shn, "files")[0], centroids, std::size_t(64) * std::size_t(K - 1), palette))
                return error();
        }

        GaussianCloud g;
        g.sh_degree = bands;
        g.positions.resize(n_), g.scales.resize(n_), g.rotations.resize(n_), g.opacities.resize(n_);
        g.sh.assign(n_ * std::size_t(K) * 3, 0.0f);
        const double range[3] = {maxs[0] - mins[0] != 0 ? maxs[0] - mins[0] : 1.0,
                                 maxs[1] - mins[1] != 0 ? maxs[1] - mins[1] : 1.0,
                                 maxs[2] - mins[2] != 0 ? maxs[2] - mins[2] : 1.0};
        static const int kOthers[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
        for (std::size_t i = 0; i < n_; ++i) {
            for (int a = 0; a < 3; ++a) {
                const double v = mins[a] + range[a] * double(lo.texel(i)[a] | hi.texel(i)[a] << 8) / 65535.0;
                const double x = std::expm1(std::abs(v));
                g.positions[i][a] = float(v < 0 ? -x : x);
                g.scales[i][a] = float(std::exp(scale_book[s.texel(i)[a]]));
                g.sh[i * std::size_t(K) * 3 + std::size_t(a)] = float(dc_book[c.texel(i)[a]]);
            }
            g.opacities[i] = float(c.texel(i)[3] / 255.0);
            const unsigned char* t = q.texel(i);
            if (t[3] < 252)
                return fail(json_name(*quats) + ": Gaussian " + std::to_string(i) + ": quaternion tag " +
                            std::to_string(t[3]) + " is not 252..255");
            const int largest = t[3] - 252;
            double wxyz[4] = {0, 0, 0, 0}, sum = 0;
            for (int k = 0; k < 3; ++k) {
                const double v = (t[k] / 255.0 * 2.0 - 1.0) / std::sqrt(2.0);
                wxyz[kOthers[largest][k]] = v;
                sum += v * v;
            }
            wxyz[largest] = std::sqrt(std::max(0.0, 1.0 - sum));
            if (!normalize_quaternion(wxyz[0], wxyz[1], wxyz[2], wxyz[3], g.rotations[i]))
                return fail("Gaussian " + std::to_string(i) + ": zero-length quaternion");
            if (shn) {
                const std::uint32_t e = std::uint32_t(labels.texel(i)[0] | labels.texel(i)[1] << 8);
                if (e >= palette)
                    return fail(json_name(*shn, 1) + ": Gaussian " + std::to_string(i) + ": label " +
                                std::to_string(e) + " beyond the palette of " + std::to_string(palette));
                const std::size_t row = e / 64, first = (e % 64) * std::size_t(K - 1);
                for (int j = 0; j < K - 1; ++j) {
                    const unsigned char* p =
                        centroids.texel(row * std::size_t(centroids.w) + first + std::size_t(j));
                    for (int ch = 0; ch < 3; ++ch)
                        g.sh[(i * std::size_t(K) + std::size_t(j) + 1) * 3 + std::size_t(ch)] =
                            float(sh_book[p[ch]]);
                }
            }
        }
        return g;  // read_gaussians validates it like every reader's output
    }

private:
    Result<GaussianCloud> fail(const std::string& why) { return make_error(name_ + ": " + why); }
    Result<GaussianCloud> error() { return make_error(error_); }
    bool set_error(const std::string& why) {
        error_ = name_ + ": " + why;
        return false;
    }

    // A section of meta.json with its "files" list of `files` plain names.
    const json* section(const json& m, const char* key, std::size_t files) {
        const std::string k = key;
        const json& sec = member(m, key);
        if (!sec.is_object()) {
            set_error("meta.json has no \"" + k + "\" object");
            return nullptr;
        }
        const json& f = member(sec, "files");
        if (!f.is_array() || f.size() != files) {
            set_error("meta.json: " + k + ".files must list " + std::to_string(files) + " image(s)");
            return nullptr;
        }
        for (const json& x : f) {
            // Names stay inside the archive or folder: no directories, no "..".
            if (!x.is_string() || x.get<std::string>().empty() ||
                x.get<std::string>().find_first_of("/\\") != std::string::npos ||
                x.get<std::string>() == "." || x.get<std::string>() == "..") {
                set_error("meta.json: " + k + ".files: " + x.dump() + " is not a plain file name");
                return nullptr;
            }
        }
        return &sec;
    }
    static std::string json_name(const json& section, std::size_t i = 0) {
        return member(section, "files")[i].get<std::string>();
    }

    // Decodes one image. Data images hold at least the count and at most 2·count + 65536 texels (the
    // writer pads to multiples of 4 in each direction); the centroids are exactly `width` wide with rows
    // for `entries` palette entries.
    bool image(const json& file, Image& out, std::size_t width = 0, std::uint64_t entries = 0) {
        const std::string f = file.get<std::string>();
        auto bytes = src_.get(f);
        if (!bytes) return set_error(bytes.message());
        WebPBitstreamFeatures features;
        if (WebPGetFeatures(bytes->data(), bytes->size(), &features) != VP8_STATUS_OK)
            return set_error(f + ": not a WebP image");
        // The texels are indices and bit fields: a lossy or animated image cannot hold them.
        if (features.has_animation) return set_error(f + ": an animated WebP image");
        if (features.format == 1) return set_error(f + ": a lossy WebP image (SOG images are lossless)");
        const int w = features.width, h = features.height;
        const std::uint64_t texels = std::uint64_t(w) * std::uint64_t(h);
        if (width == 0) {
            if (texels < n_)
                return set_error(f + ": " + std::to_string(w) + "x" + std::to_string(h) + " texels for " +
                                 std::to_string(n_) + " Gaussians");
            if (texels > 2 * std::uint64_t(n_) + 65536)
                return set_error(f + ": " + std::to_string(w) + "x" + std::to_string(h) +
                                 " texels, far more than " + std::to_string(n_) + " Gaussians need");
        } else {
            if (std::size_t(w) != width)
                return set_error(f + ": " + std::to_string(w) + " texels wide; the palette needs " +
                                 std::to_string(width));
            const std::uint64_t rows = (entries + 63) / 64;
            if (std::uint64_t(h) < rows || std::uint64_t(h) > rows + 4)
                return set_error(f + ": " + std::to_string(h) + " rows for " + std::to_string(entries) +
                                 " palette entries");
        }
        int dw = 0, dh = 0;
        out.rgba.reset(WebPDecodeRGBA(bytes->data(), bytes->size(), &dw, &dh));
        if (!out.rgba) return set_error(f + ": corrupt WebP data");
        if (dw != w || dh != h) return set_error(f + ": decoded size differs from its header");
        out.w = w, out.h = h;
        return true;
    }

    std::string name_, error_;
    Source src_;
    std::size_t n_ = 0;
};

}  // namespace

Result<GaussianCloud> read_sog(const fs::path& path) {
    const std::string name = path.string();
    Source src;
    std::vector<unsigned char> archive, meta;
    if (path.extension() == ".json") {
        src.dir = path.parent_path();
        auto m = slurp(path);
        if (!m) return make_error(name + ": " + m.message());
        meta = std::move(*m);
    } else {
        auto a = slurp(path);
        if (!a) return make_error(name + ": " + a.message());
        archive = std::move(*a);
        auto z = ZipArchive::open(archive);
        if (!z) return make_error(name + ": " + z.message());
        auto m = z->read("meta.json");
        if (!m) return make_error(name + ": " + m.message());
        meta = std::move(*m);
        src.zip = std::move(*z);
    }
    return Reader(name, std::move(src)).read(meta);
}

}  // namespace sffd::gaussian
