#include "runtime/core/atomic_file.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/core/file_io.h"
#include "runtime/core/log.h"

namespace sffd {
namespace fs = std::filesystem;

namespace {

// Temporaries alive in this process, readable from a signal handler: fixed slots, no allocation.
constexpr int kSlots = 64;
constexpr std::size_t kPathMax = 4096;
struct Slot {
    std::atomic<int> state{0};  // 0 free, 1 being written, 2 live
    char path[kPathMax];
};
Slot g_slots[kSlots];
// Temporaries being created and registered, and whether a handler is removing them. The creating thread
// holds SIGINT/SIGTERM meanwhile, but a signal sent to the process goes to any thread that does not (the
// deformers' worker threads), and the other threads run on while that handler does: it found temporaries
// that existed but were not registered yet, or were created after it looked, and left them behind. Now
// the handler says it is exiting, then waits for the creations under way; a creation that starts after
// it never creates (g_creating and g_exiting are sequentially consistent: one side sees the other).
std::atomic<int> g_creating{0};
std::atomic<bool> g_exiting{false};
std::atomic<const char*> g_program{"splatffd"};
std::once_flag g_handlers_once;

int register_temporary(const std::string& path) {
    if (path.size() + 1 > kPathMax) return -1;
    for (int i = 0; i < kSlots; ++i) {
        int expected = 0;
        if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
            std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
            g_slots[i].state = 2;
            return i;
        }
    }
    return -1;  // more than 64 saves at once: still atomic, just not removed on a signal
}

void unregister_temporary(int slot) {
    if (slot >= 0) g_slots[slot].state = 0;
}

void write_stderr(const char* s) {
    const std::size_t n = std::strlen(s);
    const ssize_t r = ::write(STDERR_FILENO, s, n);
    (void)r;
}

// Waits, up to 2 s (a creation stuck in the file system must not hold the exit forever), for the
// temporaries being created to be registered. Never on the creating thread: it holds the signals.
void wait_for_creations() {
    timespec start{}, now{};
    ::clock_gettime(CLOCK_MONOTONIC, &start);
    while (g_creating.load() != 0) {
        ::clock_gettime(CLOCK_MONOTONIC, &now);
        if (now.tv_sec - start.tv_sec >= 2) break;
    }
}

extern "C" void on_interrupt(int sig) {
    // Async-signal-safe only: clock_gettime, unlink, write, _exit.
    g_exiting.store(true);
    wait_for_creations();
    int removed = 0;
    for (Slot& s : g_slots)
        if (s.state.load() == 2 && ::unlink(s.path) == 0) ++removed;
    write_stderr("\n");
    write_stderr(g_program.load());
    write_stderr(sig == SIGINT ? ": interrupted (SIGINT)" : ": terminated (SIGTERM)");
    write_stderr(removed ? "; unfinished output removed, previous files left as they were\n"
                         : "; nothing was being saved\n");
    ::_exit(128 + sig);
}

void install_handlers() {
    std::call_once(g_handlers_once, [] {
        struct sigaction sa {};
        sa.sa_handler = on_interrupt;
        sigemptyset(&sa.sa_mask);
        for (int sig : {SIGINT, SIGTERM}) {
            struct sigaction old {};
            // A parent that ignores the signal (nohup, some CI runners) keeps it ignored.
            if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
            sigaction(sig, &sa, nullptr);
        }
    });
}

mode_t current_umask() {
    static const mode_t mask = [] {
        const mode_t m = ::umask(022);
        ::umask(m);
        return m;
    }();
    return mask;
}

bool pid_alive(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

// Parses the decimal pid at the start of `s`; -1 if there is none.
long leading_pid(std::string_view s) {
    long pid = 0;
    std::size_t i = 0;
    for (; i < s.size() && i < 10 && s[i] >= '0' && s[i] <= '9'; ++i) pid = pid * 10 + (s[i] - '0');
    return i == 0 ? -1 : pid;
}

}  // namespace

void install_interrupt_cleanup(const char* program) {
    if (program) g_program = program;
    install_handlers();
}

namespace {

// A temporary left by a process that is gone: which output it belongs to, and its path.
struct Stale {
    std::string output_name;
    fs::path path;
};

// One scan per folder per process (a render sequence saves thousands of frames into one folder): the
// stale temporaries found are remembered by output name and removed when that output is saved.
std::mutex g_stale_mutex;
std::map<std::string, std::vector<Stale>> g_stale_by_folder;

std::vector<Stale> scan_folder(const fs::path& folder) {
    std::vector<Stale> found;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string f = it->path().filename().string();
        std::string output;
        long pid = -1;
        if (const auto at = f.find(".sffd-tmp-");
            f.size() > 1 && f[0] == '.' && at != std::string::npos && at > 1) {
            // .<name>.sffd-tmp-<pid>-XXXXXX
            const std::string_view rest = std::string_view(f).substr(at + 10);
            pid = leading_pid(rest);
            const std::size_t digits = pid < 0 ? 0 : std::to_string(pid).size();
            if (pid < 0 || rest.size() <= digits || rest[digits] != '-') continue;
            output = f.substr(1, at - 1);
        } else if (const auto old = f.rfind(".tmp-"); old != std::string::npos && old > 0) {
            // <name>.tmp-<pid> (before mkstemp)
            const std::string_view rest = std::string_view(f).substr(old + 5);
            pid = leading_pid(rest);
            if (pid < 0 || rest.size() != std::to_string(pid).size()) continue;
            output = f.substr(0, old);
        } else {
            continue;
        }
        if (pid == static_cast<long>(::getpid()) || pid_alive(pid)) continue;
        struct stat st {};
        if (::lstat(it->path().c_str(), &st) != 0 || !(S_ISREG(st.st_mode) || S_ISLNK(st.st_mode))) continue;
        found.push_back({output, it->path()});
    }
    return found;
}

}  // namespace

