// GPU radix sort (runtime/gfx/radix_sort.h) against std::stable_sort on the CPU: random 32-bit keys,
// heavy duplicates (stability: the payload is the input index), counts that are not a multiple of the
// work group or block, 0 and 1 elements, partial key widths, and a 2D grid of blocks (the row width
// lowered so that a few blocks already need several rows, as >65,535 blocks would on any GL).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "runtime/gfx/context.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/radix_sort.h"
#include "tests/test_util/headless_gl.h"

using namespace sffd;

namespace {

class RadixSort : public test::HeadlessGlTest {
protected:
    void SetUp() override {
        HeadlessGlTest::SetUp();
        if (IsSkipped() || HasFatalFailure()) return;
        test::emplace_made(sorter, gfx::create_radix_sorter());
    }
    void TearDown() override { sorter.reset(); }

    // Uploads keys and payloads 0..n-1 into buffers with `tail` sentinel elements after them, sorts the
    // first keys.size() on the GPU, and checks keys, payloads and the untouched tail against the CPU.
    void check(const std::vector<std::uint32_t>& keys, int key_bits = 32, std::uint32_t tail = 3) {
        const std::size_t n = keys.size();
        std::vector<std::uint32_t> k(keys), v(n);
        std::iota(v.begin(), v.end(), 0u);
        for (std::uint32_t t = 0; t < tail; ++t) k.push_back(0xabcd0000u + t), v.push_back(0xdead0000u + t);
        gfx::Buffer kb = gfx::Buffer::create("test.keys"), vb = gfx::Buffer::create("test.values");
        // One spare element so that an empty sort still has storage to bind.
        glNamedBufferData(kb.id(), GLsizeiptr(k.size() * 4 + 4), nullptr, GL_DYNAMIC_COPY);
        glNamedBufferData(vb.id(), GLsizeiptr(v.size() * 4 + 4), nullptr, GL_DYNAMIC_COPY);
        if (!k.empty()) {
            glNamedBufferSubData(kb.id(), 0, GLsizeiptr(k.size() * 4), k.data());
            glNamedBufferSubData(vb.id(), 0, GLsizeiptr(v.size() * 4), v.data());
        }
        const std::uint64_t errors = gfx::debug_error_count();
        ASSERT_TRUE(gfx::radix_sort(*sorter, kb.id(), vb.id(), std::uint32_t(n), key_bits));
        std::vector<std::uint32_t> gk(k.size()), gv(v.size());
        glGetNamedBufferSubData(kb.id(), 0, GLsizeiptr(gk.size() * 4), gk.data());
        glGetNamedBufferSubData(vb.id(), 0, GLsizeiptr(gv.size() * 4), gv.data());
        EXPECT_EQ(gfx::debug_error_count(), errors);

        const std::uint32_t mask = key_bits == 32 ? 0xffffffffu : (1u << key_bits) - 1u;
        std::vector<std::uint32_t> order(n);
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            return (keys[a] & mask) < (keys[b] & mask);
        });
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < n; ++i) wrong += gv[i] != order[i] || gk[i] != keys[order[i]];
        EXPECT_EQ(wrong, 0u) << "of " << n << " pairs";
        for (std::uint32_t t = 0; t < tail; ++t) {
            EXPECT_EQ(gk[n + t], 0xabcd0000u + t) << "element past count was written";
            EXPECT_EQ(gv[n + t], 0xdead0000u + t) << "element past count was written";
        }
    }

    std::optional<gfx::RadixSorter> sorter;
};

std::vector<std::uint32_t> random_keys(std::size_t n, std::uint32_t max, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> u(0, max);
    std::vector<std::uint32_t> k(n);
    for (auto& x : k) x = u(rng);
    return k;
}

TEST_F(RadixSort, RandomKeysMatchStableSort) {
    check(random_keys(100000, 0xffffffffu, 1));
    check(random_keys(2048 * 3, 0xffffffffu, 2));  // whole blocks
}

TEST_F(RadixSort, DuplicatesKeepInputOrder) {
    check(random_keys(50000, 7, 3));               // 8 distinct keys: stability decides almost every slot
    check(std::vector<std::uint32_t>(5000, 42u));  // all equal: the identity permutation
    check(random_keys(20000, 0xffffffffu, 4) /* few duplicates */);
    std::vector<std::uint32_t> desc(3000);
    for (std::size_t i = 0; i < desc.size(); ++i)
        desc[i] = std::uint32_t(desc.size() - i) / 2;  // pairs, reversed
    check(desc);
}

TEST_F(RadixSort, CountsThatAreNotMultiplesOfTheGroup) {
    for (std::size_t n : {2u, 3u, 255u, 257u, 2047u, 2049u, 4097u, 9999u})
        check(random_keys(n, 0xffffu, unsigned(n)));
}

