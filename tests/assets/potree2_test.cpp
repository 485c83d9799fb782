// Potree 2 octrees of surface splats (runtime/assets/formats/surface/potree2.h, potree2_write.h): the
// full detail equals the input, the node structure (every point in one node, children inside parents,
// representatives covering what they stand for), cuts, and hostile or truncated files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <filesystem>
#include <random>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "runtime/assets/import.h"
#include "tests/assets/test_util.h"

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::assets;

namespace {

// Points on a wavy sphere of radius 3 around a far origin, every column set, some splats translucent.
SplatCloud test_cloud(std::size_t n, std::uint32_t seed = 5) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1), r(0.01, 0.05);
    SplatCloud c;
    c.origin = {1000.0, -20.0, 5.0};
    for (std::size_t i = 0; i < n; ++i) {
        glm::dvec3 d;
        do d = {u(rng), u(rng), u(rng)};
        while (glm::length(d) < 0.1 || glm::length(d) > 1.0);
        d = glm::normalize(d);
        const glm::dvec3 p = d * (3.0 + 0.2 * std::sin(5 * d.x));
        const glm::dvec3 ref = std::abs(d.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
        const glm::dvec3 a = glm::normalize(glm::cross(ref, d)), b = glm::cross(d, a);
        c.positions.push_back(glm::vec3(p));
        c.normals.push_back(glm::vec3(d));
        c.axis_u.push_back(glm::vec3(a * r(rng)));
        c.axis_v.push_back(glm::vec3(b * r(rng)));
        const std::uint32_t alpha = i % 7 == 0 ? 128u : 255u;
        c.colors.push_back((std::uint32_t(i * 2654435761u) & 0xffffffu) | alpha << 24);
        c.uvs.push_back({float(u(rng)), float(u(rng))});
        c.uv_axes.push_back({float(u(rng)), float(u(rng)), float(u(rng)), float(u(rng))});
    }
    c.texture.width = 4, c.texture.height = 2;
    for (int t = 0; t < 32; ++t) c.texture.rgba8.push_back(std::uint8_t(t * 8));
    return c;
}

// Small nodes, a coarse grid and a small budget: many levels, several hierarchy chunks and cells.
Potree2BuildOptions small_options() {
    Potree2BuildOptions o;
    o.max_leaf = 48;
    o.grid_cells = 8;
    o.memory_budget = std::uint64_t(1) << 20;
    return o;
}

fs::path build(const SplatCloud& c, const std::string& name, const Potree2BuildOptions& o = small_options()) {
    const fs::path dir = test::fresh_dir("potree2", name);
    auto stats = build_potree2(cloud_splat_source(c, "test cloud"), dir / "metadata.json", o);
    EXPECT_TRUE(stats) << (stats ? "" : stats.message());
    return dir / "metadata.json";
}

// Splats in a canonical order (their axes are unique and stored exactly).
std::vector<std::size_t> by_axes(const SplatCloud& c) {
    std::vector<std::size_t> idx(c.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
        const auto& x = c.axis_u[a];
        const auto& y = c.axis_u[b];
        return std::tie(x.x, x.y, x.z) < std::tie(y.x, y.y, y.z);
    });
    return idx;
}

std::string message_of(const fs::path& meta) {
    auto o = open_potree2(meta);
    return o ? std::string("(opened)") : o.message();
}

void patch(const fs::path& p, std::size_t at, const void* bytes, std::size_t n) {
    std::string s = test::slurp(p);
    ASSERT_LE(at + n, s.size());
    std::memcpy(&s[at], bytes, n);
    test::write(p, s);
}

void edit_meta(const fs::path& meta, const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(test::slurp(meta));
    edit(j);
    test::write(meta, j.dump());
}

}  // namespace

