// A save interrupted by SIGTERM while other threads run (as the deformers' worker threads do): the
// signal goes to any thread that does not hold it, including while the saving thread creates its
// temporary; the handler must still find and remove it.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <thread>

#include "runtime/core/atomic_file.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;

// The child: two threads that never hold the signals, and a loop creating and dropping temporaries. It
// writes to `ready` once the handler is installed and the threads run.
[[noreturn]] void save_forever(const fs::path& out, int ready) {
    std::freopen("/dev/null", "w", stderr);  // the handler's message, once per round
    ::signal(SIGTERM, SIG_DFL);              // a runner that ignores it would keep it ignored
    install_interrupt_cleanup("atomic_file_signal_test");
    static std::atomic<bool> spin{true};
    for (int i = 0; i < 2; ++i)
        std::thread([] {
            while (spin.load()) {
            }
        }).detach();
    if (::write(ready, "r", 1) != 1) ::_exit(4);
    for (;;) {
        auto f = AtomicFile::create(out);
        if (!f) ::_exit(3);
    }
}

TEST(AtomicFile, ASignalOnAnyThreadNeverLeavesATemporaryBehind) {
    const fs::path dir = fs::temp_directory_path() / ("sffd_atomic_signal_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    int left = 0;
    for (int round = 0; round < 40; ++round) {
        int ready[2];
        ASSERT_EQ(::pipe(ready), 0);
        const pid_t pid = ::fork();
        ASSERT_GE(pid, 0);
        if (pid == 0) save_forever(dir / "out.txt", ready[1]);
        char byte = 0;
        const bool started = ::read(ready[0], &byte, 1) == 1;
        ::close(ready[0]), ::close(ready[1]);
        EXPECT_TRUE(started) << "round " << round;
        ::usleep(useconds_t(1000 + (round * 797) % 5000));  // somewhere in the loop
        ::kill(pid, SIGTERM);
        int status = 0;
        for (int waited = 0; ::waitpid(pid, &status, WNOHANG) == 0; ++waited) {
            if (waited == 5000) {  // 5 s: the handler never ran
                ::kill(pid, SIGKILL);
                ::waitpid(pid, &status, 0);
                ADD_FAILURE() << "round " << round << ": SIGTERM did not end the child";
                break;
            }
            ::usleep(1000);
        }
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM)
            << "round " << round << ": wait status " << status;
        for (const auto& e : fs::directory_iterator(dir)) {
            ++left;
            ADD_FAILURE() << "round " << round << ": " << e.path().filename() << " left behind";
            fs::remove(e.path());
        }
    }
    EXPECT_EQ(left, 0);
    fs::remove_all(dir);
}

}  // namespace