TEST_F(RadixSort, ZeroAndOneElements) {
    check({}, 32, 4);
    check({77u}, 32, 4);
}

TEST_F(RadixSort, FloatDepthBitsSortLikeFloats) {
    // gl_render's keys: floatBitsToUint of positive depths, 0xffffffff for Gaussians not drawn.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.01f, 1000.0f);
    std::vector<float> depth(30000);
    std::vector<std::uint32_t> keys(depth.size());
    for (std::size_t i = 0; i < depth.size(); ++i) {
        depth[i] = i % 7 == 0 ? -1.0f : u(rng);
        std::memcpy(&keys[i], &depth[i], 4);
        if (depth[i] < 0.0f) keys[i] = 0xffffffffu;
    }
    check(keys);
    std::vector<std::uint32_t> sorted = keys;
    std::sort(sorted.begin(), sorted.end());
    float previous = 0.0f;
    for (std::uint32_t k : sorted) {
        if (k == 0xffffffffu) break;
        float f;
        std::memcpy(&f, &k, 4);
        EXPECT_GE(f, previous);
        previous = f;
    }
}

TEST_F(RadixSort, PartialKeyWidthSortsOnlyTheLowBits) {
    // 12 bits (3 passes, an odd count: the result comes back from the scratch buffers); the high bits ride
    // along, so keys equal in the low bits keep their input order.
    check(random_keys(30000, 0xffffffffu, 6), 12);
    // Widths that are not a multiple of the 4-bit digit, with keys below 2^key_bits (the contract).
    check(random_keys(5000, 1, 7), 1);
    check(random_keys(5000, 0x7fffffffu, 8), 31);
}

TEST_F(RadixSort, BlocksBeyondOneGridRow) {
    // 3 work groups per row: 40,000 keys = 20 blocks = a 3 x 7 grid with the last row partly empty,
    // exercising the same 2D indexing that > 65,535 blocks use with the real limit.
    sorter->max_groups_x = 3;
    check(random_keys(40000, 0xffffffffu, 9));
    check(random_keys(40000, 15, 10));
    sorter->max_groups_x = 1;
    check(random_keys(9000, 0xffffffffu, 11));
}

TEST_F(RadixSort, ExclusiveScanWithTotal) {
    // gl_render's tile offsets: in place, total after the elements; block boundaries (2,048), and a grid
    // of blocks over several rows.
    for (std::uint32_t n : {0u, 1u, 255u, 256u, 257u, 2048u, 2049u, 100000u, 1000000u}) {
        sorter->max_groups_x = n == 100000u ? 4u : 0u;
        const std::vector<std::uint32_t> in = random_keys(n, 40, n + 1);
        std::vector<std::uint32_t> data(in);
        data.push_back(0xdeadbeefu);  // the total's slot
        data.push_back(0x12345678u);  // past it: untouched
        gfx::Buffer b = gfx::Buffer::create("test.scan");
        glNamedBufferData(b.id(), GLsizeiptr(data.size() * 4), data.data(), GL_DYNAMIC_COPY);
        ASSERT_TRUE(gfx::exclusive_scan(*sorter, b.id(), n));
        glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(data.size() * 4), data.data());
        std::uint32_t run = 0;
        std::size_t wrong = 0;
        for (std::uint32_t i = 0; i < n; ++i) wrong += data[i] != run, run += in[i];
        EXPECT_EQ(wrong, 0u) << n;
        EXPECT_EQ(data[n], run) << n;
        EXPECT_EQ(data[n + 1], 0x12345678u) << n;
    }
}

TEST_F(RadixSort, BadKeyWidthIsAnError) {
    gfx::Buffer b = gfx::Buffer::create("test.bad");
    glNamedBufferData(b.id(), 64, nullptr, GL_DYNAMIC_COPY);
    auto s = gfx::radix_sort(*sorter, b.id(), b.id(), 4, 33);
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message(), "radix_sort(): key_bits 33 is not in 1..32");
}

// Keys past GL_MAX_SHADER_STORAGE_BLOCK_SIZE (simulated): the sort and the scan refuse, naming the limit,
// instead of reading past the block (their passes index the arrays at random: no ranges).
TEST_F(RadixSort, KeysOverTheBlockSizeAreRefusedNamingTheLimit) {
    gfx::Buffer b = gfx::Buffer::create("test.large");
    glNamedBufferData(b.id(), 4 * 2001, nullptr, GL_DYNAMIC_COPY);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 4000;  // 1,000 keys
    gfx::ScopedLimits scope(small);
    auto s = gfx::radix_sort(*sorter, b.id(), b.id(), 2000);
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message(), "radix_sort(): keys: 8000 bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (4000)");
    auto scan = gfx::exclusive_scan(*sorter, b.id(), 2000);
    ASSERT_FALSE(scan);
    EXPECT_NE(scan.message().find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (4000)"), std::string::npos)
        << scan.message();
}

}  // namespace
