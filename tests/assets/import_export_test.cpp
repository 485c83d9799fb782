// Importers (PLY, OBJ, OFF, glTF), exporters (PLY, GLB, glTF) and their round trips, hostile files, and
// the Debian assimp-testmodels glTF samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/import.h"
#include "runtime/core/log.h"
#include "tests/assets/test_util.h"
#include "tests/assets/textured_box.h"

#include <stb/stb_image_write.h>

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::assets;

namespace {

fs::path temp_dir() {
    fs::path d = fs::temp_directory_path() / ("sffd_import_test_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

fs::path write_text(const std::string& name, const std::string& text) {
    const fs::path p = temp_dir() / name;
    std::ofstream f(p, std::ios::binary);
    f << text;
    return p;
}

// A small cloud with every attribute; colours cover all 256 byte values in every channel.
SplatCloud sample_cloud(std::size_t n, glm::dvec3 origin = glm::dvec3(0.0)) {
    SplatCloud c = make_sphere_cloud(n);
    c.origin = origin;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t b = static_cast<std::uint32_t>(i % 256);
        c.colors[i] =
            b | (((b * 7) & 255u) << 8) | (((b * 13 + 5) & 255u) << 16) | (((255 - b) & 255u) << 24);
    }
    // A smaller texture keeps the GLB small; odd size checks the PNG row handling.
    Image tex = make_sphere_texture(37, 19);
    c.texture.width = tex.width;
    c.texture.height = tex.height;
    c.texture.rgba8 = tex.rgba8;
    c.texture.rgba8[3] = 17;  // one translucent texel
    return c;
}

// A material unlike the defaults, stored beside the cloud (its own component).
const SplatMaterial sample_material{glm::vec4(0.25f, 0.5f, 0.75f, 1.0f), 0.7f, 12.5f};

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_same_cloud(const SplatCloud& a, const SplatCloud& b, bool texture) {
    EXPECT_EQ(a.origin, b.origin);
    EXPECT_TRUE(same_bytes(a.positions, b.positions));
    EXPECT_TRUE(same_bytes(a.normals, b.normals));
    EXPECT_TRUE(same_bytes(a.axis_u, b.axis_u));
    EXPECT_TRUE(same_bytes(a.axis_v, b.axis_v));
    EXPECT_TRUE(same_bytes(a.colors, b.colors));
    EXPECT_TRUE(same_bytes(a.uvs, b.uvs));
    EXPECT_TRUE(same_bytes(a.uv_axes, b.uv_axes));
    if (texture) {
        EXPECT_EQ(a.texture.width, b.texture.width);
        EXPECT_EQ(a.texture.height, b.texture.height);
        EXPECT_TRUE(same_bytes(a.texture.rgba8, b.texture.rgba8));
    }
}

void expect_error(const Status& s, const fs::path& file, const std::string& needle) {
    ASSERT_FALSE(s.ok()) << file << " was accepted";
    EXPECT_NE(s.message().find(file.string()), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
}

template <class T>
Status status_of(const Result<T>& r) {
    return r.ok() ? Status{} : Status{r.error()};
}

}  // namespace

TEST(RoundTrip, GlbAndGltfStoreEveryArrayExactly) {
    const SplatCloud c = sample_cloud(1000);
    for (const char* name : {"rt.glb", "rt.gltf"}) {
        const fs::path p = temp_dir() / name;
        ASSERT_TRUE(save_splat_cloud(c, p, "cloud", sample_material).ok());
        SplatMaterial material;
        auto back = import_splat_cloud(p, {}, &material);
        ASSERT_TRUE(back.ok()) << back.message();
        expect_same_cloud(c, *back, true);
        EXPECT_EQ(material, sample_material);
    }
}

TEST(RoundTrip, GlbKeepsAFarOriginInDoublePrecision) {
    const SplatCloud c = sample_cloud(300, glm::dvec3(4.0e6 + 0.123456789, -2.5e6, 1234.5));
    const fs::path p = temp_dir() / "far.glb";
    ASSERT_TRUE(save_splat_glb(c, p, "cloud", sample_material).ok());
    SplatMaterial material;
    auto back = import_splat_cloud(p, {}, &material);
    ASSERT_TRUE(back.ok()) << back.message();
    expect_same_cloud(c, *back, true);
    EXPECT_EQ(material, sample_material);
}

TEST(RoundTrip, PlyBinaryAndAsciiStoreEveryArrayExactly) {
    SplatCloud c = sample_cloud(1000);
    for (auto fmt : {ply::Format::binary_little_endian, ply::Format::ascii}) {
        const fs::path p = temp_dir() / "rt.ply";
        ASSERT_TRUE(save_splat_ply(c, p, fmt).ok());
        auto back = import_splat_cloud(p);
        ASSERT_TRUE(back.ok()) << back.message();
        expect_same_cloud(c, *back, false);  // PLY stores no texture pixels
    }
}

TEST(RoundTrip, PlyFarCloudKeepsOriginAndPositionsToFloatPrecision) {
    const SplatCloud c = sample_cloud(500, glm::dvec3(6.0e5, 4.0e6, -12.25));
    const fs::path p = temp_dir() / "far.ply";
    ASSERT_TRUE(save_splat_ply(c, p).ok());
    auto back = import_splat_cloud(p);
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(back->origin, c.origin);
    ASSERT_EQ(back->size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        for (int a = 0; a < 3; ++a)
            EXPECT_LE(std::abs(back->positions[i][a] - c.positions[i][a]),
                      2.0f * std::numeric_limits<float>::epsilon())
                << i;
    EXPECT_TRUE(same_bytes(c.axis_u, back->axis_u));
    EXPECT_TRUE(same_bytes(c.colors, back->colors));
}

TEST(Import, FarAwayScanIsRecentredOnItsBoundingBox) {
    Geometry g;
    g.source = "far";
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0, 10);
    for (int i = 0; i < 500; ++i)
        g.positions.emplace_back(5.0e6 + u(rng), 3.0e6 + u(rng), 100.0 + 0.01 * u(rng));
    auto c = make_splat_cloud(g, {});
    ASSERT_TRUE(c.ok()) << c.message();
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : g.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    EXPECT_EQ(c->origin, 0.5 * (lo + hi));
    for (std::size_t i = 0; i < g.positions.size(); ++i)
        EXPECT_NEAR(c->origin.x + static_cast<double>(c->positions[i].x), g.positions[i].x,
                    1e-6);  // float offsets stay precise
}

TEST(Import, ObjWithQuadsNegativeIndicesMaterialsAndSeams) {
    write_text("cube.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
    const fs::path p = write_text(
        "cube.obj",
        "mtllib cube.mtl\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 9 9 9\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "usemtl red\nf 1/1 4/4 3/3 2/2\nf 5/1 6/2 7/3 8/4\n"
        "usemtl blue\nf -9/1 -8/2 -4/3 -5/4\nf 2/1 3/2 7/3 6/4\nf 3/1 4/2 8/3 7/4\nf 4/1 1/2 5/3 8/4\n");
    auto g = read_geometry(p);
    ASSERT_TRUE(g.ok()) << g.message();
    EXPECT_EQ(g->triangle_count(), 12u);
    EXPECT_EQ(g->materials.size(), 2u);
    EXPECT_EQ(g->uvs.size(), g->positions.size());
    EXPECT_EQ(g->uvs[0], glm::vec2(0.0f, 1.0f));  // OBJ v flipped to the glTF convention
    // One splat per used vertex (the stray v 9 9 9 is dropped), colour from the material.
    ImportOptions vertices;
    vertices.min_mesh_splats = 0;
    auto c = make_splat_cloud(*g, vertices);
    ASSERT_TRUE(c.ok()) << c.message();
    for (const auto& pos : c->positions) EXPECT_LE(pos.x, 1.0f);
    // Exactly N surface samples; red faces (z = 0 and z = 1) and blue faces only.
    ImportOptions opt;
    opt.splats = 600;
    auto s = make_splat_cloud(*g, opt);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(s->size(), 600u);
    std::size_t red = 0, blue = 0;
    for (std::size_t i = 0; i < s->size(); ++i) {
        const glm::vec3 q = glm::vec3(s->origin) + s->positions[i];
        const std::uint32_t col = s->colors[i];
        const bool on_z_face = std::abs(q.z) < 1e-5f || std::abs(q.z - 1.0f) < 1e-5f;
        if (col == 0xff0000ffu) {
            ++red;
            EXPECT_TRUE(on_z_face) << q.x << " " << q.y << " " << q.z;
        } else {
            EXPECT_EQ(col, 0xffff0000u);
            ++blue;
        }
        // Face normals point out of the unit cube.
        const glm::vec3 out = glm::normalize(q - glm::vec3(0.5f));
        EXPECT_GT(glm::dot(out, s->normals[i]), 0.0f);
    }
    EXPECT_NEAR(static_cast<double>(red) / 600.0, 2.0 / 6.0, 0.08);  // area-weighted
}

TEST(Import, OffWithColours) {
    const fs::path p = write_text("tet.off",
                                  "COFF\n# a tetrahedron\n4 4 6\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 "
                                  "0 0 255 255\n0 0 1 255 255 255 255\n"
                                  "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    auto g = read_geometry(p);
    ASSERT_TRUE(g.ok()) << g.message();
    EXPECT_EQ(g->positions.size(), 4u);
    EXPECT_EQ(g->triangle_count(), 4u);
    ASSERT_EQ(g->colors.size(), 4u);
    EXPECT_EQ(g->colors[1], 0xff00ff00u);
}

TEST(Import, PlyMeshWithFacesAndColours) {
    const fs::path p = write_text(
        "quad.ply",
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 255 0 0\n1 0 0 255 0 0\n1 1 0 255 0 0\n0 1 0 255 0 0\n5 5 5 0 0 0\n4 0 1 2 3\n");
    auto g = read_geometry(p);
    ASSERT_TRUE(g.ok()) << g.message();
    EXPECT_EQ(g->triangle_count(), 2u);
    ImportOptions vertices;
    vertices.min_mesh_splats = 0;
    auto c = make_splat_cloud(*g, vertices);
    ASSERT_TRUE(c.ok()) << c.message();
    EXPECT_EQ(c->size(), 4u);  // the unused fifth vertex is not a splat
    // By default a coarse mesh is sampled instead (too few vertices to cover the surface).
    auto dense = make_splat_cloud(*g, {});
    ASSERT_TRUE(dense.ok()) << dense.message();
    EXPECT_EQ(dense->size(), 20000u);
    for (const auto& n : c->normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
}

TEST(Import, ExactSplatCountsForPointsAndRefusalToInvent) {
    Geometry g;
    g.source = "points";
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 2000; ++i) g.positions.emplace_back(u(rng), u(rng), 0.0);
    ImportOptions opt;
    opt.splats = 777;
    auto c = make_splat_cloud(g, opt);
    ASSERT_TRUE(c.ok()) << c.message();
    EXPECT_EQ(c->size(), 777u);
    opt.splats = 2001;
    auto bad = make_splat_cloud(g, opt);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("without faces"), std::string::npos);
}

struct Hostile {
    const char* file;
    std::string text;
    const char* expected;
};

class HostileImport : public ::testing::TestWithParam<Hostile> {};

TEST_P(HostileImport, IsRefusedWithTheFileName) {
    const fs::path p = write_text(GetParam().file, GetParam().text);
    expect_error(status_of(import_splat_cloud(p)), p, GetParam().expected);
}

INSTANTIATE_TEST_SUITE_P(
    Files, HostileImport,
    ::testing::Values(
        Hostile{"nan.ply",
                "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float "
                "z\nend_header\n0 0 0\nnan 1 2\n",
                "non-finite coordinate"},
        Hostile{"inf_normal.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float "
                "z\nproperty float nx\nproperty float ny\n"
                "property float nz\nend_header\n0 0 0 inf 0 0\n",
                "non-finite normal"},
        Hostile{"noxyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n",
                "no x, y, z"},
        Hostile{"badface.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
                "z\nelement face 1\n"
                "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
                "refers to vertex 7"},
        Hostile{"negface.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
                "z\nelement face 1\n"
                "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
                "refers to vertex -1"},
        Hostile{"badindex.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n", "missing vertex 3"},
        Hostile{"nan.obj", "v 0 0 nan\n", "non-finite"},
        Hostile{"garbage.obj", "v 0 zero 0\n", "malformed number"},
        Hostile{"huge.off", "OFF\n999999999 999999999 0\n0 0 0\n", "exceed the file"},
        Hostile{"badmagic.off", "PLY\n1 0 0\n0 0 0\n", "bad magic"},
        Hostile{"badidx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "refers to vertex 3"},
        Hostile{"empty.gltf", "", "invalid glTF"},
        Hostile{"notjson.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [", "invalid glTF"},
        Hostile{"oob.gltf",
                R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
                   "meshes":[{"primitives":[{"mode":0,"attributes":{"POSITION":0}}]}],
                   "accessors":[{"bufferView":0,"componentType":5126,"count":1000,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}],
                   "bufferViews":[{"buffer":0,"byteLength":12}],
                   "buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}]})",
                "exceeds"},
        Hostile{
            "cycle.gltf",
            R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"children":[1]},{"children":[0]}]})",
            "cycle"},
        Hostile{
            "nanmatrix.gltf",
            R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"scale":[1e308,1e308,1e308],"children":[1]},{"mesh":0,"scale":[1e308,1,1]}],
                   "meshes":[{"primitives":[{"mode":0,"attributes":{"POSITION":0}}]}],
                   "accessors":[{"bufferView":0,"componentType":5126,"count":1,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}],
                   "bufferViews":[{"buffer":0,"byteLength":12}],
                   "buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AACAPwAAgD8AAIA/"}]})",
            "not finite"},
        Hostile{"hugeimage.gltf",
                R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
                   "meshes":[{"primitives":[{"mode":0,"attributes":{"POSITION":0},"material":0}]}],
                   "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
                   "textures":[{"source":0}],
                   "images":[{"uri":"data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAPoAAAD6ACAAAAABkFYACAAAAAElEQVQ1rwYe"}],
                   "accessors":[{"bufferView":0,"componentType":5126,"count":1,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}],
                   "bufferViews":[{"buffer":0,"byteLength":12}],
                   "buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AACAPwAAgD8AAIA/"}]})",
                "larger than 8192x8192"},
        Hostile{"unknown.xyz", "1 2 3\n", "unknown file type"}),
    [](const auto& param_info) {
        std::string n = param_info.param.file;
        for (char& ch : n)
            if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
        return n;
    });

