// `splatffd convert --order`, through the built binary: the output is a permutation of the input (every
// point's attributes found with it, by a map from position to all of them), in Morton order by a bit-by-bit
// reference computed here, deterministic, for surface splats (PLY, GLB) and Gaussians (PLY, GLB), a scene
// IN keeps its lattice, and a bad value is a usage error naming the accepted ones.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "runtime/assets/scene.h"
#include "runtime/scene/lattice.h"
#include "systems/gaussian/gaussian_read.h"
#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace {

using sffd::test::CliRun;
CliRun tool(const std::string& args) { return sffd::test::run_headless(args); }

fs::path temp_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("sffd_convert_order_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void convert(const std::string& args) {
    const CliRun r = tool("convert " + args);
    ASSERT_EQ(r.code, 0) << args << "\n" << r.out;
}

std::string bytes(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
}

// The reference Morton codes of `p`: 2^21 cells per axis across their box, bits interleaved one by one
// from the top, x before y before z.
std::vector<std::uint64_t> reference_codes(const std::vector<glm::vec3>& p) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& v : p) lo = glm::min(lo, glm::dvec3(v)), hi = glm::max(hi, glm::dvec3(v));
    std::vector<std::uint64_t> codes;
    for (const glm::vec3& v : p) {
        std::uint32_t q[3] = {0, 0, 0};
        for (int a = 0; a < 3; ++a)
            if (hi[a] > lo[a])
                q[a] = std::min<std::uint32_t>(
                    std::uint32_t(std::floor((double(v[a]) - lo[a]) / (hi[a] - lo[a]) * 2097152.0)),
                    2097151u);
        std::uint64_t c = 0;
        for (int bit = 20; bit >= 0; --bit)
            for (int a = 0; a < 3; ++a) c = c << 1 | ((q[a] >> bit) & 1u);
        codes.push_back(c);
    }
    return codes;
}

void expect_morton(const std::vector<glm::vec3>& p, const std::string& what) {
    const std::vector<std::uint64_t> c = reference_codes(p);
    for (std::size_t i = 0; i + 1 < c.size(); ++i) ASSERT_LE(c[i], c[i + 1]) << what << " at " << i;
}

using Key = std::array<float, 3>;
Key key(const glm::vec3& v) { return {v.x, v.y, v.z}; }

// All of a surface point's attributes as floats (colours as their value).
std::vector<float> surface_attrs(const sffd::SplatCloud& c, std::size_t i) {
    std::vector<float> a;
    auto add = [&](const auto& col, int n) {
        if (col.empty()) return;
        for (int k = 0; k < n; ++k) a.push_back(float(col[i][k]));
    };
    add(c.normals, 3), add(c.axis_u, 3), add(c.axis_v, 3), add(c.uvs, 2), add(c.uv_axes, 4);
    if (!c.colors.empty())
        for (int k = 0; k < 4; ++k) a.push_back(float((c.colors[i] >> (8 * k)) & 0xffu));
    return a;
}

std::vector<float> gaussian_attrs(const sffd::GaussianCloud& g, std::size_t i) {
    const std::size_t K = std::size_t(sffd::sh_coeffs(g.sh_degree)) * 3;
    // q and -q are one rotation (a format may store either): the sign that makes w non-negative.
    const glm::quat q = g.rotations[i].w < 0 ? -g.rotations[i] : g.rotations[i];
    std::vector<float> a = {g.scales[i].x, g.scales[i].y, g.scales[i].z, q.w, q.x, q.y, q.z, g.opacities[i]};
    a.insert(a.end(), g.sh.begin() + std::ptrdiff_t(i * K), g.sh.begin() + std::ptrdiff_t((i + 1) * K));
    return a;
}

// `out` holds the points of `in`, each with all its attributes (equal, or within `tol` relative to the
// largest where a format's encoding was applied a different number of times), each once; returns how many
// moved.
template <class Cloud, class Attrs>
std::size_t expect_permutation(const Cloud& in, const Cloud& out, Attrs attrs, const std::string& what,
                               float tol = 0.0f) {
    EXPECT_EQ(in.size(), out.size()) << what;
    std::map<Key, std::pair<std::vector<float>, std::size_t>> by_position;
    for (std::size_t i = 0; i < in.size(); ++i) by_position[key(in.positions[i])] = {attrs(in, i), i};
    EXPECT_EQ(by_position.size(), in.size()) << what << ": positions are not distinct";
    std::size_t moved = 0;
    for (std::size_t t = 0; t < out.size(); ++t) {
        const auto it = by_position.find(key(out.positions[t]));
        if (it == by_position.end()) {
            ADD_FAILURE() << what << ": point " << t << " is not in the input";
            return moved;
        }
        const std::vector<float> got = attrs(out, t), want = it->second.first;
        if (tol == 0.0f) {
            EXPECT_EQ(got, want) << what << ": point " << t;
        } else {
            if (got.size() != want.size()) {
                ADD_FAILURE() << what << ": point " << t << " has other attributes";
                return moved;
            }
            float scale = 0.0f;
            for (float v : want) scale = std::max(scale, std::abs(v));
            for (std::size_t k = 0; k < got.size(); ++k)
                EXPECT_NEAR(got[k], want[k], tol * std::max(scale, 1e-6f))
                    << what << ": point " << t << "[" << k << "]";
        }
        moved += it->second.second != t;
        by_position.erase(it);
    }
    EXPECT_TRUE(by_position.empty()) << what;
    return moved;
}