TEST(Potree2, FullDetailEqualsTheInput) {
    const SplatCloud in = test_cloud(6000);
    const fs::path meta = build(in, "roundtrip");
    auto o = open_potree2(meta);
    ASSERT_TRUE(o) << o.message();
    EXPECT_EQ(o->points, in.size());
    EXPECT_GT(o->chunks, 1u) << "deeper than one hierarchy chunk: proxies were written and followed";
    auto out = read_potree2(*o);
    ASSERT_TRUE(out) << out.message();
    ASSERT_EQ(out->size(), in.size());
    EXPECT_EQ(out->origin, in.origin);
    const auto a = by_axes(in), b = by_axes(*out);
    const double tol = 0.5 * o->scale.x + 1e-6;  // the int32 quantum, and float positions near 3
    for (std::size_t k = 0; k < a.size(); ++k) {
        const std::size_t i = a[k], j = b[k];
        ASSERT_EQ(in.axis_u[i], out->axis_u[j]) << k;
        EXPECT_EQ(in.axis_v[i], out->axis_v[j]);
        EXPECT_EQ(in.normals[i], out->normals[j]);
        EXPECT_EQ(in.colors[i], out->colors[j]);
        EXPECT_EQ(in.uvs[i], out->uvs[j]);
        EXPECT_EQ(in.uv_axes[i], out->uv_axes[j]);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(in.positions[i][c], out->positions[j][c], tol) << k;
    }
    EXPECT_EQ(out->texture.width, 4);
    EXPECT_EQ(out->texture.rgba8, in.texture.rgba8);
    // The import path (convert IN, render, view) reads the same full detail.
    auto imported = import_splat_cloud(meta);
    ASSERT_TRUE(imported) << imported.message();
    EXPECT_EQ(imported->size(), in.size());
}

TEST(Potree2, EveryPointInOneNodeChildrenInsideParentsRepresentativesCover) {
    const SplatCloud in = test_cloud(4000, 9);
    const fs::path meta = build(in, "structure");
    auto o = open_potree2(meta);
    ASSERT_TRUE(o) << o.message();
    std::uint64_t sum = 0;
    const double eps = o->scale.x * 2;
    std::vector<SplatCloud> own(o->nodes.size()), grown(o->nodes.size());
    for (std::uint32_t i = 0; i < o->nodes.size(); ++i) {
        const PotreeNode& n = o->nodes[i];
        sum += n.points;
        EXPECT_GT(n.points, 0u) << n.name << ": no empty node (an inner node keeps a point)";
        if (n.parent >= 0) {
            const PotreeNode& p = o->nodes[std::size_t(n.parent)];
            for (int a = 0; a < 3; ++a) {
                EXPECT_GE(n.lo[a], p.lo[a]) << n.name;
                EXPECT_LE(n.hi[a], p.hi[a]) << n.name;
            }
            EXPECT_EQ(n.name.substr(0, p.name.size()), p.name);
        }
        auto pts = read_potree2_nodes(*o, {i});
        ASSERT_TRUE(pts) << pts.message();
        grown[i] = *pts;
        for (const glm::vec3& q : pts->positions) {
            const glm::dvec3 w = pts->origin + glm::dvec3(q);
            for (int a = 0; a < 3; ++a) {
                EXPECT_GE(w[a], n.lo[a] - eps) << n.name;
                EXPECT_LE(w[a], n.hi[a] + eps) << n.name;
            }
        }
        // Its own radii: the node with all of its children.
        std::vector<std::uint32_t> with_kids{i};
        for (std::int32_t c : n.children)
            if (c >= 0) with_kids.push_back(std::uint32_t(c));
        auto full = read_potree2_nodes(*o, with_kids);
        ASSERT_TRUE(full) << full.message();
        full->positions.resize(n.points), full->axis_u.resize(n.points), full->axis_v.resize(n.points);
        own[i] = std::move(*full);
    }
    EXPECT_EQ(sum, in.size()) << "every point in exactly one node";
    // Each point below a node lies within a representative's grown radius, its own radius included.
    std::size_t checked = 0;
    for (std::uint32_t i = 0; i < o->nodes.size(); ++i) {
        if (!o->nodes[i].has_children() || o->nodes[i].points == 0) continue;
        std::vector<std::uint32_t> below;
        for (std::uint32_t j = 0; j < o->nodes.size(); ++j)
            if (j != i && o->nodes[j].name.rfind(o->nodes[i].name, 0) == 0) below.push_back(j);
        const SplatCloud& reps = grown[i];
        for (const std::uint32_t j : below)
            for (std::size_t k = 0; k < own[j].size(); ++k) {
                const glm::dvec3 p = own[j].origin + glm::dvec3(own[j].positions[k]);
                const double rp = std::max(glm::length(own[j].axis_u[k]), glm::length(own[j].axis_v[k]));
                double worst =
                    std::numeric_limits<double>::infinity();  // the least shortfall over the representatives
                for (std::size_t q = 0; q < reps.size(); ++q) {
                    const double R = std::min(glm::length(reps.axis_u[q]), glm::length(reps.axis_v[q]));
                    worst = std::min(worst,
                                     glm::length(p - (reps.origin + glm::dvec3(reps.positions[q]))) + rp - R);
                }
                ASSERT_LE(worst, 1e-5)
                    << "a point of " << o->nodes[j].name << " is not covered by " << o->nodes[i].name;
                ++checked;
            }
    }
    EXPECT_GT(checked, in.size());
}

