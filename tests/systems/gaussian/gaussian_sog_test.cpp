// SOG (PlayCanvas): hand-built archives and folders with known values (WebP lossless images made here
// with libwebp, a stored or deflated ZIP), and bad files, one per check of the reader.
#include <gtest/gtest.h>

#include <unistd.h>
#include <webp/encode.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "systems/gaussian/gaussian_scene.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;
using json = nlohmann::json;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_sog_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

void put16(std::string& s, unsigned v) { s += char(v & 0xff), s += char((v >> 8) & 0xff); }
void put32(std::string& s, std::uint32_t v) { put16(s, v & 0xffff), put16(s, v >> 16); }

std::string webp(int w, int h, const std::vector<unsigned char>& rgba) {
    std::uint8_t* out = nullptr;
    const std::size_t n = WebPEncodeLosslessRGBA(rgba.data(), w, h, w * 4, &out);
    std::string s(reinterpret_cast<const char*>(out), n);
    WebPFree(out);
    return s;
}

// A ZIP of the entries, stored, or deflated when `deflate` (raw deflate, method 8).
std::string zip(const std::map<std::string, std::string>& entries, bool deflated = false) {
    std::string out, cd;
    for (const auto& [name, data] : entries) {
        std::string body = data;
        if (deflated) {
            z_stream z{};
            deflateInit2(&z, 6, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
            body.assign(deflateBound(&z, uLong(data.size())), '\0');
            z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
            z.avail_in = uInt(data.size());
            z.next_out = reinterpret_cast<Bytef*>(body.data());
            z.avail_out = uInt(body.size());
            deflate(&z, Z_FINISH);
            body.resize(z.total_out);
            deflateEnd(&z);
        }
        const std::uint32_t crc =
            std::uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(data.data()), uInt(data.size())));
        const std::uint32_t local = std::uint32_t(out.size());
        put32(out, 0x04034b50), put16(out, 20), put16(out, 0), put16(out, deflated ? 8 : 0), put32(out, 0);
        put32(out, crc), put32(out, std::uint32_t(body.size())), put32(out, std::uint32_t(data.size()));
        put16(out, unsigned(name.size())), put16(out, 0);
        out += name + body;
        put32(cd, 0x02014b50), put16(cd, 20), put16(cd, 20), put16(cd, 0), put16(cd, deflated ? 8 : 0);
        put32(cd, 0), put32(cd, crc), put32(cd, std::uint32_t(body.size())),
            put32(cd, std::uint32_t(data.size()));
        put16(cd, unsigned(name.size())), put16(cd, 0), put16(cd, 0), put16(cd, 0), put16(cd, 0),
            put32(cd, 0);
        put32(cd, local);
        cd += name;
    }
    const std::uint32_t at = std::uint32_t(out.size());
    out += cd;
    put32(out, 0x06054b50), put16(out, 0), put16(out, 0), put16(out, unsigned(entries.size()));
    put16(out, unsigned(entries.size())), put32(out, std::uint32_t(cd.size())), put32(out, at), put16(out, 0);
    return out;
}