sffd::SplatCloud load_surface(const fs::path& p, std::size_t* lattices = nullptr) {
    sffd::ecs::Registry r;
    r.set_resource<sffd::SceneHooks>();  // assets' own formats only
    const sffd::Status s = sffd::load_scene(r, p.string());
    EXPECT_TRUE(s) << (s ? "" : s.message());
    sffd::SplatCloud c;
    r.each_entity([&](sffd::ecs::Entity e) {
        if (const auto* sc = r.try_get<sffd::SplatCloud>(e)) c = *sc;
    });
    if (lattices) *lattices = r.count<sffd::Lattice>();
    return c;
}

TEST(ConvertOrder, SurfaceSplatsInMortonOrderArePermutedWithEveryColumnInPlyAndGlb) {
    const fs::path d = temp_dir("surface");
    convert("sphere " + (d / "keep.ply").string() + " --splats 5000");
    convert("sphere " + (d / "morton.ply").string() + " --splats 5000 --order morton");
    fs::create_directories(d / "again");  // the same name: the header names the texture after the file
    convert("sphere " + (d / "again" / "morton.ply").string() + " --splats 5000 --order morton");
    convert((d / "keep.ply").string() + " " + (d / "from_file.glb").string() + " --order morton");
    convert((d / "morton.ply").string() + " " + (d / "round.glb").string() + " --order keep");
    convert((d / "round.glb").string() + " " + (d / "round.ply").string());
    const sffd::SplatCloud keep = load_surface(d / "keep.ply"), morton = load_surface(d / "morton.ply");
    ASSERT_EQ(keep.size(), 5000u);
    EXPECT_FALSE(keep.colors.empty() && keep.uvs.empty());
    EXPECT_GT(expect_permutation(keep, morton, surface_attrs, "morton.ply"), 4000u);
    expect_morton(morton.positions, "morton.ply");
    EXPECT_TRUE(bytes(d / "morton.ply") == bytes(d / "again" / "morton.ply"));  // deterministic
    const sffd::SplatCloud glb = load_surface(d / "from_file.glb");
    expect_permutation(keep, glb, surface_attrs, "from_file.glb");
    expect_morton(glb.positions, "from_file.glb");
    // Through GLB and back with --order keep: the order stays.
    const sffd::SplatCloud round = load_surface(d / "round.ply");
    ASSERT_EQ(round.size(), morton.size());
    EXPECT_EQ(expect_permutation(morton, round, surface_attrs, "round trip", 1e-4f), 0u);
}

TEST(ConvertOrder, GaussiansInMortonOrderArePermutedWithEveryColumn) {
    const fs::path d = temp_dir("gaussians");
    convert("sphere " + (d / "g.ply").string() + " --gaussians --splats 4000");
    // Each output against the same file written in the input's order: both went through the same
    // encodings (log scales, logit opacities, glTF's layout), so every value is comparable bit for bit.
    for (const char* ext : {".ply", ".glb"}) {
        const fs::path k = d / (std::string("k") + ext), m = d / (std::string("m") + ext);
        convert((d / "g.ply").string() + " " + k.string() + " --order keep");
        convert((d / "g.ply").string() + " " + m.string() + " --order morton");
        auto gk = sffd::gaussian::read_gaussians(k), gm = sffd::gaussian::read_gaussians(m);
        ASSERT_TRUE(gk && gm) << ext;
        EXPECT_GT(expect_permutation(*gk, *gm, gaussian_attrs, m.string()), 3000u);
        expect_morton(gm->positions, m.string());
    }
    // Through GLB and back to PLY with the default order: the order stays.
    convert((d / "m.glb").string() + " " + (d / "back.ply").string());
    auto m = sffd::gaussian::read_gaussians(d / "m.ply"), b = sffd::gaussian::read_gaussians(d / "back.ply");
    ASSERT_TRUE(m && b);
    EXPECT_EQ(expect_permutation(*m, *b, gaussian_attrs, "through m.glb", 1e-3f), 0u);
}

TEST(ConvertOrder, ASceneKeepsItsLatticeAndItsCloudIsReordered) {
    const fs::path d = temp_dir("scene");
    convert("sphere " + (d / "s.glb").string() + " --splats 5000 --lattice fit:4,4,4");
    convert((d / "s.glb").string() + " " + (d / "m.glb").string() + " --order morton");
    std::size_t ls = 0, lm = 0;
    const sffd::SplatCloud s = load_surface(d / "s.glb", &ls), m = load_surface(d / "m.glb", &lm);
    EXPECT_EQ(ls, 1u);
    EXPECT_EQ(lm, 1u);
    EXPECT_GT(expect_permutation(s, m, surface_attrs, "scene"), 4000u);
    expect_morton(m.positions, "scene");
    // The lattice JSON of both scenes is the same text.
    convert((d / "s.glb").string() + " " + (d / "s.json").string());
    convert((d / "m.glb").string() + " " + (d / "m.json").string());
    EXPECT_TRUE(bytes(d / "s.json") == bytes(d / "m.json"));
}

TEST(ConvertOrder, AnUnknownOrderIsAUsageErrorNamingTheAcceptedValues) {
    const fs::path d = temp_dir("bogus");
    const CliRun r = tool("convert sphere " + (d / "x.ply").string() + " --order bogus");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("--order 'bogus': expected keep or morton"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(d / "x.ply"));
}

}  // namespace