TEST(Potree2, ACutReadsItsNodesWithGrownRadii) {
    const SplatCloud in = test_cloud(3000, 11);
    auto o = open_potree2(build(in, "cut"));
    ASSERT_TRUE(o) << o.message();
    const auto cut = potree2_level_cut(*o, 1);
    std::uint64_t expect = 0;
    for (auto i : cut) expect += o->nodes[i].points;
    auto c = read_potree2_nodes(*o, cut);
    ASSERT_TRUE(c) << c.message();
    EXPECT_EQ(c->size(), expect);
    EXPECT_LT(c->size(), in.size());
    double mean_cut = 0, mean_full = 0;
    for (const auto& a : c->axis_u) mean_cut += double(glm::length(a)) / double(c->size());
    for (const auto& a : in.axis_u) mean_full += double(glm::length(a)) / double(in.size());
    EXPECT_GT(mean_cut, 2 * mean_full) << "coarse splats grow to cover the missing children";
    auto twice = read_potree2_nodes(*o, {0, 0});
    ASSERT_FALSE(twice);
    EXPECT_NE(twice.message().find("named twice"), std::string::npos) << twice.message();
}

TEST(Potree2, MetadataDeclaresPotreesAttributes) {
    const fs::path meta = build(test_cloud(500), "attributes");
    const auto j = nlohmann::json::parse(test::slurp(meta));
    EXPECT_EQ(j["version"], "2.0");
    EXPECT_EQ(j["encoding"], "DEFAULT");
    EXPECT_EQ(j["hierarchy"]["stepSize"], 4);
    EXPECT_EQ(j["attributes"][0]["name"], "position");
    EXPECT_EQ(j["attributes"][0]["type"], "int32");
    EXPECT_EQ(j["attributes"][1]["name"], "rgb");
    EXPECT_EQ(j["attributes"][1]["type"], "uint16");
    EXPECT_EQ(j["attributes"][1]["size"], 6);
    EXPECT_EQ(fs::file_size(meta.parent_path() / "hierarchy.bin") % 22, 0u);
    // A box whose sides are equal: Potree halves it into its children.
    const double side = double(j["boundingBox"]["max"][0]) - double(j["boundingBox"]["min"][0]);
    EXPECT_NEAR(double(j["boundingBox"]["max"][2]) - double(j["boundingBox"]["min"][2]), side, 1e-12 * side);
}

TEST(Potree2, StreamedSourcesBuildTheSameCount) {
    const fs::path dir = test::fresh_dir("potree2", "synthetic");
    Potree2BuildOptions o = small_options();
    o.max_leaf = 2000, o.grid_cells = 32;
    auto stats = build_potree2(synthetic_splat_source(200000), dir / "metadata.json", o);
    ASSERT_TRUE(stats) << stats.message();
    EXPECT_EQ(stats->points, 200000u);
    EXPECT_GT(stats->cells, 8u) << "bucketed into cells on disk";
    EXPECT_LT(stats->peak_bytes, std::uint64_t(48) << 20);
    auto t = open_potree2(dir / "metadata.json");
    ASSERT_TRUE(t) << t.message();
    EXPECT_EQ(t->points, 200000u);
}