// Three Gaussians in 4x1 images, SH band 1 from a palette of two entries.
struct Sog {
    json meta;
    std::map<std::string, std::vector<unsigned char>> images;  // RGBA, 4x1 unless sized
    std::map<std::string, std::pair<int, int>> sizes;
    Sog() {
        std::vector<double> scale_book, dc_book, sh_book;
        for (int i = 0; i < 256; ++i) {
            scale_book.push_back(-5.0 + i * 0.01);
            dc_book.push_back((i - 128) / 100.0);
            sh_book.push_back((i - 128) / 256.0);
        }
        meta = {{"version", 2},
                {"count", 3},
                {"means",
                 {{"mins", {-1.0, 0.0, 0.5}},
                  {"maxs", {1.0, 0.0, 2.0}},
                  {"files", {"means_l.webp", "means_u.webp"}}}},
                {"scales", {{"codebook", scale_book}, {"files", {"scales.webp"}}}},
                {"quats", {{"files", {"quats.webp"}}}},
                {"sh0", {{"codebook", dc_book}, {"files", {"sh0.webp"}}}},
                {"shN",
                 {{"count", 2},
                  {"bands", 1},
                  {"codebook", sh_book},
                  {"files", {"shN_centroids.webp", "shN_labels.webp"}}}}};
        // means: q = 0, 65535, 0x8000 on every axis (lo, hi bytes)
        images["means_l.webp"] = {0, 0, 0, 255, 255, 255, 255, 255, 0x00, 0x00, 0x00, 255, 0, 0, 0, 255};
        images["means_u.webp"] = {0, 0, 0, 255, 255, 255, 255, 255, 0x80, 0x80, 0x80, 255, 0, 0, 0, 255};
        images["scales.webp"] = {0, 100, 200, 255, 255, 255, 255, 255, 10, 20, 30, 255, 0, 0, 0, 255};
        // w largest (tag 252) with small others; z largest (255); x largest (253) with y = 0.5
        const unsigned char half =
            static_cast<unsigned char>(std::lround((0.5 * std::sqrt(2.0) + 1) / 2 * 255));
        images["quats.webp"] = {128, 128, 128, 252, 128, 128, 128, 255, 128, half, 128, 253, 0, 0, 0, 255};
        images["sh0.webp"] = {128, 228, 28, 255, 0, 255, 128, 51, 100, 100, 100, 0, 0, 0, 0, 255};
        images["shN_labels.webp"] = {0, 0, 0, 255, 1, 0, 0, 255, 1, 0, 0, 255, 0, 0, 0, 255};
        // Palette: 64 entries of 3 texels a row (192 x 1); entry 0 = codebook index 128 + j, entry 1 = 100.
        std::vector<unsigned char> c(192 * 4, 128);
        for (int j = 0; j < 3; ++j)
            for (int ch = 0; ch < 3; ++ch)
                c[std::size_t(j * 4 + ch)] = static_cast<unsigned char>(128 + j + 1);
        for (int j = 3; j < 6; ++j)
            for (int ch = 0; ch < 3; ++ch) c[std::size_t(j * 4 + ch)] = 100;
        images["shN_centroids.webp"] = c;
        sizes["shN_centroids.webp"] = {192, 1};
    }
    std::map<std::string, std::string> files() const {
        std::map<std::string, std::string> f;
        f["meta.json"] = meta.dump();
        for (const auto& [name, rgba] : images) {
            auto it = sizes.find(name);
            const auto [w, h] = it == sizes.end() ? std::pair<int, int>(4, 1) : it->second;
            f[name] = webp(w, h, rgba);
        }
        return f;
    }
    fs::path archive(const std::string& name, bool deflate = false) const {
        const fs::path p = temp(name);
        std::ofstream(p, std::ios::binary) << zip(files(), deflate);
        return p;
    }
    fs::path folder(const std::string& name) const {
        const fs::path d = temp(name);
        fs::create_directories(d);
        for (const auto& [f, bytes] : files()) std::ofstream(d / f, std::ios::binary) << bytes;
        return d / "meta.json";
    }
};

void expect_refused(const fs::path& p, const std::string& part) {
    auto g = read_gaussians(p);
    ASSERT_FALSE(g) << p;
    EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
    EXPECT_NE(g.message().find(part), std::string::npos) << g.message();
}

