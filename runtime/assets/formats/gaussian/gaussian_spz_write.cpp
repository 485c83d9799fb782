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
#include <string_view>
#include <thread>
#include <vector>

#include <tbb/parallel_for.h>

#include "runtime/core/atomic_file.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "runtime/assets/formats/gaussian/gaussian_spz_detail.h"

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

    // One gzip stream of the header and the arrays, compressed in segments on every core (as pigz does):
    // each segment is raw deflate at the reference's level 6, primed with the 32 KB before it (so the
    // ratio stays within a fraction of a percent of one stream's) and ended on a byte boundary (an empty
    // stored block), the last one with the final block; any inflate reads the concatenation as one
    // stream. Written as the segments come out: neither the payload nor the file is assembled in memory.
    std::vector<std::string_view> pieces = {header};
    for (const std::string& a : e->arrays) pieces.emplace_back(a);
    struct Segment {
        std::size_t piece = 0, first = 0, size = 0;
        std::string out;
        uLong crc = 0;
        int status = Z_OK;
    };
    constexpr std::size_t kSegment = std::size_t(4) << 20, kWindow = 32768;
    std::vector<Segment> segments;
    for (std::size_t p = 0; p < pieces.size(); ++p)
        for (std::size_t at = 0; at < pieces[p].size(); at += kSegment)
            segments.push_back(Segment{p, at, std::min(kSegment, pieces[p].size() - at), {}, 0, Z_OK});
    // The bytes before a segment, up to 32 KB, that its compressor may refer back to.
    const auto window = [&](const Segment& seg) -> std::string {
        std::string w;
        for (std::size_t p = seg.piece + 1, end = seg.first; p-- > 0 && w.size() < kWindow;) {
            const std::string_view before = pieces[p].substr(0, p == seg.piece ? end : pieces[p].size());
            const std::size_t take = std::min(kWindow - w.size(), before.size());
            w.insert(0, before.substr(before.size() - take));
        }
        return w;
    };
    uLong crc = crc32(0L, Z_NULL, 0);
    std::uint64_t total = 0;
    for (const std::string_view piece : pieces) total += piece.size();
    const Status written = write_file_atomic(path, [&](std::FILE* f) -> Status {
        // gzip header: deflate, no name or time, OS unknown (RFC 1952).
        const unsigned char gz_header[10] = {0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255};
        if (std::fwrite(gz_header, 1, sizeof gz_header, f) != sizeof gz_header)
            return make_error(name + ": write failed: " + std::strerror(errno));
        // A batch of segments at a time, so memory holds a few of them, not the file.
        const std::size_t batch = std::max<std::size_t>(8, 2 * std::thread::hardware_concurrency());
        for (std::size_t b0 = 0; b0 < segments.size(); b0 += batch) {
            const std::size_t b1 = std::min(segments.size(), b0 + batch);
            tbb::parallel_for(b0, b1, [&](std::size_t i) {
                Segment& seg = segments[i];
                const std::string_view in = pieces[seg.piece].substr(seg.first, seg.size);
                seg.crc = crc32(0L, reinterpret_cast<const Bytef*>(in.data()), uInt(in.size()));
                z_stream z{};
                if (deflateInit2(&z, 6, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
                    seg.status = Z_MEM_ERROR;
                    return;
                }
                const std::string dict = window(seg);
                if (!dict.empty())
                    deflateSetDictionary(&z, reinterpret_cast<const Bytef*>(dict.data()), uInt(dict.size()));
                seg.out.resize(deflateBound(&z, uLong(in.size())) + 16);
                z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
                z.avail_in = uInt(in.size());
                z.next_out = reinterpret_cast<Bytef*>(seg.out.data());
                z.avail_out = uInt(seg.out.size());
                const bool last = i + 1 == segments.size();
                seg.status = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
                if (seg.status == (last ? Z_STREAM_END : Z_OK) && z.avail_in == 0) seg.status = Z_OK;
                else seg.status = Z_STREAM_ERROR;
                seg.out.resize(z.total_out);
                deflateEnd(&z);
            });
            for (std::size_t i = b0; i < b1; ++i) {
                Segment& seg = segments[i];
                if (seg.status != Z_OK) return make_error(name + ": gzip compression failed");
                if (std::fwrite(seg.out.data(), 1, seg.out.size(), f) != seg.out.size())
                    return make_error(name + ": write failed: " + std::strerror(errno));
                crc = crc32_combine(crc, seg.crc, z_off_t(seg.size));
                std::string().swap(seg.out);
            }
        }
        unsigned char trailer[8];
        for (int k = 0; k < 4; ++k) {
            trailer[k] = static_cast<unsigned char>((crc >> (8 * k)) & 0xff);
            trailer[4 + k] = static_cast<unsigned char>((total >> (8 * k)) & 0xff);  // ISIZE: mod 2^32
        }
        if (std::fwrite(trailer, 1, sizeof trailer, f) != sizeof trailer)
            return make_error(name + ": write failed: " + std::strerror(errno));
        return {};
    });
    return written;
}

}  // namespace sffd::gaussian
