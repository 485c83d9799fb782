// Saving never leaves a half-written file and never writes through a planted link. Every writer (PLY
// streams, GLB/glTF, PNG/EXR frames, lattices, clips, reports) goes through AtomicFile:
//   - the temporary is created with mkstemp (O_CREAT|O_EXCL, mode 0600) in the output's folder, named
//     `.<name>.sffd-tmp-<pid>-XXXXXX`, so a planted file or symlink of that name is never followed;
//   - an existing output that is not a regular file (a FIFO, a device such as /dev/null, a folder) is
//     refused: `path: not a regular file (a FIFO); refusing to replace it`;
//   - an output that is a symlink: its target is replaced, not the link, and a warning says so;
//   - the replaced file's permission bits are kept (a new file gets 0666 & ~umask, as fopen would);
//   - commit() flushes, fsyncs and renames over the output; anything else (an error, the destructor,
//     SIGINT/SIGTERM) removes the temporary and leaves the old output untouched;
//   - SIGINT/SIGTERM: the temporaries of this process are removed, a message is printed and the process
//     exits 130/143 (handlers installed by the first AtomicFile), on whichever thread the signal lands:
//     the handler waits for temporaries being created and no new one is created after it starts
//     (test AtomicFile.ASignalOnAnyThreadNeverLeavesATemporaryBehind);
//   - stale temporaries of the same output left by a process that no longer exists (SIGKILL, power
//     loss) are removed when the next save of that output starts (`.<name>.sffd-tmp-<pid>-*` and the
//     older `<name>.tmp-<pid>`, only regular files or links, only when <pid> is not running; each folder
//     is scanned once per process, so a sequence of thousands of frames does not rescan it per frame).
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string_view>

#include "runtime/core/result.h"

namespace sffd {

class AtomicFile {
public:
    static Result<AtomicFile> create(const std::filesystem::path& path);
    AtomicFile(AtomicFile&&) noexcept;
    AtomicFile& operator=(AtomicFile&&) noexcept;
    ~AtomicFile();  // not committed: the temporary is removed

    std::FILE* file() const;                      // binary mode, positioned at 0
    const std::filesystem::path& path() const;    // the output as named
    const std::filesystem::path& target() const;  // the file that will be replaced (link resolved)
    const std::filesystem::path& temporary() const;
    Status commit();  // flush, fsync, rename; the object is spent

private:
    struct Impl;
    explicit AtomicFile(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

// `write` receives an open FILE* (binary mode) and returns an error to abort the save.
Status write_file_atomic(const std::filesystem::path& path, const std::function<Status(std::FILE*)>& write);
Status write_file_atomic(const std::filesystem::path& path, std::string_view contents);

// Removes stale temporaries of `path` (see above); returns how many were removed. Called by create().
int remove_stale_temporaries(const std::filesystem::path& path);

// Installs the SIGINT/SIGTERM handlers now (create() does it too); the exit message names `program`.
void install_interrupt_cleanup(const char* program);

}  // namespace sffd
