// Writing the ZIP archives Gaussian formats travel in (a `.sog` is one): every entry stored (method 0; the
// SOG images are WebP, already compressed), its CRC-32 and sizes in the local header (no data
// descriptors), UTF-8 names, a fixed 1980-01-01 timestamp so the same entries give the same bytes. No
// zip64: an archive that would pass 4 GiB is refused. gaussian_zip.h reads what this writes.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::gaussian {

struct ZipEntryData {
    std::string name;
    std::string_view data;  // owned by the caller while the archive is written
};

// Writes the archive of `entries`, in order, to `f`; errors read "`what`: problem".
Status write_zip_stored(std::FILE* f, const std::vector<ZipEntryData>& entries, const std::string& what);

}  // namespace sffd::gaussian
