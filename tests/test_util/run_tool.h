// Runs the built `splatffd` binary (or any shell command) as a user does, for the command-line tests: the
// test executables are compiled with SFFD_BINARY_DIR (tests/CMakeLists.txt, sffd_test) naming the build
// folder.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sffd::test {

struct CliRun {
    int code = -1;    // exit status; -1 when the command could not start or did not exit normally
    std::string out;  // stdout + stderr
};

// COMMAND through the shell with stderr joined to stdout.
inline CliRun run_command(const std::string& command) {
    const std::string cmd = command + " 2>&1";
    CliRun r;
    std::FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf{};
    while (std::size_t n = std::fread(buf.data(), 1, buf.size(), p)) r.out.append(buf.data(), n);
    const int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

// `splatffd ARGS` through the shell (ARGS is pasted as written, so quote paths with spaces).
inline CliRun run(const std::string& args) {
    return run_command(std::string(SFFD_BINARY_DIR) + "/tools/splatffd " + args);
}

// The same as on a machine without a display (DISPLAY and WAYLAND_DISPLAY unset): GL through headless EGL.
inline CliRun run_headless(const std::string& args) {
    return run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(SFFD_BINARY_DIR) +
                       "/tools/splatffd " + args);
}

// COMMAND through the shell (std::system); its exit status, or -1 when it did not exit normally.
inline int run_shell(const std::string& command) {
    const int rc = std::system(command.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace sffd::test