TEST(Import, TruncatedGlbIsRefused) {
    const SplatCloud c = sample_cloud(200);
    const fs::path good = temp_dir() / "whole.glb";
    ASSERT_TRUE(save_splat_glb(c, good).ok());
    std::ifstream f(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(f)), {});
    for (std::size_t cut : {std::size_t{5}, std::size_t{20}, bytes.size() / 2, bytes.size() - 1}) {
        const fs::path p = write_text("cut" + std::to_string(cut) + ".glb", bytes.substr(0, cut));
        auto r = import_splat_cloud(p);
        ASSERT_FALSE(r.ok()) << "accepted a GLB cut at " << cut;
        EXPECT_NE(r.message().find(p.string()), std::string::npos) << r.message();
    }
}

TEST(Import, MissingFileNamesIt) {
    auto r = import_splat_cloud("/nonexistent/scan.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message(), "/nonexistent/scan.ply: no such file");
}

// Debian's assimp-testmodels (tools/bootstrap.sh installs it): a real glTF 2.0 sample with a base-colour
// texture, and two hostile samples from the assimp test suite.
TEST(AssimpTestModels, TexturedBoxImportsWithTextureColours) {
    const fs::path dir = "/usr/share/assimp/models/glTF2";
    const fs::path glb = dir / "BoxTextured-glTF-Binary/BoxTextured.glb";
    if (!fs::exists(glb))
        GTEST_SKIP() << "assimp-testmodels not installed (apt-get install assimp-testmodels)";
    for (const fs::path& p : {glb, dir / "BoxTextured-glTF/BoxTextured.gltf"}) {
        auto g = read_geometry(p);
        ASSERT_TRUE(g.ok()) << g.message();
        EXPECT_EQ(g->triangle_count(), 12u);
        ASSERT_EQ(g->textures.size(), 1u);
        ImportOptions opt;
        opt.splats = 2000;
        auto c = make_splat_cloud(*g, opt);
        ASSERT_TRUE(c.ok()) << c.message();
        ASSERT_EQ(c->size(), 2000u);
        // The texture (a logo on a light background) gives many distinct colours, not one flat colour.
        std::vector<std::uint32_t> distinct(c->colors.begin(), c->colors.end());
        std::sort(distinct.begin(), distinct.end());
        distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
        EXPECT_GT(distinct.size(), 50u);
        // One untinted texture: kept as the cloud's material, with a uv frame per splat.
        EXPECT_EQ(c->texture.width, g->textures[0].width);
        EXPECT_EQ(c->uv_axes.size(), 2000u);
    }
    const fs::path bad = dir / "IndexOutOfRange/IndexOutOfRange.gltf";
    if (fs::exists(bad)) {
        auto r = import_splat_cloud(bad);
        ASSERT_FALSE(r.ok());
        EXPECT_NE(r.message().find(bad.string()), std::string::npos) << r.message();
    }
}

// ---------------------------------------------------------------------------------------------------
// Files from other tools: Windows paths in OBJ/MTL, PLY headers with writers' own lines,
// glTF 1.0 named as such. Hand-made files first, then the real assimp samples when installed.

namespace {

// A w x h PNG of one colour (RGBA8, R in the low byte as Geometry stores colours).
void write_png(const fs::path& p, int w, int h, std::uint32_t rgba) {
    fs::create_directories(p.parent_path());
    std::vector<std::uint32_t> px(static_cast<std::size_t>(w * h), rgba);
    ASSERT_NE(stbi_write_png(p.string().c_str(), w, h, 4, px.data(), w * 4), 0) << p;
}

}  // namespace

TEST(ForeignFiles, ObjWithWindowsBackslashPathsKeepsItsTexture) {
    const fs::path dir = temp_dir() / "obj_backslash";
    fs::remove_all(dir);
    write_png(dir / "maps" / "red.png", 2, 2, 0xff0000ffu);
    fs::create_directories(dir / "lib");
    std::ofstream(dir / "lib" / "m.mtl") << "newmtl red\r\nKd 1 1 1\r\nmap_Kd ..\\maps\\red.png\r\n";
    // The MTL is in lib/, so "..\maps" stays inside the OBJ's folder only from the OBJ; the MTL's own
    // textures resolve inside lib/: move the texture next to the MTL for the accepted case.
    write_png(dir / "lib" / "tex" / "red.png", 2, 2, 0xff0000ffu);
    std::ofstream(dir / "lib" / "ok.mtl") << "newmtl red\r\nKd 1 1 1\r\nmap_Kd .\\tex\\red.png\r\n";
    const std::string tri = "usemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    std::ofstream(dir / "ok.obj") << "mtllib .\\lib\\ok.mtl\n" << tri;
    auto g = read_obj_geometry(dir / "ok.obj");
    ASSERT_TRUE(g.ok()) << g.message();
    ASSERT_EQ(g->textures.size(), 1u);
    ASSERT_EQ(g->materials.size(), 1u);
    EXPECT_EQ(g->materials[0].texture, 0);
    ASSERT_EQ(g->textures[0].rgba8.size(), 16u);
    EXPECT_EQ(g->textures[0].rgba8[0], 255);  // red
    EXPECT_EQ(g->textures[0].rgba8[1], 0);

    // A backslash ".." out of the MTL's folder is still an escape, refused like "../".
    std::ofstream(dir / "escape.obj") << "mtllib lib\\m.mtl\n" << tri;
    auto e = read_obj_geometry(dir / "escape.obj");
    ASSERT_FALSE(e.ok());
    EXPECT_NE(e.message().find((dir / "lib" / "m.mtl").string() +
                               ": resource '../maps/red.png' is outside the file's folder"),
              std::string::npos)
        << e.message();
}

TEST(ForeignFiles, PlyHeaderWithUnknownLinesWarnsAndLoads) {
    const fs::path p = write_text(
        "created.ply",
        "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: \n"
        "obj_info num_cols 1\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n");
    log::ScopedLogCapture capture;
    auto g = read_ply_geometry(p);
    ASSERT_TRUE(g.ok()) << g.message();
    EXPECT_EQ(g->positions.size(), 3u);
    EXPECT_EQ(g->positions[1], glm::dvec3(1, 0, 0));
    EXPECT_TRUE(capture.contains(p.string() + ": header line 3: unknown keyword 'Created', line ignored"));
    EXPECT_FALSE(capture.contains("obj_info"));  // a known keyword: kept as a comment, no warning
}

TEST(ForeignFiles, PlyHeaderOfJunkLinesWarnsAFewTimesOnly) {
    std::string text = "ply\nformat ascii 1.0\n";
    for (int i = 0; i < 100; ++i) text += "junk" + std::to_string(i) + "\n";
    text += "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n";
    const fs::path p = write_text("junk.ply", text);
    log::ScopedLogCapture capture;
    auto g = read_ply_geometry(p);
    ASSERT_TRUE(g.ok()) << g.message();
    std::size_t warnings = 0;
    for (const auto& e : capture.entries())
        if (e.message.find(p.string()) != std::string::npos) ++warnings;
    EXPECT_EQ(warnings, 6u);  // five lines named, then one "further ... ignored"
    EXPECT_TRUE(capture.contains("unknown keyword 'junk4'"));
    EXPECT_FALSE(capture.contains("unknown keyword 'junk5'"));
}

TEST(ForeignFiles, Gltf1IsNamedAsUnsupported) {
    const fs::path text = write_text(
        "v1.gltf", R"({"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}}, "scene": "s"})");
    auto r = read_gltf_geometry(text);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message(),
              text.string() + ": glTF 1.0 is not supported (asset.version \"1.0\"); convert it to glTF 2.0");

    // Binary glTF 1.0 (KHR_binary_glTF): container version 1, then length, JSON length, format 0.
    const std::string json = R"({"asset":{"version":"1.0.1"}} )";
    std::string glb = "glTF";
    auto u32 = [&](std::uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
    u32(1);
    u32(static_cast<std::uint32_t>(20 + json.size()));
    u32(static_cast<std::uint32_t>(json.size()));
    u32(0);
    glb += json;
    const fs::path bin = write_text("v1.glb", glb);
    auto b = read_gltf_geometry(bin);
    ASSERT_FALSE(b.ok());
    EXPECT_EQ(b.message(),
              bin.string() + ": glTF 1.0 is not supported (asset.version \"1.0.1\"); convert it to glTF 2.0");

    // glTF 2.0 with a broken body keeps tinygltf's own message.
    const fs::path v2 = write_text(
        "v2.gltf",
        R"({"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 7}}]}]})");
    auto r2 = read_gltf_geometry(v2);
    ASSERT_FALSE(r2.ok());
    EXPECT_EQ(r2.message().find("glTF 1.0"), std::string::npos) << r2.message();
}

