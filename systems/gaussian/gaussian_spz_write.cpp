// SPZ writing, version 3 (one gzip stream) or 4 (zstd streams, gaussian_spz4.cpp); the layout is in
// gaussian_spz.h. The internal 3DGS PLY frame is turned into SPZ's RUB first, so any SPZ reader that
// follows the SPZ README sees the capture the right way up.
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
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
    // Each array grows once (appending byte by byte doubled and copied them).
    const std::size_t bytes[6] = {9, 1, 3, 3, 4, rest};
    for (std::size_t a = 0; a < 6; ++a) e.arrays[a].reserve(n * bytes[a]);
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
    std::string header;
    put32(header, spz_detail::kMagic), put32(header, 3), put32(header, e->n);
    header += char(e->degree), header += char(e->frac), header += char(0), header += char(0);

    // One gzip stream, fed the header and each array in turn and written as it comes out: neither the
    // payload nor the compressed file is assembled in memory (those copies and their fresh pages were
    // half of writing 1M degree-3 Gaussians).
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        return make_error(name + ": zlib initialisation failed");
    std::vector<unsigned char> out(1 << 20);
    const Status written = write_file_atomic(path, [&](std::FILE* f) -> Status {
        std::vector<const std::string*> pieces = {&header};
        for (const std::string& a : e->arrays) pieces.push_back(&a);
        for (std::size_t p = 0; p < pieces.size(); ++p) {
            const bool last = p + 1 == pieces.size();
            const std::string& in = *pieces[p];
            std::size_t at = 0;
            int rc = Z_OK;
            do {  // zlib counts in 32 bits: a piece goes in up to 1 GiB at a time
                const std::size_t take = std::min<std::size_t>(in.size() - at, std::size_t(1) << 30);
                z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data() + at));
                z.avail_in = uInt(take);
                at += take;
                const int flush = last && at == in.size() ? Z_FINISH : Z_NO_FLUSH;
                do {
                    z.next_out = out.data();
                    z.avail_out = uInt(out.size());
                    rc = deflate(&z, flush);
                    if (rc == Z_STREAM_ERROR) return make_error(name + ": gzip compression failed");
                    const std::size_t produced = out.size() - z.avail_out;
                    if (std::fwrite(out.data(), 1, produced, f) != produced)
                        return make_error(name + ": write failed: " + std::strerror(errno));
                } while (z.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
            } while (at < in.size());
        }
        return {};
    });
    deflateEnd(&z);
    return written;
}

}  // namespace sffd::gaussian
