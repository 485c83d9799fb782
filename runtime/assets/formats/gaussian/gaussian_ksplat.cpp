#include "runtime/assets/formats/gaussian/gaussian_ksplat.h"

#include "runtime/assets/formats/gaussian/gaussian_io.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kMainHeader = 4096, kSectionHeader = 1024;

struct Mode {
    std::uint64_t centre, scale, rotation, colour, sh;  // bytes per field (sh: per component)
    std::uint32_t range;                                // default quantisation range
};
constexpr Mode kModes[3] = {{12, 12, 16, 4, 4, 1}, {6, 6, 8, 4, 2, 32767}, {6, 6, 8, 4, 1, 32767}};

std::uint16_t u16(const unsigned char* p) { return std::uint16_t(p[0] | p[1] << 8); }
std::uint32_t u32(const unsigned char* p) {
    return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
           std::uint32_t(p[3]) << 24;
}
float f32(const unsigned char* p) {
    const std::uint32_t b = u32(p);
    float f;
    std::memcpy(&f, &b, 4);
    return f;
}
float f16(const unsigned char* p) {
    const std::uint32_t h = u16(p), sign = h >> 15, e = (h >> 10) & 31u, m = h & 1023u;
    float v;
    if (e == 0) v = std::ldexp(float(m), -24);  // zero and subnormals
    else if (e == 31) v = m ? NAN : INFINITY;
    else v = std::ldexp(float(m | 1024u), int(e) - 25);
    return sign ? -v : v;
}

}  // namespace

