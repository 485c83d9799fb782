#include "runtime/assets/formats/archive/gaussian_zip_write.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace sffd::gaussian {

namespace {

void put16(std::string& s, std::uint32_t v) { s += char(v & 0xff), s += char((v >> 8) & 0xff); }
void put32(std::string& s, std::uint32_t v) { put16(s, v & 0xffff), put16(s, v >> 16); }

constexpr std::uint32_t kDosDate = (0u << 9) | (1u << 5) | 1u;  // 1980-01-01, 00:00
constexpr std::uint32_t kUtf8 = 0x800;

// The fields local and central headers share: version needed, flags, method, time, date, CRC, sizes, name.
void common(std::string& s, std::uint32_t crc, std::uint32_t size, std::size_t name) {
    put16(s, 20), put16(s, kUtf8), put16(s, 0), put16(s, 0), put16(s, kDosDate);
    put32(s, crc), put32(s, size), put32(s, size), put16(s, std::uint32_t(name));
}

}  // namespace

Status write_zip_stored(std::FILE* f, const std::vector<ZipEntryData>& entries, const std::string& what) {
    std::uint64_t total = 22;
    for (const ZipEntryData& e : entries) total += 30 + 46 + 2 * e.name.size() + e.data.size();
    if (total >= 0xffffffffu || entries.size() > 0xffff)
        return make_error(what + ": " + std::to_string(total) +
                          " bytes or too many entries for a ZIP without zip64");
    const auto out = [&](std::string_view bytes) -> Status {
        if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size())
            return make_error(what + ": write failed: " + std::strerror(errno));
        return {};
    };
    std::string central;
    std::uint32_t offset = 0;
    for (const ZipEntryData& e : entries) {
        // zlib's crc32 takes uInt lengths: fed in pieces below 4 GiB.
        uLong crc = crc32(0L, Z_NULL, 0);
        for (std::size_t at = 0; at < e.data.size(); at += std::size_t(1) << 30) {
            const std::size_t len = std::min(e.data.size() - at, std::size_t(1) << 30);
            crc = crc32(crc, reinterpret_cast<const Bytef*>(e.data.data() + at), uInt(len));
        }
        const std::uint32_t size = std::uint32_t(e.data.size());
        std::string local;
        put32(local, 0x04034b50);
        common(local, std::uint32_t(crc), size, e.name.size());
        put16(local, 0);  // extra field
        local += e.name;
        if (Status s = out(local); !s) return s;
        if (Status s = out(e.data); !s) return s;
        put32(central, 0x02014b50);
        put16(central, 20);  // made by: MS-DOS attributes, ZIP 2.0
        common(central, std::uint32_t(crc), size, e.name.size());
        put16(central, 0), put16(central, 0), put16(central, 0),
            put16(central, 0);  // extra, comment, disk, attrs
        put32(central, 0), put32(central, offset);
        central += e.name;
        offset += std::uint32_t(local.size() + e.data.size());
    }
    std::string end;
    put32(end, 0x06054b50);
    put16(end, 0), put16(end, 0), put16(end, std::uint32_t(entries.size())),
        put16(end, std::uint32_t(entries.size()));
    put32(end, std::uint32_t(central.size())), put32(end, offset), put16(end, 0);
    if (Status s = out(central); !s) return s;
    return out(end);
}

}  // namespace sffd::gaussian