TEST(AssimpTestModels, ForeignSamplesImport) {
    const fs::path dir = "/usr/share/assimp/models";
    if (!fs::exists(dir / "OBJ/spider.obj"))
        GTEST_SKIP() << "assimp-testmodels not installed (apt-get install assimp-testmodels)";
    // spider.mtl names its five textures ".\SpiderTex.jpg" etc.; all ship next to it.
    auto spider = read_obj_geometry(dir / "OBJ/spider.obj");
    ASSERT_TRUE(spider.ok()) << spider.message();
    ASSERT_EQ(spider->textures.size(), 5u);
    for (const Image& t : spider->textures) EXPECT_GT(t.width, 0);

    log::ScopedLogCapture capture;
    const fs::path wuson = dir / "PLY/Wuson.ply";
    auto w = read_ply_geometry(wuson);
    ASSERT_TRUE(w.ok()) << w.message();
    EXPECT_EQ(w->positions.size(), 11184u);
    EXPECT_TRUE(
        capture.contains(wuson.string() + ": header line 3: unknown keyword 'Created', line ignored"));

    for (const char* f :
         {"glTF/BoxTextured-glTF/BoxTextured.gltf", "glTF/BoxTextured-glTF-Binary/BoxTextured.glb"}) {
        auto r = read_gltf_geometry(dir / f);
        ASSERT_FALSE(r.ok()) << f;
        EXPECT_NE(r.message().find((dir / f).string() + ": glTF 1.0 is not supported (asset.version \"1.0"),
                  std::string::npos)
            << r.message();
        EXPECT_NE(r.message().find("convert it to glTF 2.0"), std::string::npos) << r.message();
    }
}