TEST(Sog, HandBuiltArchiveAndFolderDecodeToKnownValues) {
    const Sog s;
    for (const fs::path& p : {s.archive("known.sog"), s.archive("deflated.sog", true), s.folder("known")}) {
        auto g = read_gaussians(p);
        ASSERT_TRUE(g) << g.message();
        ASSERT_EQ(g->size(), 3u);
        ASSERT_EQ(g->sh_degree, 1);
        auto x = [](double v) { return float(v < 0 ? -std::expm1(-v) : std::expm1(v)); };
        // Gaussian 0: q = 0 on every axis: the mins; a zero range (y) counts as 1.
        EXPECT_FLOAT_EQ(g->positions[0].x, x(-1.0));
        EXPECT_FLOAT_EQ(g->positions[0].y, 0.0f);
        EXPECT_FLOAT_EQ(g->positions[0].z, x(0.5));
        // Gaussian 1: q = 65535: the maxs (y: min + 1).
        EXPECT_FLOAT_EQ(g->positions[1].x, x(1.0));
        EXPECT_FLOAT_EQ(g->positions[1].y, x(1.0));
        EXPECT_FLOAT_EQ(g->positions[1].z, x(2.0));
        // Gaussian 2: q = 0x8000.
        EXPECT_NEAR(g->positions[2].x, x(-1.0 + 2.0 * 32768 / 65535), 1e-6);
        EXPECT_NEAR(g->scales[0].y, std::exp(-5.0 + 100 * 0.01), 1e-6);
        EXPECT_NEAR(g->scales[2].z, std::exp(-5.0 + 30 * 0.01), 1e-6);
        EXPECT_NEAR(g->opacities[0], 1.0f, 1e-6f);
        EXPECT_NEAR(g->opacities[1], 51 / 255.0f, 1e-6f);
        EXPECT_NEAR(g->opacities[2], 0.0f, 1e-6f);
        EXPECT_NEAR(g->sh[0], 0.0f, 1e-6f);   // DC: codebook[128]
        EXPECT_NEAR(g->sh[1], 1.0f, 1e-6f);   // codebook[228]
        EXPECT_NEAR(g->sh[2], -1.0f, 1e-6f);  // codebook[28]
        // Rotations: about identity; about z by 180 degrees; w and x equal-ish with y 0.5.
        EXPECT_GT(std::abs(g->rotations[0].w), 0.9999f);
        EXPECT_GT(std::abs(g->rotations[1].z), 0.9999f);
        EXPECT_NEAR(g->rotations[2].y, 0.5f, 0.004f);
        EXPECT_NEAR(g->rotations[2].x, std::sqrt(0.75f), 0.004f);
        // Band 1 from the palette: Gaussian 0 has entry 0 (coefficient j + 1 = codebook[128 + j + 1]),
        // Gaussians 1 and 2 entry 1 (codebook[100]).
        for (int j = 0; j < 3; ++j)
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(g->sh[std::size_t((1 + j) * 3 + c)], (j + 1) / 256.0f, 1e-6f) << j;
                EXPECT_NEAR(g->sh[std::size_t(12 + (1 + j) * 3 + c)], (100 - 128) / 256.0f, 1e-6f) << j;
            }
    }
}

// What `render` and `view` open (load_scene): a SOG archive, a SOG folder given as the folder or as its
// meta.json; and a refused type's message lists the Gaussian formats too.
TEST(Sog, SceneLoaderOpensArchiveFolderAndMetaJson) {
    const Sog s;
    const fs::path meta = s.folder("scene_folder");
    for (const fs::path& p : {s.archive("scene.sog"), meta, meta.parent_path()}) {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        ASSERT_TRUE(load_scene(r, p.string())) << p;
        ASSERT_EQ(r.count<GaussianCloud>(), 1u) << p;
        EXPECT_EQ(r.count<Camera>(), 1u) << p;
        r.view<const GaussianCloud, const Name>().each(
            [&](ecs::Entity, const GaussianCloud& g, const Name& n) {
                EXPECT_EQ(g.size(), 3u);
                EXPECT_EQ(n.value, p.extension() == ".sog" ? "scene" : "scene_folder") << p;
            });
    }
    const fs::path odd = temp("odd.xyz");
    std::ofstream(odd) << "1 2 3\n";
    ecs::Registry r;
    register_gaussian_scene_hooks(SceneHooks::in(r));
    const Status refused = load_scene(r, odd.string());
    ASSERT_FALSE(refused);
    for (const std::string& type :
         std::vector<std::string>{odd.string(), "unknown file type '.xyz'", ".ply", ".glb", ".spz", ".splat",
                                  ".ksplat", ".sog", "meta.json"})
        EXPECT_NE(refused.message().find(type), std::string::npos) << type << " in " << refused.message();
}