namespace {

// The output name as it appears in its temporary's name: the name itself, unless the temporary
// (".<name>.sffd-tmp-<pid>-XXXXXX", up to 38 bytes more) would pass NAME_MAX (255 bytes on every Linux
// file system): then a prefix of the name and a hash of the whole name, so a 250-byte output name can
// still be saved and its stale temporaries still be recognised.
std::string temporary_stem(const std::string& name) {
    constexpr std::size_t kNameMax = 255, kSuffix = 1 + 10 + 20 + 7;  // ".", ".sffd-tmp-", pid, "-XXXXXX"
    if (name.size() + kSuffix <= kNameMax) return name;
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a
    for (const unsigned char c : name) h = (h ^ c) * 1099511628211ull;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
    return name.substr(0, kNameMax - kSuffix - 17) + "~" + hex;
}

}  // namespace

int remove_stale_temporaries(const fs::path& path) {
    const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const std::string name = temporary_stem(path.filename().string());
    std::vector<Stale> mine;
    {
        std::lock_guard lock(g_stale_mutex);
        std::error_code ec;
        const std::string key = fs::weakly_canonical(fs::absolute(folder, ec), ec).string();
        auto it = g_stale_by_folder.find(key);
        if (it == g_stale_by_folder.end()) it = g_stale_by_folder.emplace(key, scan_folder(folder)).first;
        auto& list = it->second;
        for (auto s = list.begin(); s != list.end();) {
            if (s->output_name == name) {
                mine.push_back(std::move(*s));
                s = list.erase(s);
            } else {
                ++s;
            }
        }
    }
    int removed = 0;
    for (const Stale& s : mine)
        if (::unlink(s.path.c_str()) == 0) {
            ++removed;
            log::info(path.string(), ": removed a stale temporary file of an interrupted save (",
                      s.path.filename().string(), ")");
        }
    return removed;
}

struct AtomicFile::Impl {
    fs::path path, target, tmp;
    std::FILE* file = nullptr;
    int slot = -1;
    bool done = false;

    ~Impl() {
        if (file) std::fclose(file);
        if (!done && !tmp.empty()) ::unlink(tmp.c_str());
        unregister_temporary(slot);
    }
    Error fail(const std::string& why) const { return make_error(path.string() + ": " + why); }
};