Result<GaussianCloud> read_ksplat(const fs::path& path) {
    const std::string name = path.string();
    auto fail = [&](const std::string& why) { return make_error(name + ": " + why); };
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        return fail(fs::exists(path, ec) ? "not a regular file" : "no such file");
    const std::uint64_t size = fs::file_size(path, ec);
    if (ec) return fail("cannot stat: " + ec.message());
    if (size < kMainHeader)
        return fail("too small for a .ksplat file (" + std::to_string(size) +
                    " bytes, the header alone is 4096)");
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!f) return fail(std::string("cannot open: ") + std::strerror(errno));
    // The whole file is read: its size is what is on disk, not a declared count.
    std::vector<unsigned char> file(static_cast<std::size_t>(size));
    if (std::fread(file.data(), 1, file.size(), f.get()) != file.size()) return fail("read error");
    const unsigned char* h = file.data();
    if (h[0] != 0 || h[1] < 1)
        return fail("unsupported .ksplat version " + std::to_string(h[0]) + "." + std::to_string(h[1]) +
                    " (0.1 and later are read)");
    const std::uint64_t sections = u32(h + 4), n = u32(h + 16);
    const unsigned mode_index = u16(h + 20);
    if (mode_index > 2)
        return fail("unsupported compression mode " + std::to_string(mode_index) + " (0, 1, 2)");
    const Mode mode = kModes[mode_index];
    float sh_min = f32(h + 36), sh_max = f32(h + 40);
    if (sh_min == 0.0f) sh_min = -1.5f;
    if (sh_max == 0.0f) sh_max = 1.5f;
    if (!std::isfinite(sh_min) || !std::isfinite(sh_max)) return fail("non-finite SH range in the header");
    if (n == 0) return fail("holds no splats");
    if (kMainHeader + sections * kSectionHeader > size)
        return fail(std::to_string(sections) + " section headers do not fit in " + std::to_string(size) +
                    " bytes");

    // First pass: the sections' layout, every range checked against the file before allocating.
    struct Section {
        std::uint64_t splats, capacity, bucket_capacity, buckets, full, partial, degree, range, data;
        float block;
    };
    std::vector<Section> list;
    std::uint64_t offset = kMainHeader + sections * kSectionHeader, total = 0;
    int degree = 0;
    for (std::uint64_t s = 0; s < sections; ++s) {
        const unsigned char* sh = h + kMainHeader + s * kSectionHeader;
        Section c{u32(sh),      u32(sh + 4),  u32(sh + 8), u32(sh + 12), u32(sh + 32), u32(sh + 36),
                  u16(sh + 40), u32(sh + 24), 0,           f32(sh + 16)};
        if (c.range == 0) c.range = mode.range;
        const std::string where = "section " + std::to_string(s) + ": ";
        if (c.degree > 3) return fail(where + "SH degree " + std::to_string(c.degree) + " (0..3 are read)");
        if (c.splats > c.capacity)
            return fail(where + std::to_string(c.splats) + " splats exceed its capacity " +
                        std::to_string(c.capacity));
        if (c.full + c.partial > c.buckets) return fail(where + "more full and partial buckets than buckets");
        if (mode_index > 0 && c.splats > 0 && (c.buckets == 0 || !std::isfinite(c.block)))
            return fail(where + "quantised positions without buckets or with a non-finite block size");
        const std::uint64_t rest = std::uint64_t(3 * (sh_coeffs(int(c.degree)) - 1));
        const std::uint64_t record = mode.centre + mode.scale + mode.rotation + mode.colour + rest * mode.sh;
        const std::uint64_t storage = std::uint64_t(u16(sh + 20)) * c.buckets + 4 * c.partial;
        // 32-bit fields: these products stay far below 2^64.
        if (offset + storage + record * c.capacity > size)
            return fail(where + "its buckets and " + std::to_string(c.capacity) +
                        " records run past the end of the file");
        if (c.buckets * 12 + 4 * c.partial > storage && mode_index > 0)
            return fail(where + "bucket storage too small for its bucket centres");
        c.data = offset;
        offset += storage + record * c.capacity;
        total += c.splats;
        if (c.splats > 0) degree = std::max(degree, int(c.degree));
        list.push_back(c);
    }
    if (total != n)
        return fail("the header declares " + std::to_string(n) + " splats, the sections hold " +
                    std::to_string(total));

    GaussianCloud g;
    g.sh_degree = degree;
    const std::size_t K = std::size_t(sh_coeffs(degree));
    g.positions.reserve(n), g.scales.reserve(n), g.rotations.reserve(n), g.opacities.reserve(n);
    g.sh.assign(std::size_t(n) * K * 3, 0.0f);
    for (std::size_t s = 0; s < list.size(); ++s) {
        const Section& c = list[s];
        const std::uint64_t storage =
            std::uint64_t(u16(h + kMainHeader + s * kSectionHeader + 20)) * c.buckets + 4 * c.partial;
        const unsigned char* partial_sizes = h + c.data;
        const unsigned char* centres = h + c.data + 4 * c.partial;
        const unsigned char* records = h + c.data + storage;
        const int sk = sh_coeffs(int(c.degree)) - 1;  // per channel in this section
        const std::uint64_t record =
            mode.centre + mode.scale + mode.rotation + mode.colour + std::uint64_t(3 * sk) * mode.sh;
        const double unit = double(c.block) / 2.0 / double(c.range);
        std::uint64_t bucket = 0, partial_bucket = c.full, partial_base = c.full * c.bucket_capacity;
        for (std::uint64_t j = 0; j < c.splats; ++j) {
            const unsigned char* r = records + j * record;
            const std::size_t i = g.size();
            const std::string where = "splat " + std::to_string(i) + ": ";
            glm::vec3 p;
            if (mode_index == 0) {
                p = {f32(r), f32(r + 4), f32(r + 8)};
            } else {
                if (j < c.full * c.bucket_capacity) {
                    bucket = j / std::max<std::uint64_t>(c.bucket_capacity, 1);
                } else {
                    // Partial buckets follow the full ones, each with its stored size.
                    while (partial_bucket - c.full < c.partial &&
                           j >= partial_base + u32(partial_sizes + 4 * (partial_bucket - c.full))) {
                        partial_base += u32(partial_sizes + 4 * (partial_bucket - c.full));
                        ++partial_bucket;
                    }
                    bucket = partial_bucket;
                }
                if (bucket >= c.buckets)
                    return fail(where + "its bucket " + std::to_string(bucket) + " is past the section's " +
                                std::to_string(c.buckets));
                for (int a = 0; a < 3; ++a)
                    p[a] = float((double(u16(r + 2 * a)) - double(c.range)) * unit +
                                 double(f32(centres + bucket * 12 + std::uint64_t(a) * 4)));
            }
            const unsigned char* sc = r + mode.centre;
            const unsigned char* ro = sc + mode.scale;
            const unsigned char* co = ro + mode.rotation;
            const unsigned char* shp = co + mode.colour;
            glm::vec3 scale;
            double q[4];
            for (int a = 0; a < 3; ++a) scale[a] = mode_index == 0 ? f32(sc + 4 * a) : f16(sc + 2 * a);
            for (int a = 0; a < 4; ++a) q[a] = mode_index == 0 ? f32(ro + 4 * a) : f16(ro + 2 * a);
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                return fail(where + "non-finite position");
            if (!(scale.x >= 0 && scale.y >= 0 && scale.z >= 0) ||
                !std::isfinite(scale.x + scale.y + scale.z))
                return fail(where + "scale negative or not finite");
            const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            if (!(len > 1e-30) || !std::isfinite(len))
                return fail(where + "zero-length or non-finite rotation");
            g.positions.push_back(p);
            g.scales.push_back(scale);
            g.rotations.emplace_back(float(q[0] / len), float(q[1] / len), float(q[2] / len),
                                     float(q[3] / len));
            g.opacities.push_back(float(co[3] / 255.0));
            for (std::size_t ch = 0; ch < 3; ++ch)
                g.sh[i * K * 3 + ch] = float((co[ch] / 255.0 - 0.5) / kShDc);
            // Bands in order, each per channel: component index -> (channel, coefficient k).
            int component = 0;
            for (int band = 1; band <= int(c.degree); ++band) {
                const int first = band * band, width = 2 * band + 1;
                for (int ch = 0; ch < 3; ++ch)
                    for (int m = 0; m < width; ++m, ++component) {
                        float v;
                        if (mode_index == 0) v = f32(shp + 4 * component);
                        else if (mode_index == 1) v = f16(shp + 2 * component);
                        else v = sh_min + float(shp[component]) / 255.0f * (sh_max - sh_min);
                        if (!std::isfinite(v)) return fail(where + "non-finite SH coefficient");
                        g.sh[(i * K + std::size_t(first + m)) * 3 + std::size_t(ch)] = v;
                    }
            }
        }
    }
    return g;
}

}  // namespace sffd::gaussian
