// ply::MappedElement (a binary element in place) and the surface PLY reader's in-place vertex path: the
// same geometry as ply::Reader's columns, bit for bit, for every property the reader knows and every
// scalar type; the files the mapping must refuse (so the caller falls back) are refused.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_mapped.h"
#include "tests/assets/test_util.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

// The file's header as ply::Reader reads it, then the mapping.
Result<ply::MappedElement> map(const fs::path& p, std::string_view element) {
    const std::string text = test::slurp(p);
    std::size_t header_bytes = 0;
    auto h = ply::parse_header(text, p.string(), header_bytes);
    if (!h) return h.error();
    return ply::MappedElement::map(p, *h, element);
}

template <class T>
void put(std::string& s, T v) {
    s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

TEST(PlyMapped, FindsTheElementAfterListFreeOnes) {
    const fs::path dir = test::fresh_dir("ply_mapped", "offset");
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement extra 3\nproperty short a\nproperty double b\n"
        "element vertex 2\nproperty float x\nproperty uchar c\nend_header\n";
    for (int i = 0; i < 3; ++i) put(s, std::int16_t(i)), put(s, double(i));
    put(s, 1.5f), put(s, std::uint8_t(200)), put(s, -2.5f), put(s, std::uint8_t(7));
    test::write(dir / "a.ply", s);
    auto m = map(dir / "a.ply", "vertex");
    ASSERT_TRUE(m) << m.message();
    EXPECT_EQ(m->count(), 2u);
    EXPECT_EQ(m->row_size(), 5u);
    EXPECT_EQ(m->property_offset(1), 4u);
    float x;
    std::memcpy(&x, m->rows() + m->row_size(), 4);
    EXPECT_EQ(x, -2.5f);
    EXPECT_EQ(m->rows()[m->row_size() + 4], 7);
}

TEST(PlyMapped, RefusesWhatItCannotMap) {
    const fs::path dir = test::fresh_dir("ply_mapped", "refused");
    const std::string vertex = "element vertex 1\nproperty float x\nend_header\n";
    std::string one;
    put(one, 1.0f);
    test::write(dir / "ascii.ply", "ply\nformat ascii 1.0\n" + vertex + "1\n");
    test::write(dir / "big.ply", "ply\nformat binary_big_endian 1.0\n" + vertex + one);
    test::write(dir / "list_first.ply",
                "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int i\n" + vertex +
                    std::string(1, '\0') + one);
    test::write(dir / "short.ply", "ply\nformat binary_little_endian 1.0\n" + vertex + "ab");
    for (const char* name : {"ascii.ply", "big.ply", "list_first.ply", "short.ply", "absent.ply"})
        EXPECT_FALSE(map(dir / name, "vertex")) << name;
    // The header says binary, the file has none (changed since it was read): refused, not read past its end.
    test::write(dir / "changed.ply", "ply\nformat ascii 1.0\n" + vertex + "1\n");
    std::size_t header_bytes = 0;
    auto stale =
        ply::parse_header("ply\nformat binary_little_endian 1.0\n" + vertex, "changed.ply", header_bytes);
    ASSERT_TRUE(stale) << stale.message();
    EXPECT_FALSE(ply::MappedElement::map(dir / "changed.ply", *stale, "vertex"));
    test::write(dir / "fine.ply", "ply\nformat binary_little_endian 1.0\n" + vertex + one);
    EXPECT_TRUE(map(dir / "fine.ply", "vertex"));
    EXPECT_FALSE(map(dir / "fine.ply", "face"));
}

// A splat cloud with every attribute the PLY layout stores, 20,000 splats (several parallel ranges).
SplatCloud full_cloud(std::size_t n) {
    SplatCloud c;
    for (std::size_t i = 0; i < n; ++i) {
        const float t = float(i) * 0.001f;
        c.positions.emplace_back(std::sin(t), std::cos(t) * 3.0f, t);
        c.normals.push_back(glm::normalize(glm::vec3(1.0f, t, -2.0f)));
        c.axis_u.emplace_back(0.01f, t * 1e-3f, 0.0f);
        c.axis_v.emplace_back(0.0f, 0.01f, -t * 1e-3f);
        c.colors.push_back(0x80000000u | std::uint32_t(i * 2654435761u & 0xffffffu));
        c.uvs.emplace_back(t, 1.0f - t);
        c.uv_axes.emplace_back(t, 0.5f, -0.25f, 2.0f * t);
    }
    return c;
}

void expect_same(const assets::Geometry& a, const assets::Geometry& b) {
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.colors, b.colors);
    EXPECT_EQ(a.uvs, b.uvs);
    EXPECT_EQ(a.axis_u, b.axis_u);
    EXPECT_EQ(a.axis_v, b.axis_v);
    EXPECT_EQ(a.uv_axes, b.uv_axes);
    EXPECT_EQ(a.origin, b.origin);
}

TEST(PlyMapped, SurfaceVerticesMatchTheColumnPath) {
    const fs::path dir = test::fresh_dir("ply_mapped", "surface");
    SplatCloud c = full_cloud(20000);
    for (bool far : {false, true}) {  // far: double positions and an origin comment
        c.origin = far ? glm::dvec3(5e5, -3e5, 12.0) : glm::dvec3(0.0);
        ASSERT_TRUE(assets::save_splat_ply(c, dir / "bin.ply"));
        ASSERT_TRUE(assets::save_splat_ply(c, dir / "text.ply", ply::Format::ascii));
        auto a = assets::read_ply_geometry(dir / "bin.ply");
        auto b = assets::read_ply_geometry(dir / "text.ply");
        ASSERT_TRUE(a) << a.message();
        ASSERT_TRUE(b) << b.message();
        ASSERT_EQ(a->positions.size(), c.size());
        expect_same(*a, *b);
    }
}

// Integer and 16-bit colour channels, a mesh's face element after the vertices, a non-finite colour.
TEST(PlyMapped, SurfaceTypesFacesAndBadColour) {
    const fs::path dir = test::fresh_dir("ply_mapped", "types");
    auto file = [&](float red_of_last) {
        std::string s =
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty int x\nproperty short y\n"
            "property double z\nproperty float red\nproperty ushort green\nproperty uchar blue\n"
            "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
        for (int i = 0; i < 3; ++i) {
            put(s, std::int32_t(-7 + i)), put(s, std::int16_t(300 * i)), put(s, 0.125 * i);
            put(s, i == 2 ? red_of_last : 0.5f), put(s, std::uint16_t(65535)), put(s, std::uint8_t(51));
        }
        put(s, std::uint8_t(3)), put(s, 0u), put(s, 1u), put(s, 2u);
        return s;
    };
    test::write(dir / "mesh.ply", file(0.25f));
    auto g = assets::read_ply_geometry(dir / "mesh.ply");
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->positions.size(), 3u);
    EXPECT_EQ(g->positions[2], glm::dvec3(-5, 600, 0.25));
    ASSERT_EQ(g->colors.size(), 3u);
    EXPECT_EQ(g->triangles, (std::vector<std::uint32_t>{0, 1, 2}));
    test::write(dir / "nan.ply", file(std::numeric_limits<float>::quiet_NaN()));
    auto bad = assets::read_ply_geometry(dir / "nan.ply");
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.message().find((dir / "nan.ply").string() + ": vertex 2 has a non-finite colour"),
              std::string::npos)
        << bad.message();
}

}  // namespace
