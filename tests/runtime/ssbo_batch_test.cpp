// gfx::ssbo_batches (runtime/gfx/ssbo_batch.h): the element ranges of a pass whose buffers exceed
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE. CPU only: the limits are given, no context is needed.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/gfx/ssbo_batch.h"

using namespace sffd;

namespace {

gfx::GlLimits small_limits(std::int64_t block, int alignment) {
    gfx::GlLimits l;
    l.max_ssbo_block_size = block;
    l.ssbo_offset_alignment = alignment;
    return l;
}

}  // namespace

TEST(SsboBatches, OneBatchWhenEveryBufferFits) {
    const std::uint64_t strides[] = {64, 48};
    auto b = gfx::ssbo_batches(1000, strides, small_limits(64 * 1000, 256));
    ASSERT_TRUE(b) << b.message();
    ASSERT_EQ(b->size(), 1u);
    EXPECT_EQ((*b)[0].first, 0u);
    EXPECT_EQ((*b)[0].count, 1000u);
    auto none = gfx::ssbo_batches(0, strides, small_limits(64, 256));
    ASSERT_TRUE(none);
    EXPECT_TRUE(none->empty());
}

// Every range fits the block for every stride, every offset is aligned for every stride, and the ranges
// cover 0..count once, in order.
TEST(SsboBatches, RangesCoverTheElementsAlignedAndWithinTheBlock) {
    const std::vector<std::vector<std::uint64_t>> cases = {{64, 64}, {48, 48, 108}, {12}, {192, 16, 0}};
    for (const int align : {1, 16, 64, 256}) {
        for (const auto& strides : cases) {
            const std::int64_t block = 100'000;
            auto b = gfx::ssbo_batches(12'345, strides, small_limits(block, align));
            ASSERT_TRUE(b) << b.message();
            EXPECT_GT(b->size(), 1u);
            std::uint64_t next = 0;
            for (const gfx::SsboBatch& batch : *b) {
                EXPECT_EQ(batch.first, next);
                EXPECT_GT(batch.count, 0u);
                for (const std::uint64_t s : strides) {
                    EXPECT_LE(batch.count * s, std::uint64_t(block)) << "stride " << s;
                    EXPECT_EQ(batch.first * s % std::uint64_t(align), 0u)
                        << "stride " << s << " align " << align;
                }
                next = batch.first + batch.count;
            }
            EXPECT_EQ(next, 12'345u);
        }
    }
}

TEST(SsboBatches, RefusesWhenNotOneAlignedGroupFitsAndNamesTheLimit) {
    const std::uint64_t strides[] = {64};
    auto tiny = gfx::ssbo_batches(10, strides, small_limits(32, 16));  // one element is 64 bytes
    ASSERT_FALSE(tiny);
    EXPECT_NE(tiny.message().find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (32)"), std::string::npos)
        << tiny.message();
    // 108-byte elements at 256-byte alignment: offsets step by 64 elements (6912 bytes) at least.
    const std::uint64_t sh[] = {108};
    EXPECT_FALSE(gfx::ssbo_batches(1000, sh, small_limits(6000, 256)));
    EXPECT_TRUE(gfx::ssbo_batches(1000, sh, small_limits(6912, 256)));
}
