// GLB containers read by load_gltf_model(): buffer 0 is the BIN chunk (read where the file is mapped),
// images stored in it still decode, other buffers keep their URIs, views outside their buffers and broken
// containers are refused with the file's name, and a file shortened after loading is refused by the
// accessor reads that would have seen zeros.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/gltf_detail.h"
#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/formats/surface/gltf_model.h"
#include "runtime/assets/formats/archive/mapping_guard.h"
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

// Writes `bytes` to `p` and loads it.
Status load_written(const fs::path& p, const std::string& bytes) {
    test::write(p, bytes);
    GltfModel m;
    return load_gltf_model(p, m);
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
    GltfModel m;
    const Status s = load_gltf_model(p, m);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.gltf.buffers.size(), 1u);
    EXPECT_EQ(gltf_buffer(m, 0).size(), 24u);
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
    GltfModel m;
    const Status s = load_gltf_model(p, m);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.gltf.buffers.size(), 2u);
    auto v = read_gltf_accessor(m, 0, 3, p.string(), "POSITION");
    ASSERT_TRUE(v.ok()) << v.message();
    EXPECT_EQ(*v, (std::vector<double>{1, 2, 3, 4, 5, 6}));
    // The second buffer is still read from its URI.
    ASSERT_EQ(gltf_buffer(m, 1).size(), 24u);
    float first = 0;
    std::memcpy(&first, gltf_buffer(m, 1).data(), 4);
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
        // A declared total length under the headers' 28 bytes: the chunk checks subtracted past zero and
        // read far beyond the file.
        {"total_zero.glb",
         [&] {
             std::string g = glb(two_points_json(), bin);
             std::memset(g.data() + 8, 0, 4);
             const std::uint32_t huge_json = 0x40000000u;
             std::memcpy(g.data() + 12, &huge_json, 4);
             return g;
         }()},
    };
    for (const auto& [name, bytes] : cases) {
        const Status s = load_written(dir / name, bytes);
        ASSERT_FALSE(s.ok()) << name << " was accepted";
        EXPECT_NE(s.message().find((dir / name).string() + ": "), std::string::npos) << s.message();
    }
}

// A 1x1 RGBA PNG (one opaque red pixel), stored in buffer 0 after the two points.
const unsigned char kRedPixelPng[] = {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d,
                                      0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01,
                                      0x08, 0x06, 0x00, 0x00, 0x00, 0x1f, 0x15, 0xc4, 0x89, 0x00, 0x00, 0x00,
                                      0x0d, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0, 0xf0,
                                      0x1f, 0x00, 0x05, 0x00, 0x01, 0xff, 0x89, 0x99, 0x3d, 0x1d, 0x00, 0x00,
                                      0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

std::string with_image_json(std::size_t png_at, std::size_t png_bytes, std::size_t buffer_bytes) {
    return R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + std::to_string(buffer_bytes) +
           R"(}],"bufferViews":[{"buffer":0,"byteLength":24},{"buffer":0,"byteOffset":)" +
           std::to_string(png_at) + R"(,"byteLength":)" + std::to_string(png_bytes) +
           R"(}],"accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"VEC3"}],)" +
           R"("images":[{"bufferView":1,"mimeType":"image/png"}]})";
}

TEST(GlbContainer, AnImageStoredInBufferZeroDecodes) {
    const fs::path dir = test::fresh_dir("glb", "image");
    const fs::path p = dir / "image.glb";
    std::string bin = floats({1, 2, 3, 4, 5, 6});
    bin.append(reinterpret_cast<const char*>(kRedPixelPng), sizeof kRedPixelPng);
    while (bin.size() % 4) bin += '\0';
    test::write(p, glb(with_image_json(24, sizeof kRedPixelPng, bin.size()), bin));
    GltfModel m;
    const Status s = load_gltf_model(p, m);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.gltf.images.size(), 1u);
    const auto& im = m.gltf.images[0];
    ASSERT_EQ(im.width, 1);
    ASSERT_EQ(im.height, 1);
    ASSERT_EQ(im.component, 4);
    EXPECT_EQ(im.image, (std::vector<unsigned char>{255, 0, 0, 255}));
    auto v = read_gltf_accessor(m, 0, 3, p.string(), "POSITION");
    ASSERT_TRUE(v.ok()) << v.message();
    EXPECT_EQ(*v, (std::vector<double>{1, 2, 3, 4, 5, 6}));
}