// ---------------------------------------------------------------------------------------------------
// Textured meshes keep their texture: mesh sampling gives each splat the uv of its point and
// the uv derivatives along its two axes from its triangle's affine 3D -> uv map; our PLY and glTF files
// store that frame and read it back; re-estimated axes get the frame re-expressed along them.

namespace {

// Every splat's uv and uv frame against the box's analytic map (the face found by the splat's normal).
void expect_box_uv_frame(const SplatCloud& c, const char* what) {
    const auto faces = sffd::test::textured_box_faces();
    const std::size_t n = c.size();
    ASSERT_EQ(c.uvs.size(), n) << what;
    ASSERT_EQ(c.uv_axes.size(), n) << what;
    ASSERT_EQ(c.axis_u.size(), n) << what;
    std::size_t bad = 0;
    int faces_seen = 0;
    bool seen[6] = {false, false, false, false, false, false};
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 x = c.origin + glm::dvec3(c.positions[i]);
        const sffd::test::BoxFace* f = sffd::test::box_face_of(faces, glm::dvec3(c.normals[i]));
        ASSERT_NE(f, nullptr) << what << ": splat " << i << " has normal off every face";
        seen[f - faces.data()] = true;
        const glm::dvec2 uv = f->uv(x);
        const glm::dvec2 du = f->duv(glm::dvec3(c.axis_u[i])), dv = f->duv(glm::dvec3(c.axis_v[i]));
        const glm::dvec4 want(du.x, du.y, dv.x, dv.y), got(c.uv_axes[i]);
        const bool ok =
            std::abs(uv.x - double(c.uvs[i].x)) < 2e-6 && std::abs(uv.y - double(c.uvs[i].y)) < 2e-6 &&
            glm::all(glm::lessThan(glm::abs(want - got), glm::dvec4(1e-7) + 1e-4 * glm::abs(want)));
        if (!ok && bad++ < 5)
            ADD_FAILURE() << what << ": splat " << i << " uv " << c.uvs[i].x << "," << c.uvs[i].y << " (want "
                          << uv.x << "," << uv.y << ") frame " << got.x << "," << got.y << "," << got.z << ","
                          << got.w << " (want " << want.x << "," << want.y << "," << want.z << "," << want.w
                          << ")";
        // The frame is not trivially zero: the axes have a radius and the map a scale.
        EXPECT_GT(glm::length(got), 1e-4) << what << ": splat " << i;
    }
    EXPECT_EQ(bad, 0u) << what;
    for (bool b : seen) faces_seen += b;
    EXPECT_EQ(faces_seen, 6) << what;
}

}  // namespace