AtomicFile::AtomicFile(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
AtomicFile::AtomicFile(AtomicFile&&) noexcept = default;
AtomicFile& AtomicFile::operator=(AtomicFile&&) noexcept = default;
AtomicFile::~AtomicFile() = default;

std::FILE* AtomicFile::file() const { return m_impl->file; }
const fs::path& AtomicFile::path() const { return m_impl->path; }
const fs::path& AtomicFile::target() const { return m_impl->target; }
const fs::path& AtomicFile::temporary() const { return m_impl->tmp; }

Result<AtomicFile> AtomicFile::create(const fs::path& path) {
    install_handlers();
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->target = path;
    if (path.empty() || path.filename().empty()) return impl->fail("not a file name");
    struct stat lst {};
    mode_t mode = 0666 & ~current_umask();
    if (::lstat(path.c_str(), &lst) == 0) {
        if (S_ISLNK(lst.st_mode)) {
            std::error_code ec;
            const fs::path real = fs::weakly_canonical(fs::absolute(path, ec), ec);
            if (ec) return impl->fail("cannot resolve the symbolic link: " + ec.message());
            impl->target = real;
            log::warn(path.string(), ": is a symbolic link; replacing its target ", real.string());
        }
        struct stat st {};
        if (::stat(impl->target.c_str(), &st) == 0) {
            if (!S_ISREG(st.st_mode))
                return impl->fail(std::string("not a regular file (") + file_kind(st.st_mode) +
                                  "); refusing to replace it");
            mode = st.st_mode & 07777;
        }
    }
    remove_stale_temporaries(impl->target);
    const fs::path folder = impl->target.parent_path();
    std::string base(".");  // built by appending: GCC 12 warns (-Wrestrict) on "." + std::string
    base += temporary_stem(impl->target.filename().string());
    base += ".sffd-tmp-";
    base += std::to_string(::getpid());
    base += "-XXXXXX";
    std::string templ = (folder / base).string();
    // SIGINT/SIGTERM are held in this thread while the temporary is created and registered, and a
    // handler on any other thread waits for g_creating: a signal never finds a temporary it does not know
    // about (here it is delivered, and the temporary removed, right after).
    sigset_t hold, previous;
    sigemptyset(&hold);
    sigaddset(&hold, SIGINT);
    sigaddset(&hold, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &hold, &previous);
    g_creating.fetch_add(1);
    if (g_exiting.load()) {  // a handler is removing the temporaries and ends the process: create none
        g_creating.fetch_sub(1);
        for (;;) ::pause();  // the signals are held here: only the handler's _exit ends this
    }
    const int fd = ::mkostemp(templ.data(), O_CLOEXEC);
    const int mkstemp_errno = errno;
    if (fd >= 0) impl->slot = register_temporary(templ);
    g_creating.fetch_sub(1);
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    if (fd < 0) return impl->fail(std::string("cannot write: ") + std::strerror(mkstemp_errno));
    impl->tmp = templ;
    if (::fchmod(fd, mode) != 0) {
        ::close(fd);
        return impl->fail(std::string("cannot set permissions: ") + std::strerror(errno));
    }
    impl->file = ::fdopen(fd, "wb");
    if (!impl->file) {
        ::close(fd);
        return impl->fail(std::string("cannot write: ") + std::strerror(errno));
    }
    return AtomicFile(std::move(impl));
}

Status AtomicFile::commit() {
    Impl& m = *m_impl;
    if (m.done || !m.file) return m.fail("commit(): already finished");
    Status status;
    if (std::fflush(m.file) != 0) status = m.fail(std::string("write failed: ") + std::strerror(errno));
    if (status && ::fsync(fileno(m.file)) != 0)
        status = m.fail(std::string("fsync failed: ") + std::strerror(errno));
    const int rc = std::fclose(m.file);
    m.file = nullptr;
    if (rc != 0 && status) status = m.fail(std::string("close failed: ") + std::strerror(errno));
    if (status && ::rename(m.tmp.c_str(), m.target.c_str()) != 0)
        status = m.fail(std::string("cannot rename temporary file: ") + std::strerror(errno));
    if (status) m.done = true;  // renamed: nothing to remove
    return status;
}

Status write_file_atomic(const fs::path& path, const std::function<Status(std::FILE*)>& write) {
    auto file = AtomicFile::create(path);
    if (!file) return file.error();
    if (Status s = write(file->file()); !s) return s;
    return file->commit();
}

Status write_file_atomic(const fs::path& path, std::string_view contents) {
    return write_file_atomic(path, [&](std::FILE* f) -> Status {
        if (!contents.empty() && std::fwrite(contents.data(), 1, contents.size(), f) != contents.size())
            return make_error(path.string() + ": write failed: " + std::strerror(errno));
        return {};
    });
}

}  // namespace sffd
