#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"

using namespace sffd;

TEST(Log, CaptureSinkSeesMessages) {
    log::ScopedLogCapture capture;
    log::warn("lattice ", 3, " is inverted");
    EXPECT_TRUE(capture.contains("lattice 3 is inverted"));
    EXPECT_EQ(capture.entries().at(0).level, log::Level::warn);
}

TEST(AtomicFile, FailedWriteLeavesOldFileUntouched) {
    const auto path = std::filesystem::temp_directory_path() / "sffd_atomic_test.txt";
    ASSERT_TRUE(write_file_atomic(path, "old"));
    Status s = write_file_atomic(path, [](std::FILE* f) -> Status {
        std::fputs("half", f);
        return make_error("simulated failure");
    });
    EXPECT_FALSE(s);
    std::ifstream in(path);
    std::string content((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(content, "old");
    for (auto& entry : std::filesystem::directory_iterator(path.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find("sffd_atomic_test.txt.tmp"), std::string::npos);
    std::filesystem::remove(path);
}