TEST(TexturedMesh, SampledSplatsCarryTheTextureAndTheAnalyticUvFrame) {
    const fs::path obj = sffd::test::write_textured_box(sffd::test::fresh_dir("import", "textured_box"));
    auto g = read_geometry(obj);
    ASSERT_TRUE(g.ok()) << g.message();
    ImportOptions opt;
    opt.splats = 3000;
    auto c = make_splat_cloud(*g, opt);
    ASSERT_TRUE(c.ok()) << c.message();
    ASSERT_EQ(c->size(), 3000u);
    // The mesh's one texture becomes the cloud's material, pixel for pixel (not baked into colours only).
    EXPECT_EQ(c->texture.width, 256);
    EXPECT_EQ(c->texture.height, 256);
    EXPECT_TRUE(same_bytes(c->texture.rgba8, sffd::test::checker_texels(256, 16)));
    EXPECT_EQ(c->colors.size(), c->size());  // baked as well: the untextured fallback
    expect_box_uv_frame(*c, "sampled");

    // One splat per vertex (24): each vertex's frame is its face's (the mean over its two triangles).
    opt.splats = 0;
    opt.min_mesh_splats = 0;
    auto v = make_splat_cloud(*g, opt);
    ASSERT_TRUE(v.ok()) << v.message();
    ASSERT_EQ(v->size(), 24u);
    EXPECT_EQ(v->texture.width, 256);
    expect_box_uv_frame(*v, "per vertex");
}

