// SPZ version 4 (nianticlabs/spz README "File layout (version 4)", src/cc/load-spz.cc): a plaintext
// 32-byte header, optional extension records, a table of contents of (compressed, decoded) u64 sizes,
// then one zstd frame per non-empty attribute array in the order of version 3. The checks follow the
// reference loader's and add the ones it leaves to zstd: every size is checked against the header's
// count before anything is allocated, and each stream must decode to exactly its array.
#include <zstd.h>

#include <memory>
#include <string>
#include <vector>

#include "runtime/core/log.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_spz_detail.h"

namespace sffd::gaussian::spz_detail {

namespace {

constexpr std::size_t kHeaderBytes = 32;
constexpr std::uint8_t kFlagExtensions = 0x2;
// kMaxRatio (gaussian_spz_detail.h) is the reference's bound on the zstd ratio, so a header cannot claim
// more splats than the file could hold: at most size · 1024 / 9 splats (9 bytes of positions each, the
// smallest array that is always present).
// SPZ_ADOBE_coordinate_system: the data is stored in another frame than RUB (extensions/README.md).
constexpr std::uint32_t kCoordinateSystemExtension = 0xADBE0003u;

std::uint64_t u64(const unsigned char* p) { return std::uint64_t(u32(p)) | std::uint64_t(u32(p + 4)) << 32; }

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}
void put64(std::string& s, std::uint64_t v) { put32(s, std::uint32_t(v)), put32(s, std::uint32_t(v >> 32)); }

}  // namespace

