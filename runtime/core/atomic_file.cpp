#include "runtime/core/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace sffd {
namespace fs = std::filesystem;

Status write_file_atomic(const fs::path& path, const std::function<Status(std::FILE*)>& write) {
    const fs::path tmp = path.string() + ".tmp-" + std::to_string(getpid());
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return make_error(path.string() + ": cannot write: " + std::strerror(errno));
    Status status = write(f);
    if (status && std::fflush(f) != 0) status = make_error(path.string() + ": write failed: " + std::strerror(errno));
    if (status && fsync(fileno(f)) != 0) status = make_error(path.string() + ": fsync failed: " + std::strerror(errno));
    if (std::fclose(f) != 0 && status) status = make_error(path.string() + ": close failed: " + std::strerror(errno));
    std::error_code ec;
    if (status) {
        fs::rename(tmp, path, ec);
        if (ec) status = make_error(path.string() + ": cannot rename temporary file: " + ec.message());
    }
    if (!status) fs::remove(tmp, ec);
    return status;
}

Status write_file_atomic(const fs::path& path, std::string_view contents) {
    return write_file_atomic(path, [&](std::FILE* f) -> Status {
        if (!contents.empty() && std::fwrite(contents.data(), 1, contents.size(), f) != contents.size())
            return make_error(path.string() + ": write failed: " + std::strerror(errno));
        return {};
    });
}

}  // namespace sffd
