// The heap policy of frame-rendering programs (runtime/core/allocator.h), observed through glibc's own
// accounting: frame-sized blocks come from the heap and stay there when freed; cloud-sized ones are mapped.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "runtime/core/allocator.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define SFFD_TEST_OWN_ALLOCATOR 0  // the sanitizer's allocator replaces glibc's
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SFFD_TEST_OWN_ALLOCATOR 0
#endif
#endif
#ifndef SFFD_TEST_OWN_ALLOCATOR
#define SFFD_TEST_OWN_ALLOCATOR 1
#endif

TEST(Allocator, FrameSizedBlocksStayInTheProcessCloudSizedOnesAreReturned) {
#if !defined(__GLIBC__) || !SFFD_TEST_OWN_ALLOCATOR
    GTEST_SKIP() << "the policy sets glibc's allocator; this build does not use it";
#else
    sffd::keep_freed_frame_memory();
    constexpr std::size_t kFrameBlock = 8u << 20;  // glibc's default maps blocks from 128 KiB up
    const struct mallinfo2 before = mallinfo2();
    void* block = std::malloc(kFrameBlock);
    ASSERT_NE(block, nullptr);
    std::memset(block, 1, kFrameBlock);
    EXPECT_EQ(mallinfo2().hblkhd, before.hblkhd) << "served from the heap, not a fresh mapping";
    std::free(block);
    EXPECT_GE(mallinfo2().fordblks, before.fordblks + kFrameBlock) << "kept free in the heap, not trimmed";
    constexpr std::size_t kCloudBlock = 64u << 20;
    void* cloud = std::malloc(kCloudBlock);
    ASSERT_NE(cloud, nullptr);
    EXPECT_GE(mallinfo2().hblkhd, before.hblkhd + kCloudBlock) << "mapped, so freeing returns it";
    std::free(cloud);
    EXPECT_EQ(mallinfo2().hblkhd, before.hblkhd);
#endif
}
