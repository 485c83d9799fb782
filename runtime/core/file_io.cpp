#include "runtime/core/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <new>

namespace sffd {
namespace fs = std::filesystem;

namespace {

std::atomic<bool> g_allow_outside{false};

Error not_regular(const fs::path& path, mode_t m) {
    const std::string kind = file_kind(m);
    return make_error(path.string() + ": not a regular file" +
                      (kind == "not a regular file" ? "" : " (" + kind + ")"));
}

// Closes the descriptor on every path out of read_file().
struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

}  // namespace

const char* file_kind(mode_t m) {
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISSOCK(m)) return "a socket";
    if (S_ISDIR(m)) return "a folder";
    return "not a regular file";
}

Result<std::string> read_file(const fs::path& path, std::uint64_t limit) {
    Fd f;
    f.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (f.fd < 0)
        return make_error(path.string() + (errno == ENOENT
                                               ? std::string(": cannot open: no such file")
                                               : std::string(": cannot open: ") + std::strerror(errno)));
    struct stat st {};
    if (::fstat(f.fd, &st) != 0) return make_error(path.string() + ": cannot stat: " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) return not_regular(path, st.st_mode);
    const auto size = static_cast<std::uint64_t>(st.st_size);
    if (size > limit)
        return make_error(path.string() + ": file is " + std::to_string(size) + " bytes, more than the " +
                          std::to_string(limit) + "-byte limit");
    std::string out;
    try {
        out.resize(static_cast<std::size_t>(size));
    } catch (const std::bad_alloc&) {
        return make_error(path.string() + ": out of memory reading " + std::to_string(size) + " bytes");
    }
    std::size_t done = 0;
    while (done < out.size()) {
        const ssize_t n = ::read(f.fd, out.data() + done, out.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return make_error(path.string() + ": cannot read: " + std::strerror(errno));
        if (n == 0) break;  // shrank while reading
        done += static_cast<std::size_t>(n);
    }
    out.resize(done);
    return out;
}

void set_allow_outside_resources(bool allow) { g_allow_outside = allow; }
bool allow_outside_resources() { return g_allow_outside; }

Result<fs::path> resolve_resource(const fs::path& owner, std::string_view uri) {
    const std::string quoted = "resource '" + std::string(uri.substr(0, 200)) + "'";
    auto outside = [&] {
        return make_error(owner.string() + ": " + quoted + " is outside the file's folder");
    };
    if (uri.empty()) return make_error(owner.string() + ": empty resource name");
    if (uri.find('\0') != std::string_view::npos)
        return make_error(owner.string() + ": " + quoted + " contains a NUL byte");
    std::error_code ec;
    const fs::path folder = fs::weakly_canonical(fs::absolute(owner, ec).parent_path(), ec);
    if (ec) return make_error(owner.string() + ": cannot resolve the file's folder: " + ec.message());
    const fs::path rel(uri);
    const bool allow = allow_outside_resources();
    fs::path candidate;
    if (rel.is_absolute()) {
        if (!allow) return outside();
        candidate = rel.lexically_normal();
    } else {
        const fs::path norm = rel.lexically_normal();
        if (!allow && (norm.empty() || *norm.begin() == "..")) return outside();
        candidate = (folder / norm).lexically_normal();
    }
    struct stat st {};
    if (::stat(candidate.c_str(), &st) != 0) return make_error(owner.string() + ": " + quoted + " not found");
    // Symlinks (of the file or of folders on the way) must not lead out of the folder either.
    const fs::path real = fs::canonical(candidate, ec);
    if (ec) return make_error(owner.string() + ": " + quoted + " cannot be resolved: " + ec.message());
    if (!allow) {
        const auto [f_end, r_it] = std::mismatch(folder.begin(), folder.end(), real.begin(), real.end());
        if (f_end != folder.end()) return outside();
    }
    if (!S_ISREG(st.st_mode))
        return make_error(owner.string() + ": " + quoted + " is " + file_kind(st.st_mode) +
                          ", not a regular file");
    return real;
}

Status check_json_depth(std::string_view text, const std::string& name, int max_depth) {
    int depth = 0;
    bool in_string = false, escaped = false;
    for (const char c : text) {
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
            continue;
        }
        if (c == '"') in_string = true;
        else if (c == '[' || c == '{') {
            if (++depth > max_depth)
                return make_error(name + ": JSON nesting deeper than " + std::to_string(max_depth) +
                                  " levels");
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return {};
}

}  // namespace sffd