TEST(Sog, RefusesBadFiles) {
    {
        Sog s;
        s.images["quats.webp"][3] = 10;
        expect_refused(s.archive("tag.sog"), "quaternion tag 10");
    }
    {
        Sog s;
        s.images["shN_labels.webp"][0] = 2;
        expect_refused(s.archive("label.sog"), "label 2 beyond the palette of 2");
    }
    {
        Sog s;
        s.meta["count"] = 5;
        expect_refused(s.archive("small.sog"), "4x1 texels for 5 Gaussians");
    }
    {
        Sog s;
        s.meta["count"] = 0;
        s.images["sh0.webp"].resize(400 * 200 * 4);
        s.sizes["sh0.webp"] = {400, 200};
        s.meta["shN"]["count"] = 0;
        expect_refused(s.archive("big.sog"), "far more than 0 Gaussians need");
    }
    {
        Sog s;
        s.images["shN_centroids.webp"].resize(191 * 4);
        s.sizes["shN_centroids.webp"] = {191, 1};
        expect_refused(s.archive("centroids.sog"), "191 texels wide; the palette needs 192");
    }
    {
        Sog s;
        s.meta["quats"]["files"] = {"../quats.webp"};
        expect_refused(s.folder("escape"), "is not a plain file name");
    }
    {
        Sog s;
        s.meta.erase("version");
        s.meta["means"]["shape"] = {3, 3};
        expect_refused(s.archive("v1.sog"), "SOG version 1");
    }
    {
        Sog s;
        s.meta["version"] = 3;
        expect_refused(s.archive("v3.sog"), "SOG version 3 is not read");
    }
    {
        Sog s;
        s.meta["scales"]["codebook"].erase(0);
        expect_refused(s.archive("book.sog"), "scales.codebook must be 256 finite numbers");
    }
    {
        Sog s;
        s.meta["count"] = std::uint64_t(1) << 40;
        expect_refused(s.archive("count.sog"), "more than the 67108864 limit");
    }
    {
        Sog s;
        s.meta["shN"]["bands"] = 4;
        expect_refused(s.archive("bands.sog"), "shN.bands must be 1, 2 or 3");
    }
    {
        // A corrupt image behind a valid header: libwebp's decode fails.
        Sog s;
        auto f = s.files();
        std::string& w = f["scales.webp"];
        w = w.substr(0, w.size() / 2 + 10);
        const fs::path p = temp("webp.sog");
        std::ofstream(p, std::ios::binary) << zip(f);
        expect_refused(p, "scales.webp");
    }
    {
        // The archive: a flipped data byte fails the CRC-32, a cut file has no end record.
        const std::string good = zip(Sog().files());
        std::string b = good;
        b[50] ^= 1;  // inside the first entry's data (30-byte header, 12-byte name)
        std::ofstream(temp("crc.sog"), std::ios::binary) << b;
        expect_refused(temp("crc.sog"), "CRC-32 does not match");
        std::ofstream(temp("cut.sog"), std::ios::binary) << good.substr(0, good.size() - 30);
        expect_refused(temp("cut.sog"), "no end of central directory record");
        std::ofstream(temp("text.sog"), std::ios::binary) << "not a zip at all, just text";
        expect_refused(temp("text.sog"), "not a ZIP archive");
    }
    {
        Sog s;
        auto f = s.files();
        f.erase("meta.json");
        const fs::path p = temp("nometa.sog");
        std::ofstream(p, std::ios::binary) << zip(f);
        expect_refused(p, "no entry 'meta.json'");
    }
}

}  // namespace