TEST(Potree2, TruncatedFilesAreRefused) {
    const fs::path meta = build(test_cloud(2000), "truncated");
    const fs::path dir = meta.parent_path();
    fs::resize_file(dir / "octree.bin", fs::file_size(dir / "octree.bin") - 5);
    EXPECT_NE(message_of(meta).find("lie outside"), std::string::npos) << message_of(meta);
    const fs::path meta2 = build(test_cloud(2000), "truncated2");
    fs::resize_file(meta2.parent_path() / "hierarchy.bin",
                    fs::file_size(meta2.parent_path() / "hierarchy.bin") - 22);
    EXPECT_NE(message_of(meta2).find("hierarchy.bin"), std::string::npos) << message_of(meta2);
    const fs::path meta3 = build(test_cloud(200), "truncated3");
    fs::resize_file(meta3, fs::file_size(meta3) / 2);
    EXPECT_NE(message_of(meta3).find("not valid JSON"), std::string::npos) << message_of(meta3);
    EXPECT_EQ(message_of(meta3).rfind(meta3.string(), 0), 0u) << "names the file";
}

TEST(Potree2, HostileHierarchyRecordsAreRefused) {
    const auto expect = [](const std::string& name, std::size_t at, std::vector<std::uint8_t> bytes,
                           const std::string& what) {
        const fs::path meta = build(test_cloud(2000), "hostile_" + name);
        patch(meta.parent_path() / "hierarchy.bin", at, bytes.data(), bytes.size());
        const std::string m = message_of(meta);
        EXPECT_NE(m.find(what), std::string::npos) << name << ": " << m;
        EXPECT_NE(m.find("hierarchy.bin"), std::string::npos) << name << ": " << m;
    };
    const auto u32 = [](std::uint32_t v) {
        std::vector<std::uint8_t> b(4);
        std::memcpy(b.data(), &v, 4);
        return b;
    };
    const auto i64 = [](std::int64_t v) {
        std::vector<std::uint8_t> b(8);
        std::memcpy(b.data(), &v, 8);
        return b;
    };
    expect("type", 0, {7}, "type 7");
    expect("leaf_with_children", 0, {1}, "a leaf (type 1) with children");
    expect("fewer_children", 1, {0x01}, "declare");
    expect("count", 2, u32(4000000000u), "are not its");
    expect("offset", 6, i64(std::int64_t(1) << 40), "lie outside");
    expect("negative", 14, i64(-22), "negative");
    expect("root_proxy", 0, {2}, "proxy again");
    // The root's first child record pointed at the root's own bytes: the second child shares them.
    const fs::path meta = build(test_cloud(2000), "hostile_shared");
    const std::string h = test::slurp(meta.parent_path() / "hierarchy.bin");
    std::int64_t root_off, root_size;
    std::memcpy(&root_off, h.data() + 6, 8), std::memcpy(&root_size, h.data() + 14, 8);
    std::uint32_t root_points;
    std::memcpy(&root_points, h.data() + 2, 4);
    patch(meta.parent_path() / "hierarchy.bin", 22 + 2, &root_points, 4);
    patch(meta.parent_path() / "hierarchy.bin", 22 + 6, &root_off, 8);
    patch(meta.parent_path() / "hierarchy.bin", 22 + 14, &root_size, 8);
    EXPECT_NE(message_of(meta).find("share bytes"), std::string::npos) << message_of(meta);
}

TEST(Potree2, ProxiesThatLoopOrLeaveTheFileAreRefused) {
    const fs::path meta = build(test_cloud(6000), "proxies");
    const fs::path hp = meta.parent_path() / "hierarchy.bin";
    const std::string h = test::slurp(hp);
    std::size_t proxy = 0;
    for (std::size_t at = 0; at < h.size(); at += 22)
        if (h[at] == 2) {
            proxy = at;
            break;
        }
    ASSERT_GT(proxy, 0u) << "the test cloud is deep enough for proxies";
    const std::int64_t zero = 0, far = std::int64_t(h.size()) + 22;
    patch(hp, proxy + 6, &zero, 8);  // back into the first chunk
    EXPECT_NE(message_of(meta).find("again"), std::string::npos) << message_of(meta);
    test::write(hp, h);
    patch(hp, proxy + 6, &far, 8);
    EXPECT_NE(message_of(meta).find("inside the file"), std::string::npos) << message_of(meta);
}

