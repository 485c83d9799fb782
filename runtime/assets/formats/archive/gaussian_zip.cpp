#include "runtime/assets/formats/archive/gaussian_zip.h"

#include <zlib.h>

#include <algorithm>

namespace sffd::gaussian {

namespace {

std::uint16_t u16(const unsigned char* p) { return std::uint16_t(p[0] | p[1] << 8); }
std::uint32_t u32(const unsigned char* p) {
    return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
           std::uint32_t(p[3]) << 24;
}

}  // namespace

Result<ZipArchive> ZipArchive::open(const std::vector<unsigned char>& b) {
    const std::size_t size = b.size();
    if (size < 22) return make_error("not a ZIP archive (" + std::to_string(size) + " bytes)");
    // The end record is the last 22 bytes plus a comment of up to 65535: search backwards.
    std::size_t eocd = size;
    for (std::size_t i = size - 22 + 1, stop = size >= 22 + 65535 ? size - 22 - 65535 : 0; i-- > stop;)
        if (u32(b.data() + i) == 0x06054b50u) {
            eocd = i;
            break;
        }
    if (eocd == size) return make_error("not a ZIP archive (no end of central directory record)");
    const unsigned char* e = b.data() + eocd;
    const std::uint16_t disk = u16(e + 4), cd_disk = u16(e + 6), here = u16(e + 8), count = u16(e + 10);
    const std::uint32_t cd_size = u32(e + 12), cd_offset = u32(e + 16);
    if (count == 0xffff || cd_size == 0xffffffffu || cd_offset == 0xffffffffu)
        return make_error("zip64 archives are not read");
    if (disk != 0 || cd_disk != 0 || here != count) return make_error("multi-disk archives are not read");
    if (std::uint64_t(cd_offset) + cd_size > eocd)
        return make_error("central directory runs past its end record");
    ZipArchive z;
    z.bytes_ = &b;
    std::size_t at = cd_offset;
    const std::size_t end = std::size_t(cd_offset) + cd_size;
    for (std::uint16_t i = 0; i < count; ++i) {
        if (end - at < 46 || u32(b.data() + at) != 0x02014b50u)
            return make_error("central directory entry " + std::to_string(i) + " is missing or truncated");
        const unsigned char* c = b.data() + at;
        Entry en;
        en.flags = u16(c + 8), en.method = u16(c + 10), en.crc = u32(c + 16);
        en.packed = u32(c + 20), en.size = u32(c + 24), en.local = u32(c + 42);
        const std::size_t name_len = u16(c + 28), extra = u16(c + 30), comment = u16(c + 32);
        if (end - at - 46 < name_len + extra + comment)
            return make_error("central directory entry " + std::to_string(i) + " is truncated");
        en.name.assign(reinterpret_cast<const char*>(c + 46), name_len);
        at += 46 + name_len + extra + comment;
        z.entries_.push_back(std::move(en));
    }
    return z;
}

bool ZipArchive::contains(const std::string& name) const {
    return std::any_of(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.name == name; });
}

Result<std::vector<unsigned char>> ZipArchive::read(const std::string& name) const {
    auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.name == name; });
    if (it == entries_.end()) return make_error("archive has no entry '" + name + "'");
    const Entry& en = *it;
    auto fail = [&](const std::string& why) { return make_error("entry '" + name + "': " + why); };
    if (en.flags & 1u) return fail("is encrypted");
    if (en.method != 0 && en.method != 8)
        return fail("compression method " + std::to_string(en.method) +
                    " (only stored and deflate are read)");
    if (en.size > kMaxZipEntryBytes)
        return fail(std::to_string(en.size) + " bytes, more than the " + std::to_string(kMaxZipEntryBytes) +
                    "-byte limit");
    // Deflate expands at most ~1032:1; a stored entry is its own size.
    if (en.method == 0 ? en.size != en.packed : double(en.size) > double(en.packed) * 1032.0 + 64.0)
        return fail("declares " + std::to_string(en.size) + " bytes from " + std::to_string(en.packed) +
                    " stored");
    const std::vector<unsigned char>& b = *bytes_;
    if (en.local > b.size() || b.size() - en.local < 30 || u32(b.data() + en.local) != 0x04034b50u)
        return fail("bad local header");
    const std::uint64_t data =
        en.local + 30 + u16(b.data() + en.local + 26) + std::uint64_t(u16(b.data() + en.local + 28));
    if (data > b.size() || b.size() - data < en.packed) return fail("runs past the end of the archive");
    std::vector<unsigned char> out(static_cast<std::size_t>(en.size));
    const unsigned char* src = b.data() + data;
    if (en.method == 0) {
        std::copy(src, src + en.size, out.begin());
    } else {
        z_stream s{};
        if (inflateInit2(&s, -MAX_WBITS) != Z_OK) return fail("zlib initialisation failed");
        s.next_in = const_cast<unsigned char*>(src);
        s.avail_in = uInt(en.packed);
        s.next_out = out.data();
        s.avail_out = uInt(out.size());
        unsigned char spare = 0;
        int rc = inflate(&s, Z_FINISH);
        const std::size_t got = s.total_out;
        if (rc == Z_BUF_ERROR && s.avail_out == 0) {  // full: is there more than declared?
            s.next_out = &spare, s.avail_out = 1;
            rc = inflate(&s, Z_FINISH);
            if (s.avail_out == 0) rc = Z_DATA_ERROR;
        }
        inflateEnd(&s);
        if (rc != Z_STREAM_END || got != en.size)
            return fail("corrupt deflate data or not the " + std::to_string(en.size) + " bytes declared");
    }
    if (crc32(0L, out.data(), uInt(out.size())) != en.crc) return fail("CRC-32 does not match");
    return out;
}

}  // namespace sffd::gaussian