// tinygltf itself reads an image's view without a bounds check: these files crashed the reader.
TEST(GlbContainer, AnImageViewOutsideItsBufferIsRefused) {
    const fs::path dir = test::fresh_dir("glb", "image_outside");
    const std::string bin = floats({1, 2, 3, 4, 5, 6});
    const std::string json = with_image_json(2000000000, 100, bin.size());
    // A well-formed container, one off the fast path (JSON length not a multiple of 4), and text glTF.
    std::string off_path = glb(json, bin);
    const std::uint32_t odd = static_cast<std::uint32_t>(json.size() | 1u);
    std::memcpy(off_path.data() + 12, &odd, 4);
    const std::string b64 = "AACAPwAAAEAAAEBAAACAQAAAoEAAAMBA";  // the six floats
    std::string text = json;
    text.replace(text.find(R"("byteLength":24})"), 0,
                 R"("uri":"data:application/octet-stream;base64,)" + b64 + "\",");
    for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
             {"fast.glb", glb(json, bin)}, {"off_path.glb", off_path}, {"text.gltf", text}}) {
        const Status s = load_written(dir / name, bytes);
        ASSERT_FALSE(s.ok()) << name << " was accepted";
        EXPECT_NE(
            s.message().find((dir / name).string() +
                             ": image 0: bufferView 1 (100 bytes at 2000000000) lies outside buffer 0 (24 "
                             "bytes)"),
            std::string::npos)
            << s.message();
    }
}

TEST(GlbContainer, ColoursDecodeToTheWritersSrgbBytes) {
    // Every 16-bit level in each channel of a normalised unsigned short COLOR_0, and float colours with
    // one non-finite value.
    const fs::path dir = test::fresh_dir("glb", "colours");
    const std::size_t n = 65536;
    std::string bin(n * 8, '\0');
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint16_t c[4] = {std::uint16_t(i), std::uint16_t(65535 - i), std::uint16_t(i * 7),
                                    std::uint16_t(i * 13)};
        std::memcpy(bin.data() + i * 8, c, 8);
    }
    const std::string json =
        R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + std::to_string(bin.size()) +
        R"(}],"bufferViews":[{"buffer":0,"byteLength":)" + std::to_string(bin.size()) +
        R"(}],"accessors":[{"bufferView":0,"componentType":5123,"normalized":true,"count":)" +
        std::to_string(n) + R"(,"type":"VEC4"}]})";
    const fs::path p = dir / "ushort.glb";
    test::write(p, glb(json, bin));
    GltfModel m;
    ASSERT_TRUE(load_gltf_model(p, m).ok());
    std::vector<std::uint32_t> got;
    const Status s = read_gltf_colors_into(m, 0, 4, p.string(), "COLOR_0", got);
    ASSERT_TRUE(s.ok()) << s.message();
    auto v = read_gltf_accessor(m, 0, 4, p.string(), "COLOR_0");
    ASSERT_TRUE(v.ok());
    ASSERT_EQ(got.size(), n);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double* c = &(*v)[i * 4];
        const std::uint32_t a = static_cast<std::uint32_t>(std::lround(c[3] * 255.0));
        const std::uint32_t want = gltf_detail::linear_to_srgb8(c[0]) |
                                   gltf_detail::linear_to_srgb8(c[1]) << 8 |
                                   gltf_detail::linear_to_srgb8(c[2]) << 16 | a << 24;
        wrong += got[i] != want;
    }
    EXPECT_EQ(wrong, 0u);

    const std::string fbin = floats({0.0f, 0.5f, 1.0f, 0.25f, std::nanf(""), 0.0f});
    const std::string fjson =
        R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":24}],)"
        R"("bufferViews":[{"buffer":0,"byteLength":24}],)"
        R"("accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"VEC3"}]})";
    const fs::path f = dir / "float.glb";
    test::write(f, glb(fjson, fbin));
    GltfModel fm;
    ASSERT_TRUE(load_gltf_model(f, fm).ok());
    const Status bad = read_gltf_colors_into(fm, 0, 3, f.string(), "COLOR_0", got);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.message(), f.string() + ": COLOR_0: non-finite value at element 1");
}