TEST(Potree2, HostileMetadataIsRefused) {
    const auto expect = [](const std::string& name, const std::function<void(nlohmann::json&)>& edit,
                           const std::string& what) {
        const fs::path meta = build(test_cloud(300), "meta_" + name);
        edit_meta(meta, edit);
        const std::string m = message_of(meta);
        EXPECT_NE(m.find(what), std::string::npos) << name << ": " << m;
        EXPECT_EQ(m.rfind(meta.string(), 0), 0u) << name << ": names the file: " << m;
    };
    expect(
        "points", [](auto& j) { j["points"] = 1e15; }, "\"points\"");
    expect(
        "points_sum", [](auto& j) { j["points"] = 301; }, "the nodes hold 300");
    expect(
        "brotli", [](auto& j) { j["encoding"] = "BROTLI"; }, "BROTLI");
    expect(
        "version", [](auto& j) { j["version"] = "1.8"; }, "version");
    expect(
        "step", [](auto& j) { j["hierarchy"]["stepSize"] = 0; }, "stepSize");
    expect(
        "chunk", [](auto& j) { j["hierarchy"]["firstChunkSize"] = 23; }, "firstChunkSize");
    expect(
        "scale",
        [](auto& j) {
            j["scale"] = {0, 1, 1};
        },
        "\"scale\"");
    expect(
        "box", [](auto& j) { j["boundingBox"]["max"] = j["boundingBox"]["min"]; }, "boundingBox");
    expect(
        "element_size", [](auto& j) { j["attributes"][1]["elementSize"] = 4; }, "elementSize");
    expect(
        "size", [](auto& j) { j["attributes"][1]["size"] = 1000000; }, "size must be");
    expect(
        "type", [](auto& j) { j["attributes"][0]["type"] = "int33"; }, "type");
    expect(
        "our_type", [](auto& j) { j["attributes"][3]["type"] = "int32"; }, "it is read as float x 3");
    expect(
        "no_position", [](auto& j) { j["attributes"][0]["name"] = "other"; }, "no \"position\"");
    expect(
        "many",
        [](auto& j) {
            for (int i = 0; i < 100; ++i) j["attributes"].push_back(j["attributes"][0]);
        },
        "more than the 64 limit");
    expect(
        "texture_out", [](auto& j) { j["sffd"]["texture"] = "../escape.png"; }, "outside the file's folder");
    expect(
        "texture_abs", [](auto& j) { j["sffd"]["texture"] = "/etc/passwd"; }, "outside the file's folder");
}

TEST(Potree2, FilesOutsideTheFolderAndOversizedMetadataAreRefused) {
    const fs::path meta = build(test_cloud(300), "escape");
    const fs::path dir = meta.parent_path();
    const fs::path outside = dir.parent_path() / "escape_outside.bin";
    fs::rename(dir / "hierarchy.bin", outside);
    fs::create_symlink(outside, dir / "hierarchy.bin");
    EXPECT_NE(message_of(meta).find("outside the file's folder"), std::string::npos) << message_of(meta);
    const fs::path big = build(test_cloud(300), "big");
    test::write(big, std::string(std::size_t(kMaxPotreeMetaBytes) + 1, ' '));
    EXPECT_NE(message_of(big).find("limit"), std::string::npos) << message_of(big);
    const fs::path deep = build(test_cloud(300), "deep");
    test::write(deep, std::string(100000, '['));
    EXPECT_NE(message_of(deep).find("nesting"), std::string::npos) << message_of(deep);
}