TEST(TexturedMesh, TintedOrMultiTextureMeshesStayBakedIntoColours) {
    const fs::path dir = sffd::test::fresh_dir("import", "tinted_box");
    const fs::path obj = sffd::test::write_textured_box(dir);
    // A base colour the textured path cannot apply (it has no tint factor): colours are baked as before.
    std::ofstream(dir / "box.mtl") << "newmtl checker\nKd 1 0.5 1\nmap_Kd checker.png\n";
    auto g = read_geometry(obj);
    ASSERT_TRUE(g.ok()) << g.message();
    ImportOptions opt;
    opt.splats = 500;
    auto c = make_splat_cloud(*g, opt);
    ASSERT_TRUE(c.ok()) << c.message();
    EXPECT_TRUE(c->texture.rgba8.empty());
    EXPECT_TRUE(c->uv_axes.empty());
    ASSERT_EQ(c->colors.size(), 500u);
    for (std::uint32_t col : c->colors)
        EXPECT_LE((col >> 8) & 255u, 190u);  // green halved (sRGB of 0.5 * 0.8 at most)
}

TEST(TexturedMesh, UvFrameAndTextureRoundTripThroughPlyAndGltf) {
    const fs::path dir = sffd::test::fresh_dir("import", "textured_box_rt");
    auto g = read_geometry(sffd::test::write_textured_box(dir));
    ASSERT_TRUE(g.ok()) << g.message();
    ImportOptions opt;
    opt.splats = 2000;
    auto c = make_splat_cloud(*g, opt);
    ASSERT_TRUE(c.ok()) << c.message();
    for (const char* name : {"rt.ply", "rt_ascii.ply", "rt.glb", "rt.gltf"}) {
        const fs::path p = dir / name;
        const bool ascii = std::string(name) == "rt_ascii.ply";
        ASSERT_TRUE((ascii ? save_splat_ply(*c, p, ply::Format::ascii) : save_splat_cloud(*c, p)).ok())
            << name;
        auto back = import_splat_cloud(p);
        ASSERT_TRUE(back.ok()) << back.message();
        expect_same_cloud(*c, *back, false);
        // PLY keeps the texels in <stem>_texture.png beside it (TextureFile comment); glTF embeds them.
        EXPECT_EQ(back->texture.width, 256) << name;
        EXPECT_TRUE(same_bytes(back->texture.rgba8, c->texture.rgba8)) << name;
        if (p.extension() == ".ply") {
            EXPECT_TRUE(fs::exists(dir / (p.stem().string() + "_texture.png"))) << name;
            auto geom = read_geometry(p);
            ASSERT_TRUE(geom.ok()) << geom.message();
            EXPECT_NE(std::find(geom->attributes.begin(), geom->attributes.end(), "float du_ds"),
                      geom->attributes.end())
                << name;
        }
    }
    // Thinned (axes re-estimated) and re-estimated radii: the stored frame is re-expressed along the new
    // axes and still matches the analytic map.
    ImportOptions thin;
    thin.splats = 1200;
    auto t = import_splat_cloud(dir / "rt.ply", thin);
    ASSERT_TRUE(t.ok()) << t.message();
    ASSERT_EQ(t->size(), 1200u);
    expect_box_uv_frame(*t, "thinned from PLY");
    ImportOptions radii;
    radii.estimate_radii = true;
    auto r = import_splat_cloud(dir / "rt.glb", radii);
    ASSERT_TRUE(r.ok()) << r.message();
    expect_box_uv_frame(*r, "radii re-estimated from GLB");
}

TEST(TexturedMesh, NonFiniteUvFrameInAPlyIsRefusedNamingTheFile) {
    const fs::path p = sffd::test::fresh_dir("import", "bad_uv_frame") / "bad.ply";
    std::ofstream(p)
        << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
           "property float axis_ux\nproperty float axis_uy\nproperty float axis_uz\n"
           "property float axis_vx\nproperty float axis_vy\nproperty float axis_vz\n"
           "property float u\nproperty float v\n"
           "property float du_ds\nproperty float dv_ds\nproperty float du_dt\nproperty float "
           "dv_dt\nend_header\n"
           "0 0 0 1 0 0 0 1 0 0.5 0.5 nan 0 0 1\n";
    auto g = read_geometry(p);
    expect_error(status_of(g), p, "non-finite uv frame");
}