Result<GaussianCloud> read_v4(const std::string& name, const std::vector<unsigned char>& file) {
    auto fail = [&](const std::string& why) { return make_error(name + ": SPZ version 4: " + why); };
    const std::size_t size = file.size();
    if (size < kHeaderBytes) return fail("truncated header (" + std::to_string(size) + " of 32 bytes)");
    const unsigned char* h = file.data();
    const std::uint32_t n = u32(h + 8);
    const int degree = h[12], frac = h[13], flags = h[14], streams = h[15];
    const std::uint32_t toc = u32(h + 16);
    if (degree > 4) return fail("unsupported SH degree " + std::to_string(degree) + " (0..4)");
    if (frac > 30) return fail("fractional bits " + std::to_string(frac) + " out of range");
    if (n == 0) return fail("declares no splats");
    if (n > kMaxGaussians)
        return fail("declares " + std::to_string(n) + " splats, more than the " +
                    std::to_string(kMaxGaussians) + "-Gaussian limit");
    if (std::uint64_t(n) > std::uint64_t(size) * kMaxRatio / 9)
        return fail("declares " + std::to_string(n) + " splats, more than its " + std::to_string(size) +
                    " bytes can hold");
    const Arrays sizes = array_sizes(4, n, degree);
    std::uint64_t total = 0;
    int expected = 0;
    for (std::uint64_t b : sizes.bytes) total += b, expected += b > 0;
    if (total > kMaxDecodedBytes)
        return fail(std::to_string(total) + " decoded bytes, more than the " +
                    std::to_string(kMaxDecodedBytes) + "-byte limit");
    if (streams != expected)
        return fail(std::to_string(streams) + " streams; SH degree " + std::to_string(degree) + " has " +
                    std::to_string(expected));
    if (toc < kHeaderBytes || toc > size)
        return fail("table of contents at byte " + std::to_string(toc) + ", outside 32.." +
                    std::to_string(size));
    // Extension records (type u32, length u32, payload) fill the bytes between header and table.
    // Unknown ones are skipped as the reference does; one that moves the data into another frame
    // would be read wrongly, so it is refused.
    if (toc > kHeaderBytes && !(flags & kFlagExtensions))
        return fail(std::to_string(toc - kHeaderBytes) +
                    " bytes before the table of contents, but the header flags no extensions");
    for (std::size_t at = kHeaderBytes; at < toc;) {
        if (toc - at < 8) return fail("extension record at byte " + std::to_string(at) + " is truncated");
        const std::uint32_t type = u32(h + at), length = u32(h + at + 4);
        if (length > toc - at - 8)
            return fail("extension record at byte " + std::to_string(at) +
                        " runs past the table of contents");
        if (type == kCoordinateSystemExtension)
            return fail(
                "stores its data in another coordinate system (SPZ_ADOBE_coordinate_system), "
                "which is not supported");
        at += 8 + std::size_t(length);
    }
    if (std::uint64_t(streams) * 16 > size - toc) return fail("truncated table of contents");
    std::uint64_t offset = toc + std::uint64_t(streams) * 16;
    struct Stream {
        std::uint64_t at, packed, decoded, dst;
    };
    std::vector<Stream> table;
    std::uint64_t dst = 0;
    for (int a = 0, s = 0; a < 6; dst += sizes.bytes[a], ++a) {
        if (sizes.bytes[a] == 0) continue;
        const unsigned char* e = h + toc + std::size_t(s) * 16;
        const std::uint64_t packed = u64(e), decoded = u64(e + 8);
        if (decoded != sizes.bytes[a])
            return fail("stream " + std::to_string(s) + " decodes to " + std::to_string(decoded) +
                        " bytes; " + std::to_string(n) + " splats need " + std::to_string(sizes.bytes[a]));
        if (packed > size - offset)
            return fail("stream " + std::to_string(s) + " (" + std::to_string(packed) +
                        " bytes) runs past the end of the file");
        table.push_back({offset, packed, decoded, dst});
        offset += packed, ++s;
    }
    if (offset != size) return fail(std::to_string(size - offset) + " bytes after the last stream");
    std::vector<unsigned char> data(static_cast<std::size_t>(total));
    for (std::size_t s = 0; s < table.size(); ++s) {
        const Stream& t = table[s];
        // A frame that declares its decoded size must declare this one; zstd then checks the size and,
        // when the frame carries one, its XXH64 checksum.
        const unsigned long long declared = ZSTD_getFrameContentSize(h + t.at, t.packed);
        if (declared == ZSTD_CONTENTSIZE_ERROR)
            return fail("stream " + std::to_string(s) + " is not a zstd frame");
        if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != t.decoded)
            return fail("stream " + std::to_string(s) + " declares " + std::to_string(declared) +
                        " decoded bytes, the table " + std::to_string(t.decoded));
        const std::size_t got = ZSTD_decompress(data.data() + t.dst, t.decoded, h + t.at, t.packed);
        if (ZSTD_isError(got))
            return fail("stream " + std::to_string(s) + ": corrupt zstd data (" + ZSTD_getErrorName(got) +
                        ")");
        if (got != t.decoded)
            return fail("stream " + std::to_string(s) + " decodes to " + std::to_string(got) +
                        " bytes, not " + std::to_string(t.decoded));
    }
    if (degree == 4) log::info(name, ": SH degree 4 read as degree 3 (band 4 dropped)");
    return decode(4, n, degree, frac, data);
}

Result<std::string> pack_v4(const Encoded& e) {
    std::string out;
    put32(out, kMagic), put32(out, 4), put32(out, e.n);
    out += char(e.degree), out += char(e.frac), out += char(0);
    int streams = 0;
    for (const std::string& a : e.arrays) streams += !a.empty();
    out += char(streams);
    put32(out, std::uint32_t(kHeaderBytes));
    out.append(12, '\0');
    std::vector<std::string> packed;
    std::unique_ptr<ZSTD_CCtx, std::size_t (*)(ZSTD_CCtx*)> cctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
    if (!cctx) return make_error("zstd initialisation failed");
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, 12);
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);  // readers verify each stream
    for (const std::string& a : e.arrays) {
        if (a.empty()) continue;
        std::string z(ZSTD_compressBound(a.size()), '\0');
        const std::size_t got = ZSTD_compress2(cctx.get(), z.data(), z.size(), a.data(), a.size());
        if (ZSTD_isError(got))
            return make_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(got));
        z.resize(got);
        put64(out, z.size()), put64(out, a.size());
        packed.push_back(std::move(z));
    }
    for (const std::string& z : packed) out += z;
    return out;
}

}  // namespace sffd::gaussian::spz_detail
