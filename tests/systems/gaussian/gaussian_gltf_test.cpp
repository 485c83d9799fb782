// KHR_gaussian_splatting: round trips through our GLB writer, hand-built .gltf files with known values
// (node transform, COLOR_0 fallback), and refusals of bad files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_gauss_gltf_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

GaussianCloud random_cloud(int degree, std::size_t n) {
    std::mt19937 rng(unsigned(degree + 1));
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.1f + 0.05f * u(rng), 0.02f, 0.3f);
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng) + 2)));
        g.opacities.push_back(0.5f + 0.5f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

TEST(GaussianGltf, GlbRoundTripsEveryDegree) {
    for (int degree = 0; degree <= 3; ++degree) {
        GaussianCloud g = random_cloud(degree, 200);
        g.origin = glm::dvec3(10.0, -2.0, 0.5);  // written as the node translation
        const fs::path p = temp("rt.glb");
        ASSERT_TRUE(write_glb(p, g));
        auto back = read_gaussians(p);
        ASSERT_TRUE(back) << back.message();
        ASSERT_EQ(back->size(), g.size());
        EXPECT_EQ(back->sh_degree, degree);
        for (std::size_t i = 0; i < g.size(); ++i) {
            EXPECT_LT(glm::length(glm::dvec3(back->positions[i]) + back->origin -
                                  (glm::dvec3(g.positions[i]) + g.origin)),
                      2e-6);
            const glm::dmat3 a = covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
            const glm::dmat3 b = covariance(glm::dvec3(back->scales[i]), glm::dquat(back->rotations[i]));
            for (int c = 0; c < 3; ++c) EXPECT_LT(glm::length(a[c] - b[c]), 1e-6);
            EXPECT_EQ(back->opacities[i], g.opacities[i]);
        }
        EXPECT_EQ(back->sh, g.sh);
    }
}

// append_primitive (scene files hold several clouds) stores a cloud as given, in the buffer it is handed
// (here after 2 bytes that are not the cloud's); read as a plain GLB, the file's axes turn it as read_gltf
// turns every GLB, exactly.
TEST(GaussianGltf, AppendedPrimitiveStoresTheCloudAsGiven) {
    GaussianCloud g = random_cloud(3, 150);
    nlohmann::json doc = nlohmann::json::object();
    std::string bin = "xy";
    nlohmann::json prim;
    ASSERT_TRUE(append_primitive(doc, bin, g, prim, "test cloud"));
    EXPECT_EQ(bin.size() % 4, 0u);
    doc["asset"] = {{"version", "2.0"}};
    doc["scene"] = 0;
    doc["scenes"] = {{{"nodes", {0}}}};
    doc["nodes"] = {{{"mesh", 0}}};
    doc["meshes"] = {{{"primitives", {prim}}}};
    doc["buffers"] = {{{"byteLength", bin.size()}}};
    std::string text = doc.dump();
    while (text.size() % 4) text.push_back(' ');
    const std::uint32_t header[5] = {0x46546C67u, 2, std::uint32_t(12 + 8 + text.size() + 8 + bin.size()),
                                     std::uint32_t(text.size()), 0x4E4F534Au};
    const std::uint32_t bin_header[2] = {std::uint32_t(bin.size()), 0x004E4942u};
    const fs::path p = temp("appended.glb");
    {
        std::ofstream f(p, std::ios::binary);
        f.write(reinterpret_cast<const char*>(header), sizeof header);
        f.write(text.data(), std::streamsize(text.size()));
        f.write(reinterpret_cast<const char*>(bin_header), sizeof bin_header);
        f.write(bin.data(), std::streamsize(bin.size()));
    }
    auto back = read_gaussians(p);
    ASSERT_TRUE(back) << back.message();
    turn_axes(g, AxisTurn::z180);
    ASSERT_EQ(back->size(), g.size());
    EXPECT_EQ(back->positions, g.positions);
    EXPECT_EQ(back->scales, g.scales);
    EXPECT_EQ(back->opacities, g.opacities);
    EXPECT_EQ(back->sh, g.sh);
    for (std::size_t i = 0; i < g.size(); ++i)
        EXPECT_LT(glm::length(glm::vec4(
                      back->rotations[i].x - g.rotations[i].x, back->rotations[i].y - g.rotations[i].y,
                      back->rotations[i].z - g.rotations[i].z, back->rotations[i].w - g.rotations[i].w)),
                  1e-6f)
            << i;
}

std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const unsigned v =
            (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8 | (unsigned char)in[i + 2];
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += t[v >> 6 & 63], out += t[v & 63];
    }
    if (i + 1 == in.size()) {
        const unsigned v = (unsigned char)in[i] << 16;
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += "==";
    } else if (i + 2 == in.size()) {
        const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8;
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += t[v >> 6 & 63], out += '=';
    }
    return out;
}

struct Attr {
    std::string name, type;
    std::vector<float> values;
};