TEST(Potree2, AnotherToolsOctreeReadsAsPoints) {
    // PotreeConverter's own files carry no splat axes: read_potree2 refuses, the geometry path reads the
    // points (convert estimates normals and radii for them).
    const fs::path meta = build(test_cloud(300), "foreign");
    edit_meta(meta, [](auto& j) {
        for (auto& a : j["attributes"])
            if (a["name"] == "sffd_axis_u") a["name"] = "intensity_like";
    });
    auto o = open_potree2(meta);
    ASSERT_TRUE(o) << o.message();
    auto c = read_potree2(*o);
    ASSERT_FALSE(c);
    EXPECT_NE(c.message().find("read it as points"), std::string::npos) << c.message();
    auto g = read_geometry(meta);
    ASSERT_TRUE(g) << g.message();
    EXPECT_EQ(g->positions.size(), 300u);
    EXPECT_EQ(g->colors.size(), 300u);
}

TEST(Potree2, PotreeConvertersOwnLayoutReads) {
    // A one-leaf octree as PotreeConverter writes one from a LAS file: position, intensity, then rgb
    // (16-bit), no splat attributes; hierarchy.bin is the root's one record (type 1, no children).
    const fs::path dir = test::fresh_dir("potree2", "converter");
    const std::int32_t pos[3][3] = {{0, 0, 0}, {1000, 2000, 3000}, {4000, 100, 50}};
    const std::uint16_t rgb[3][3] = {{65535, 0, 0}, {0, 256 * 128, 0}, {10, 20, 30}};  // 16- and 8-bit values
    std::string octree;
    for (int i = 0; i < 3; ++i) {
        octree.append(reinterpret_cast<const char*>(pos[i]), 12);
        octree.push_back(char(7));  // intensity (uint8)
        octree.append(reinterpret_cast<const char*>(rgb[i]), 6);
    }
    test::write(dir / "octree.bin", octree);
    std::string h(22, '\0');
    const std::uint32_t n = 3;
    const std::int64_t off = 0, size = std::int64_t(octree.size());
    h[0] = 1;
    std::memcpy(&h[2], &n, 4), std::memcpy(&h[6], &off, 8), std::memcpy(&h[14], &size, 8);
    test::write(dir / "hierarchy.bin", h);
    nlohmann::json m = {{"version", "2.0"},
                        {"name", "las"},
                        {"description", ""},
                        {"points", 3},
                        {"projection", ""},
                        {"hierarchy", {{"firstChunkSize", 22}, {"stepSize", 4}, {"depth", 0}}},
                        {"offset", {10.0, 20.0, 30.0}},
                        {"scale", {0.001, 0.001, 0.001}},
                        {"spacing", 0.1},
                        {"boundingBox", {{"min", {10.0, 20.0, 30.0}}, {"max", {15.0, 25.0, 35.0}}}},
                        {"encoding", "DEFAULT"},
                        {"attributes",
                         {{{"name", "position"},
                           {"description", ""},
                           {"size", 12},
                           {"numElements", 3},
                           {"elementSize", 4},
                           {"type", "int32"},
                           {"min", {10, 20, 30}},
                           {"max", {14, 22, 33}}},
                          {{"name", "intensity"},
                           {"description", ""},
                           {"size", 1},
                           {"numElements", 1},
                           {"elementSize", 1},
                           {"type", "uint8"},
                           {"min", {7}},
                           {"max", {7}}},
                          {{"name", "rgb"},
                           {"description", ""},
                           {"size", 6},
                           {"numElements", 3},
                           {"elementSize", 2},
                           {"type", "uint16"},
                           {"min", {0, 0, 0}},
                           {"max", {65535, 32768, 30}}}}}};
    test::write(dir / "metadata.json", m.dump());
    auto g = read_geometry(dir / "metadata.json");
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->positions.size(), 3u);
    EXPECT_NEAR(g->positions[1].x, 11.0, 1e-9);
    EXPECT_NEAR(g->positions[1].y, 22.0, 1e-9);
    EXPECT_NEAR(g->positions[2].z, 30.05, 1e-9);
    EXPECT_EQ(g->colors[0], 0xff0000ffu);  // 65535 / 256 = 255
    EXPECT_EQ(g->colors[1], 0xff008000u);  // 32768 / 256 = 128
    EXPECT_EQ(g->colors[2], 0xff1e140au);  // 8-bit values as they are
    EXPECT_TRUE(g->normals.empty()) << "estimated by make_splat_cloud";
}
