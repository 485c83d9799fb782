// SPZ writing, version 3 (one gzip stream) or 4 (zstd streams, gaussian_spz4.cpp); the layout is in
// gaussian_spz.h. The internal 3DGS PLY frame is turned into SPZ's RUB first, so any SPZ reader that
// follows the SPZ README sees the capture the right way up.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/core/atomic_file.h"
#include "systems/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_spz.h"
#include "systems/gaussian/gaussian_spz_detail.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}

unsigned char byte(double v) { return static_cast<unsigned char>(std::clamp(std::lround(v), 0L, 255L)); }

}  // namespace

namespace spz_detail {

Result<Encoded> encode(const GaussianCloud& g) {
    const std::size_t n = g.size();
    if (n > 0xffffffffu) return make_error(std::to_string(n) + " Gaussians do not fit SPZ's 32-bit count");
    // 24-bit fixed point: as many fractional bits (up to 12, the reference's) as the largest coordinate
    // allows.
    double largest = 0.0;
    for (const glm::vec3& p : g.positions)
        for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(g.origin[c] + double(p[c])));
    int frac = 12;
    while (frac > 0 && largest * double(1 << frac) > 8388607.0) --frac;
    if (largest > 8388607.0)
        return make_error("a coordinate of " + std::to_string(largest) + " is beyond SPZ's 24-bit range");
    Encoded e;
    e.n = std::uint32_t(n), e.degree = g.sh_degree, e.frac = frac;
    const int K = sh_coeffs(g.sh_degree);
    const std::size_t rest = std::size_t(3 * (K - 1));
    std::string& pos = e.arrays[0];
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const std::int32_t v =
                std::int32_t(std::lround((g.origin[c] + double(g.positions[i][c])) * double(1 << frac)));
            for (int b = 0; b < 3; ++b) pos += char((std::uint32_t(v) >> (8 * b)) & 0xff);
        }
    for (std::size_t i = 0; i < n; ++i) e.arrays[1] += char(byte(double(g.opacities[i]) * 255.0));
    for (std::size_t i = 0; i < n; ++i)  // SPZ's colour scale 0.15, not C0
        for (int c = 0; c < 3; ++c)
            e.arrays[2] +=
                char(byte((double(g.sh[i * std::size_t(K) * 3 + std::size_t(c)]) * 0.15 + 0.5) * 255.0));
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            e.arrays[3] +=
                char(byte(g.scales[i][c] > 0 ? (std::log(double(g.scales[i][c])) + 10.0) * 16.0 : 0.0));
    for (std::size_t i = 0; i < n; ++i) {
        const glm::quat q = glm::normalize(g.rotations[i]);
        double xyzw[4] = {q.x, q.y, q.z, q.w};
        int largest_c = 0;
        for (int c = 1; c < 4; ++c)
            if (std::abs(xyzw[c]) > std::abs(xyzw[largest_c])) largest_c = c;
        const double sign = xyzw[largest_c] < 0 ? -1.0 : 1.0;  // q and -q: keep the dropped one positive
        std::uint32_t packed = 0;
        for (int c = 0; c < 4; ++c) {
            if (c == largest_c) continue;
            const double v = sign * xyzw[c];
            const std::uint32_t mag =
                std::uint32_t(std::clamp(std::lround(std::abs(v) / std::sqrt(0.5) * 511.0), 0L, 511L));
            packed = packed << 10 | (v < 0 ? 1u << 9 : 0u) | mag;
        }
        put32(e.arrays[4], packed | std::uint32_t(largest_c) << 30);
    }
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < rest; ++k)
            e.arrays[5] += char(byte(double(g.sh[i * std::size_t(K) * 3 + 3 + k]) * 128.0 + 128.0));
    return e;
}

}  // namespace spz_detail

Status write_spz(const fs::path& path, const GaussianCloud& cloud, int version) {
    const std::string name = path.string();
    if (version != 3 && version != 4)
        return make_error(name + ": SPZ version " + std::to_string(version) + " is not written (3 or 4)");
    if (auto s = validate(cloud, name); !s) return s;
    GaussianCloud g = cloud;
    turn_axes(g, AxisTurn::x180);
    auto e = spz_detail::encode(g);
    if (!e) return make_error(name + ": " + e.message());
    if (version == 4) {
        // The reference loader refuses a version-4 header that declares no splats.
        if (e->n == 0) return make_error(name + ": an empty cloud cannot be written as SPZ version 4");
        auto bytes = spz_detail::pack_v4(*e);
        if (!bytes) return make_error(name + ": " + bytes.message());
        return write_file_atomic(path, *bytes);
    }
    std::string raw;
    put32(raw, spz_detail::kMagic), put32(raw, 3), put32(raw, e->n);
    raw += char(e->degree), raw += char(e->frac), raw += char(0), raw += char(0);
    for (const std::string& a : e->arrays) raw += a;

    // One deflate call: zlib's counters are 32-bit (a 4 GiB payload is ~50M degree-3 Gaussians).
    if (raw.size() > 0xffff0000u)
        return make_error(name + ": " + std::to_string(raw.size()) +
                          " bytes of SPZ data exceed one 4 GiB gzip call");
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        return make_error(name + ": zlib initialisation failed");
    std::string gz(deflateBound(&z, uLong(raw.size())), '\0');
    z.next_in = reinterpret_cast<Bytef*>(raw.data());
    z.avail_in = uInt(raw.size());
    z.next_out = reinterpret_cast<Bytef*>(gz.data());
    z.avail_out = uInt(gz.size());
    const int rc = deflate(&z, Z_FINISH);
    gz.resize(z.total_out);
    deflateEnd(&z);
    if (rc != Z_STREAM_END) return make_error(name + ": gzip compression failed");
    return write_file_atomic(path, gz);
}

}  // namespace sffd::gaussian