// A .gltf with one POINTS primitive (one element per attribute) and a data-URI buffer.
void write_gltf_text(const fs::path& p, const std::vector<Attr>& attrs, const std::string& node_extra = "") {
    std::string bin, views, accessors, attributes;
    for (std::size_t a = 0; a < attrs.size(); ++a) {
        const std::size_t comps = attrs[a].type == "SCALAR" ? 1 : attrs[a].type == "VEC3" ? 3 : 4;
        const std::size_t off = bin.size();
        bin.append(reinterpret_cast<const char*>(attrs[a].values.data()), attrs[a].values.size() * 4);
        const std::string sep = a ? "," : "";
        views += sep + "{\"buffer\":0,\"byteOffset\":" + std::to_string(off) +
                 ",\"byteLength\":" + std::to_string(attrs[a].values.size() * 4) + "}";
        accessors += sep + "{\"bufferView\":" + std::to_string(a) +
                     ",\"componentType\":5126,\"count\":" + std::to_string(attrs[a].values.size() / comps) +
                     ",\"type\":\"" + attrs[a].type + "\"" +
                     (attrs[a].name == "POSITION" ? ",\"min\":[-9,-9,-9],\"max\":[9,9,9]" : "") + "}";
        attributes += sep + "\"" + attrs[a].name + "\":" + std::to_string(a);
    }
    std::ofstream(p)
        << "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_gaussian_splatting\"],\"scene\":0,"
           "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0" +
               node_extra +
               "}],"
               "\"meshes\":[{\"primitives\":[{\"mode\":0,\"attributes\":{" +
               attributes +
               "},"
               "\"extensions\":{\"KHR_gaussian_splatting\":{\"kernel\":\"ellipse\",\"colorSpace\":\"srgb_"
               "rec709_display\"}}}]}],"
               "\"buffers\":[{\"byteLength\":" +
               std::to_string(bin.size()) + ",\"uri\":\"data:application/octet-stream;base64," + base64(bin) +
               "\"}],\"bufferViews\":[" + views + "],\"accessors\":[" + accessors + "]}";
}

const std::string K = "KHR_gaussian_splatting:";

TEST(GaussianGltf, HandWrittenFileWithNodeRotationAndColorFallback) {
    // One Gaussian at (1,0,0), identity rotation (x,y,z,w) = (0,0,0,1), linear scales, opacity 0.25,
    // no SH_DEGREE_0_COEF_0 but COLOR_0 (0.75, 0.5, 0.25, 1); node rotated 90° about +z. The same node
    // rotation written unnormalised (twice as long) reads the same, as surface glTF nodes do: taken as a
    // matrix, that quaternion would scale by 4 and shear.
    for (const std::string rotation :
         {"0.7071067811865476,0.7071067811865476", "1.4142135623730951,1.4142135623730951"}) {
        SCOPED_TRACE(rotation);
        const fs::path p = temp("hand.gltf");
        write_gltf_text(p,
                        {{"POSITION", "VEC3", {1, 0, 0}},
                         {K + "ROTATION", "VEC4", {0, 0, 0, 1}},
                         {K + "SCALE", "VEC3", {0.1f, 0.2f, 0.3f}},
                         {K + "OPACITY", "SCALAR", {0.25f}},
                         {"COLOR_0", "VEC4", {0.75f, 0.5f, 0.25f, 1.0f}}},
                        ",\"rotation\":[0,0," + rotation + "]");
        auto g = read_gltf(p);
        ASSERT_TRUE(g) << g.message();
        ASSERT_EQ(g->size(), 1u);
        // (0, 1, 0) in glTF's frame, (0, -1, 0) in the internal one (turned 180 degrees about z).
        EXPECT_LT(glm::length(g->positions[0] - glm::vec3(0, -1, 0)), 1e-6f);
        EXPECT_EQ(g->opacities[0], 0.25f);
        // Σ' = Rz Σ Rzᵀ: the 0.1 axis now along y, the 0.2 axis along −x.
        const glm::dmat3 s = covariance(glm::dvec3(g->scales[0]), glm::dquat(g->rotations[0]));
        EXPECT_NEAR(s[0][0], 0.04, 1e-7);
        EXPECT_NEAR(s[1][1], 0.01, 1e-7);
        EXPECT_NEAR(s[2][2], 0.09, 1e-7);
        EXPECT_NEAR(s[1][0], 0.0, 1e-7);
        const glm::vec3 col = sh_color(0, g->sh.data(), {0, 0, 1});
        EXPECT_LT(glm::length(col - glm::vec3(0.75f, 0.5f, 0.25f)), 1e-6f);
    }
}

TEST(GaussianGltf, BadFiles) {
    auto expect = [](const fs::path& p, const std::string& fragment) {
        auto g = read_gltf(p);
        ASSERT_FALSE(g);
        EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
        EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
    };
    const std::vector<Attr> base = {{"POSITION", "VEC3", {1, 0, 0}},
                                    {K + "ROTATION", "VEC4", {0, 0, 0, 1}},
                                    {K + "SCALE", "VEC3", {0.1f, 0.2f, 0.3f}},
                                    {K + "OPACITY", "SCALAR", {0.25f}},
                                    {K + "SH_DEGREE_0_COEF_0", "VEC3", {0, 0, 0}}};
    std::vector<Attr> a = base;
    a.erase(a.begin() + 3);
    write_gltf_text(temp("no_opacity.gltf"), a);
    expect(temp("no_opacity.gltf"), "missing attribute KHR_gaussian_splatting:OPACITY");
    a = base;
    a[2].values = {-2.3f, -1.6f, -1.2f};  // log-space scales (review draft)
    write_gltf_text(temp("log_scale.gltf"), a);
    expect(temp("log_scale.gltf"), "negative scale");
    a = base;
    a.push_back({K + "SH_DEGREE_1_COEF_0", "VEC3", {0, 0, 0}});
    write_gltf_text(temp("partial.gltf"), a);
    expect(temp("partial.gltf"), "SH degree 1 is partial (1 of 3 coefficients)");
    a = base;
    a[3].values = {1.5f};
    write_gltf_text(temp("opacity.gltf"), a);
    expect(temp("opacity.gltf"), "opacity outside [0, 1]");
    a = base;
    a[1].values = {0, 0, 0, 1, 0, 0, 0, 1};  // two rotations, one position
    write_gltf_text(temp("count.gltf"), a);
    expect(temp("count.gltf"), "has 2 elements, POSITION 1");
    std::ofstream(temp("garbage.glb")) << "glTF garbage";
    expect(temp("garbage.glb"), "invalid glTF");
}

}  // namespace
