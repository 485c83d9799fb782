// A minimal ZIP reader for the archives Gaussian formats travel in (a `.sog` is one): the end-of-central-
// directory record, the central directory, and entries stored (method 0) or deflated (method 8). The
// sizes and CRC-32 come from the central directory (writers such as splat-transform put zeros in the
// local headers and the real values in data descriptors). Refused with a message: no end record, zip64,
// a multi-disk archive, encryption, other methods, entries or records running past the file, a bad
// local header, a decoded size or CRC-32 that does not match, entries over the budget.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::gaussian {

inline constexpr std::uint64_t kMaxZipEntryBytes = std::uint64_t(1) << 30;  // decoded, per entry

class ZipArchive {
public:
    // Parses the directory of `bytes` (the whole archive, kept by the caller alive while this is used).
    static Result<ZipArchive> open(const std::vector<unsigned char>& bytes);
    bool contains(const std::string& name) const;
    // The decoded entry; errors name the entry, not the archive (the caller prefixes the file).
    Result<std::vector<unsigned char>> read(const std::string& name) const;

private:
    struct Entry {
        std::string name;
        std::uint16_t method = 0, flags = 0;
        std::uint32_t crc = 0;
        std::uint64_t packed = 0, size = 0, local = 0;
    };
    const std::vector<unsigned char>* bytes_ = nullptr;
    std::vector<Entry> entries_;
};

}  // namespace sffd::gaussian
