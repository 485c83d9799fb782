// GLB containers read by load_gltf_model(): buffer 0 is the BIN chunk (copied in parallel from the mapped
// file), other buffers keep their URIs, and broken containers are refused with the file's name.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "runtime/assets/gltf_io.h"
#include "tests/assets/test_util.h"

namespace sffd::assets {
namespace {
namespace fs = std::filesystem;

std::string floats(std::initializer_list<float> v) {
    std::string s(v.size() * 4, '\0');
    std::memcpy(s.data(), std::data(v), s.size());
    return s;
}

// A GLB of `json` (space-padded to 4 bytes) and a BIN chunk of `bin` (`bin_len` overrides its length).
std::string glb(std::string json, const std::string& bin, std::int64_t bin_len = -1) {
    while (json.size() % 4) json += ' ';
    std::string out = "glTF";
    auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
    u32(static_cast<std::uint32_t>(json.size()));
    u32(0x4E4F534Au);
    out += json;
    u32(static_cast<std::uint32_t>(bin_len < 0 ? std::int64_t(bin.size()) : bin_len));
    u32(0x004E4942u);
    return out + bin;
}

std::string two_points_json(const std::string& extra_buffers = "", std::uint32_t length = 24) {
    return R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + std::to_string(length) + "}" +
           extra_buffers + R"(],"bufferViews":[{"buffer":0,"byteLength":24}],)" +
           R"("accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"VEC3"}]})";
}

TEST(GlbContainer, BufferZeroIsTheBinChunkWithoutItsPadding) {
    const fs::path dir = test::fresh_dir("glb", "padded");
    const fs::path p = dir / "padded.glb";
    test::write(p, glb(two_points_json(), floats({1, 2, 3, 4, 5, 6, 7, 8})));
    tinygltf::Model m;
    const Status s = load_gltf_model(p, m);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.buffers.size(), 1u);
    EXPECT_EQ(m.buffers[0].data.size(), 24u);
    auto v = read_gltf_accessor(m, 0, 3, p.string(), "POSITION");
    ASSERT_TRUE(v.ok()) << v.message();
    EXPECT_EQ(*v, (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

TEST(GlbContainer, AFileBesideTheGlbNeverStandsInForTheBinChunk) {
    const fs::path dir = test::fresh_dir("glb", "beside");
    for (const auto& entry : {"glb-bin-chunk.sffd-internal", "padded.bin"})
        test::write(dir / entry, floats({9, 9, 9, 9, 9, 9}));
    const fs::path p = dir / "beside.glb";
    test::write(p,
                glb(two_points_json(R"(,{"byteLength":24,"uri":"padded.bin"})"), floats({1, 2, 3, 4, 5, 6})));
    tinygltf::Model m;
    const Status s = load_gltf_model(p, m);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.buffers.size(), 2u);
    auto v = read_gltf_accessor(m, 0, 3, p.string(), "POSITION");
    ASSERT_TRUE(v.ok()) << v.message();
    EXPECT_EQ(*v, (std::vector<double>{1, 2, 3, 4, 5, 6}));
    // The second buffer is still read from its URI.
    ASSERT_EQ(m.buffers[1].data.size(), 24u);
    float first = 0;
    std::memcpy(&first, m.buffers[1].data.data(), 4);
    EXPECT_EQ(first, 9.0f);
}

TEST(GlbContainer, BrokenContainersAreRefusedNamingTheFile) {
    const fs::path dir = test::fresh_dir("glb", "broken");
    const std::string bin = floats({1, 2, 3, 4, 5, 6});
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"longer_buffer.glb", glb(two_points_json("", 28), bin)},
        {"bin_past_end.glb", glb(two_points_json(), bin, 4096)},
        {"version3.glb",
         [&] {
             std::string g = glb(two_points_json(), bin);
             g[4] = 3;
             return g;
         }()},
        {"truncated.glb", glb(two_points_json(), bin).substr(0, 40)},
    };
    for (const auto& [name, bytes] : cases) {
        const fs::path p = dir / name;
        test::write(p, bytes);
        tinygltf::Model m;
        const Status s = load_gltf_model(p, m);
        ASSERT_FALSE(s.ok()) << name << " was accepted";
        EXPECT_NE(s.message().find(p.string() + ": "), std::string::npos) << s.message();
    }
}

}  // namespace
}  // namespace sffd::assets