TEST(GlbContainer, StridedReadsInterleaveAttributes) {
    // Two VEC3 attributes (floats; normalised shorts) interleaved into one array of 7 floats per element.
    const fs::path dir = test::fresh_dir("glb", "strided");
    std::string bin = floats({1, 2, 3, 4, 5, 6});
    const std::int16_t shorts[6] = {32767, -32767, 0, 16384, -32768, 1};
    bin.append(reinterpret_cast<const char*>(shorts), sizeof shorts);
    const std::string json =
        R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":36}],"bufferViews":[{"buffer":0,"byteLength":24},)"
        R"({"buffer":0,"byteOffset":24,"byteLength":12}],"accessors":[)"
        R"({"bufferView":0,"componentType":5126,"count":2,"type":"VEC3"},)"
        R"({"bufferView":1,"componentType":5122,"normalized":true,"count":2,"type":"VEC3"}]})";
    const fs::path p = dir / "strided.glb";
    test::write(p, glb(json, bin));
    GltfModel m;
    ASSERT_TRUE(load_gltf_model(p, m).ok());
    std::vector<float> out(14, -9.0f);
    ASSERT_TRUE(read_gltf_accessor_strided(m, 0, 3, p.string(), "A", out.data(), 7, 2).ok());
    ASSERT_TRUE(read_gltf_accessor_strided(m, 1, 3, p.string(), "B", out.data() + 3, 7, 2).ok());
    auto b = read_gltf_accessor(m, 1, 3, p.string(), "B");
    ASSERT_TRUE(b.ok());
    const std::vector<float> want = {1, 2, 3, float((*b)[0]), float((*b)[1]), float((*b)[2]), -9,
                                     4, 5, 6, float((*b)[3]), float((*b)[4]), float((*b)[5]), -9};
    EXPECT_EQ(out, want);
    EXPECT_EQ(out[4], -1.0f);   // -32767 / 32767
    EXPECT_EQ(out[11], -1.0f);  // -32768 clamps to -1

    const Status count = read_gltf_accessor_strided(m, 0, 3, p.string(), "A", out.data(), 7, 3);
    EXPECT_EQ(count.message(), p.string() + ": A: 2 elements, expected 3");
    const Status narrow = read_gltf_accessor_strided(m, 0, 3, p.string(), "A", out.data(), 2, 2);
    EXPECT_FALSE(narrow.ok());
    const Status matrix = read_gltf_accessor_strided(m, 0, 16, p.string(), "A", out.data(), 16, 2);
    EXPECT_FALSE(matrix.ok());
}

TEST(GlbContainer, AGlbShortenedAfterLoadingIsRefusedByItsAccessors) {
    const fs::path dir = test::fresh_dir("glb", "shortened");
    const fs::path p = dir / "shortened.glb";
    const std::size_t n = 64 * 1024;  // floats: 256 KiB of BIN chunk, far past the page that stays
    std::string bin(n * 4, '\0');
    for (std::size_t i = 0; i < n; ++i) {
        const float x = 1.0f + float(i % 7);
        std::memcpy(bin.data() + i * 4, &x, 4);
    }
    const std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" +
                             std::to_string(bin.size()) + R"(}],"bufferViews":[{"buffer":0,"byteLength":)" +
                             std::to_string(bin.size()) +
                             R"(}],"accessors":[{"bufferView":0,"componentType":5126,"count":)" +
                             std::to_string(n) + R"(,"type":"SCALAR"}]})";
    test::write(p, glb(json, bin));
    GltfModel m;
    ASSERT_TRUE(load_gltf_model(p, m).ok());
    fs::resize_file(p, 4096);  // another program truncates the file while it is open
    auto v = read_gltf_accessor(m, 0, 1, p.string(), "values");
    ASSERT_FALSE(v.ok()) << "zeros were read as the file's values";
    EXPECT_EQ(v.message(), p.string() + ": " + kChangedWhileRead);
}

}  // namespace
}  // namespace sffd::assets
