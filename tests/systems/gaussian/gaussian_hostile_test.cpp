// Hostile Gaussian files: each class of failure a hostile user found in the Gaussian readers, as a test
// that failed before the fix (crash, hang, read outside the folder, silent garbage), and every format
// truncated at every byte (an error naming the file or a valid cloud, never a crash).
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/core/json_text.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;
using namespace sffd::gaussian;

fs::path temp_dir() {
    const fs::path d = fs::temp_directory_path() / ("sffd_gauss_hostile_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
}
fs::path temp(const std::string& name) { return temp_dir() / name; }

void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// Refused, with the file's name and `fragment` in the message.
void expect_refused(const fs::path& p, const std::string& fragment) {
    auto g = read_gaussians(p);
    ASSERT_FALSE(g) << p << " was accepted";
    EXPECT_NE(g.message().find(p.string()), std::string::npos) << g.message();
    EXPECT_NE(g.message().find(fragment), std::string::npos) << g.message();
}

// An ASCII 3DGS PLY (degree 0) with double properties and one row per entry of `rows`
// (x y z f_dc_0 f_dc_1 f_dc_2 opacity scale_0 scale_1 scale_2 rot_0 rot_1 rot_2 rot_3).
void write_ascii_ply(const fs::path& p, const std::vector<std::string>& rows) {
    std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(rows.size()) + "\n";
    for (const char* n : {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1",
                          "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
        s += std::string("property double ") + n + "\n";
    s += "end_header\n";
    for (const std::string& r : rows) s += r + "\n";
    write_bytes(p, s);
}
const std::string kRow = "0 0 0 0.1 0.2 0.3 0 -2 -2 -2 1 0 0 0";

// --- silent garbage: one validation after all transforms -------------------------------------------

TEST(GaussianHostile, AbsurdOrOverflowingValuesAreRefusedWithFileRowAndField) {
    write_ascii_ply(temp("x_1e300.ply"), {kRow, "1e300 0 0 0.1 0.2 0.3 0 -2 -2 -2 1 0 0 0"});
    expect_refused(temp("x_1e300.ply"), "Gaussian 1: position.x");
    write_ascii_ply(temp("x_1e30.ply"), {"1e30 0 0 0.1 0.2 0.3 0 -2 -2 -2 1 0 0 0"});
    expect_refused(temp("x_1e30.ply"),
                   "Gaussian 0: position.x = 1.00000002e+30: beyond the +-1e10 coordinate bound");
    write_ascii_ply(temp("dc_1e300.ply"), {"0 0 0 1e300 0.2 0.3 0 -2 -2 -2 1 0 0 0"});
    expect_refused(temp("dc_1e300.ply"), "Gaussian 0: sh[0].r");
    write_ascii_ply(temp("logscale_87.ply"), {"0 0 0 0.1 0.2 0.3 0 87 -2 -2 1 0 0 0"});
    expect_refused(temp("logscale_87.ply"), "Gaussian 0: scale.x");
}

TEST(GaussianHostile, HugeQuaternionComponentsNormaliseInsteadOfCollapsing) {
    write_ascii_ply(temp("rot_1e200.ply"), {"0 0 0 0.1 0.2 0.3 0 -2 -2 -2 1e200 0 0 1e200"});
    auto g = read_gaussians(temp("rot_1e200.ply"));
    ASSERT_TRUE(g) << g.message();
    EXPECT_NEAR(g->rotations[0].w, std::sqrt(0.5f), 1e-6f);
    EXPECT_NEAR(g->rotations[0].z, std::sqrt(0.5f), 1e-6f);
}

// --- KHR glTF: node graph, scenes, SH bands, accessors, detection ------------------------------------

std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const unsigned v = unsigned((unsigned char)in[i]) << 16 | unsigned((unsigned char)in[i + 1]) << 8 |
                           (unsigned char)in[i + 2];
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += t[v >> 6 & 63], out += t[v & 63];
    }
    if (i + 1 == in.size()) {
        const unsigned v = unsigned((unsigned char)in[i]) << 16;
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += "==";
    } else if (i + 2 == in.size()) {
        const unsigned v = unsigned((unsigned char)in[i]) << 16 | unsigned((unsigned char)in[i + 1]) << 8;
        out += t[v >> 18 & 63], out += t[v >> 12 & 63], out += t[v >> 6 & 63], out += '=';
    }
    return out;
}

const std::string K = "KHR_gaussian_splatting:";

// One Gaussian primitive (mesh 0) with the given extra attributes; `nodes` and `scenes` are raw JSON.
std::string khr_gltf(const std::string& nodes, const std::string& scenes,
                     const std::vector<std::string>& extra_sh = {},
                     const std::string& extra_attributes = "") {
    struct A {
        std::string name, type;
        std::vector<float> v;
    };
    std::vector<A> attrs = {{"POSITION", "VEC3", {1, 0, 0}},
                            {K + "ROTATION", "VEC4", {0, 0, 0, 1}},
                            {K + "SCALE", "VEC3", {0.1f, 0.2f, 0.3f}},
                            {K + "OPACITY", "SCALAR", {0.5f}},
                            {K + "SH_DEGREE_0_COEF_0", "VEC3", {0, 0, 0}}};
    for (const std::string& s : extra_sh) attrs.push_back({K + s, "VEC3", {0, 0, 0}});
    std::string bin, views, accessors, attributes;
    for (std::size_t a = 0; a < attrs.size(); ++a) {
        const std::size_t comps = attrs[a].type == "SCALAR" ? 1 : attrs[a].type == "VEC3" ? 3 : 4;
        const std::size_t off = bin.size();
        bin.append(reinterpret_cast<const char*>(attrs[a].v.data()), attrs[a].v.size() * 4);
        const std::string sep = a ? "," : "";
        views += sep + "{\"buffer\":0,\"byteOffset\":" + std::to_string(off) +
                 ",\"byteLength\":" + std::to_string(attrs[a].v.size() * 4) + "}";
        accessors += sep + "{\"bufferView\":" + std::to_string(a) +
                     ",\"componentType\":5126,\"count\":" + std::to_string(attrs[a].v.size() / comps) +
                     ",\"type\":\"" + attrs[a].type + "\"" +
                     (attrs[a].name == "POSITION" ? ",\"min\":[1,0,0],\"max\":[1,0,0]" : "") + "}";
        attributes += sep + "\"" + attrs[a].name + "\":" + std::to_string(a);
    }
    return "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_gaussian_splatting\"]," + scenes +
           "\"nodes\":" + nodes + ",\"meshes\":[{\"primitives\":[{\"mode\":0,\"attributes\":{" + attributes +
           extra_attributes +
           "},\"extensions\":{\"KHR_gaussian_splatting\":{\"kernel\":\"ellipse\"}}}]}],"
           "\"buffers\":[{\"byteLength\":" +
           std::to_string(bin.size()) + ",\"uri\":\"data:application/octet-stream;base64," + base64(bin) +
           "\"}],\"bufferViews\":[" + views + "],\"accessors\":[" + accessors + "]}";
}

TEST(GaussianHostile, NodeDagIsRefusedQuicklyInsteadOfExponentialWork) {
    // 40 nodes, each listing the next one twice: 2^40 paths before the fix.
    std::string nodes = "[";
    for (int i = 0; i < 40; ++i)
        nodes += "{\"children\":[" + std::to_string(i + 1) + "," + std::to_string(i + 1) + "]},";
    nodes += "{\"mesh\":0}]";
    write_bytes(temp("dag.gltf"), khr_gltf(nodes, "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"));
    expect_refused(temp("dag.gltf"), "at most one parent");
}

TEST(GaussianHostile, GltfWithoutScenesVisitsOnlyRootNodes) {
    // Node 0 is the parent of node 1, which holds the cloud: without `scenes` only node 0 is a root, so
    // the Gaussian appears once (twice before the fix), moved by both translations.
    write_bytes(
        temp("noscene.gltf"),
        khr_gltf("[{\"children\":[1],\"translation\":[0,5,0]},{\"mesh\":0,\"translation\":[0,0,2]}]", ""));
    auto g = read_gaussians(temp("noscene.gltf"));
    ASSERT_TRUE(g) << g.message();
    ASSERT_EQ(g->size(), 1u);
    // (1, 5, 2) in glTF's frame is (-1, -5, 2) in the internal one (turned 180 degrees about z).
    EXPECT_EQ(glm::vec3(glm::dvec3(g->positions[0]) + g->origin), glm::vec3(-1, -5, 2));
}

TEST(GaussianHostile, ShDegreeTwoWithoutDegreeOneIsRefused) {
    std::vector<std::string> band2;
    for (int c = 0; c < 5; ++c) band2.push_back("SH_DEGREE_2_COEF_" + std::to_string(c));
    write_bytes(temp("sh2.gltf"),
                khr_gltf("[{\"mesh\":0}]", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],", band2));
    expect_refused(temp("sh2.gltf"), "SH degree 2 coefficients without degree 1");
}

TEST(GaussianHostile, NodeScaleThatOverflowsIsRefused) {
    write_bytes(temp("scale1e30.gltf"), khr_gltf("[{\"mesh\":0,\"scale\":[1e30,1e30,1e30]}]",
                                                 "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"));
    expect_refused(temp("scale1e30.gltf"), "Gaussian 0:");
}

TEST(GaussianHostile, ExtensionDeclarationDecidesDetectionNotASubstring) {
    const std::string good = khr_gltf("[{\"mesh\":0}]", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],");
    write_bytes(temp("declared.gltf"), good);
    EXPECT_TRUE(gltf_declaration(temp("declared.gltf")).gaussian_splatting);
    EXPECT_TRUE(is_gaussian_scene_file(temp("declared.gltf")));
    // A surface glTF whose node is merely named after the extension is not a Gaussian file.
    write_bytes(temp("named.gltf"),
                "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"name\":\"KHR_gaussian_splatting\"}]}");
    EXPECT_FALSE(gltf_declaration(temp("named.gltf")).gaussian_splatting);
    EXPECT_FALSE(is_gaussian_scene_file(temp("named.gltf")));
    // A declared file that the Gaussian reader refuses is still declared (read as Gaussians or refused).
    std::string broken = good;
    broken.replace(broken.find("\"" + K + "OPACITY\":3"), K.size() + 11, "\"" + K + "OPACITY\":99");
    write_bytes(temp("declared_broken.gltf"), broken);
    EXPECT_TRUE(gltf_declaration(temp("declared_broken.gltf")).gaussian_splatting);
    expect_refused(temp("declared_broken.gltf"), "OPACITY");
}

TEST(GaussianHostile, ColorAccessorIndexOutOfRangeIsAnError) {
    // No SH_DEGREE_0_COEF_0, COLOR_0 naming accessor 99.
    std::string text =
        khr_gltf("[{\"mesh\":0}]", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],", {}, ",\"COLOR_0\":99");
    text.replace(text.find("\"" + K + "SH_DEGREE_0_COEF_0\":4,"), K.size() + 23, "");
    write_bytes(temp("color99.gltf"), text);
    expect_refused(temp("color99.gltf"), "COLOR_0");
}

// --- SPZ: budgets, CRC, decoded length -------------------------------------------------------------

void put32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(char((v >> (8 * i)) & 0xff));
}

std::string gzip(const std::string& bytes) {
    z_stream z{};
    EXPECT_EQ(deflateInit2(&z, 9, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&z, uLong(bytes.size())) + 64, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    z.avail_in = uInt(bytes.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

// A valid v2 SPZ payload of `n` splats (degree 0).
std::string spz_payload(std::uint32_t declared, std::uint32_t n) {
    std::string s;
    put32(s, 0x5053474e), put32(s, 2), put32(s, declared);
    s += char(0), s += char(12), s += char(0), s += char(0);
    s += std::string(std::size_t(n) * 9, '\0');       // positions
    s += std::string(n, char(200));                   // alphas
    s += std::string(std::size_t(n) * 3, char(128));  // colours
    s += std::string(std::size_t(n) * 3, char(140));  // scales
    s += std::string(std::size_t(n) * 3, char(128));  // rotations
    return s;
}

TEST(GaussianHostile, SpzChecksCrcLengthAndBudgetBeforeAllocating) {
    write_bytes(temp("ok.spz"), gzip(spz_payload(4, 4)));
    ASSERT_TRUE(read_gaussians(temp("ok.spz")));
    // The CRC-32 in the gzip trailer (the 8 bytes before the length): one bit flipped.
    std::string bad_crc = gzip(spz_payload(4, 4));
    bad_crc[bad_crc.size() - 8] = char(bad_crc[bad_crc.size() - 8] ^ 1);
    write_bytes(temp("crc.spz"), bad_crc);
    expect_refused(temp("crc.spz"), "corrupt gzip stream");
    // More decoded data than the header declares.
    write_bytes(temp("long.spz"), gzip(spz_payload(4, 5)));
    expect_refused(temp("long.spz"), "longer than the header declares");
    // A count past the Gaussian budget, in a file large enough (incompressible bytes) to pass the
    // compression-ratio check, is refused before anything is allocated.
    std::string noise(std::size_t(1400) << 10, '\0');
    std::mt19937 rng(3);
    for (char& c : noise) c = char(rng() & 0xff);
    write_bytes(temp("budget.spz"), gzip(spz_payload((1u << 26) + 1, 0) + noise));
    expect_refused(temp("budget.spz"), "67108864-Gaussian");
    // A count the data does not hold.
    write_bytes(temp("short.spz"), gzip(spz_payload(4, 3)));
    expect_refused(temp("short.spz"), "truncated");
}

// Raw deflate of `bytes` ending in a full flush: byte-aligned, non-final blocks that refer to nothing
// before them, so such pieces concatenate into one valid stream.
std::string deflate_piece(const std::string& bytes, int flush) {
    z_stream z{};
    EXPECT_EQ(deflateInit2(&z, 9, Z_DEFLATED, -MAX_WBITS, 9, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&z, uLong(bytes.size())) + 64, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    z.avail_in = uInt(bytes.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&z, flush), flush == Z_FINISH ? Z_STREAM_END : Z_OK);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

// A valid gzipped SPZ v3 of degree 0 declaring `n` splats, all zeros (20 bytes each): the deflate
// stream of `pieces` identical runs of zeros, built from one compressed piece so the test does not
// deflate a gigabyte.
std::string zero_spz_v3(std::uint32_t n, std::uint32_t pieces) {
    std::string header;
    put32(header, 0x5053474e), put32(header, 3), put32(header, n);
    header += std::string("\0\x0c\0\0", 4);
    const std::uint64_t total = std::uint64_t(n) * 20;
    EXPECT_EQ(total % pieces, 0u);
    const std::string zeros(std::size_t(total / pieces), '\0');
    const std::string piece = deflate_piece(zeros, Z_FULL_FLUSH);
    std::string out("\x1f\x8b\x08\0\0\0\0\0\0\x03", 10);
    out += deflate_piece(header, Z_FULL_FLUSH);
    uLong crc = crc32(0, reinterpret_cast<const Bytef*>(header.data()), uInt(header.size()));
    const uLong piece_crc = crc32(0, reinterpret_cast<const Bytef*>(zeros.data()), uInt(zeros.size()));
    for (std::uint32_t i = 0; i < pieces; ++i)
        out += piece, crc = crc32_combine(crc, piece_crc, z_off_t(zeros.size()));
    out += deflate_piece("", Z_FINISH);
    put32(out, std::uint32_t(crc)), put32(out, std::uint32_t(header.size() + total));
    return out;
}

// What gunzip says of `gz`: the decoded length, or -1 when the stream or its trailer is bad.
std::int64_t gunzipped_size(const std::string& gz) {
    z_stream z{};
    EXPECT_EQ(inflateInit2(&z, 16 + MAX_WBITS), Z_OK);
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
    z.avail_in = uInt(gz.size());
    std::vector<unsigned char> sink(1 << 20);
    int rc = Z_OK;
    while (rc == Z_OK) {
        z.next_out = sink.data(), z.avail_out = uInt(sink.size());
        rc = inflate(&z, Z_NO_FLUSH);
    }
    const std::int64_t out = rc == Z_STREAM_END ? std::int64_t(z.total_out) : -1;
    inflateEnd(&z);
    return out;
}

TEST(GaussianHostile, SpzOfZerosDeclaringFiftyMillionSplatsIsRefusedUnderThreeGigabytes) {
    // 50M splats of zeros: 1e9 decoded bytes in under 1 MB of valid gzip (deflate's ratio on zeros is
    // ~1030:1). Decoded, the cloud alone would take 2.8 GB.
    const std::string gz = zero_spz_v3(50'000'000, 20);
    ASSERT_EQ(gunzipped_size(gz), std::int64_t(16) + 1'000'000'000);
    ASSERT_LT(gz.size(), std::size_t(1) << 20);
    const fs::path p = temp("zeros50m.spz");
    write_bytes(p, gz);
    // Read in a child under a 3 GB address-space limit, as the review ran it; the child reports the
    // message through a pipe. (ASan reserves terabytes of address space: no limit under it.)
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        close(fds[0]);
#if !defined(__SANITIZE_ADDRESS__)
        const rlimit limit{rlim_t(3) << 30, rlim_t(3) << 30};
        if (setrlimit(RLIMIT_AS, &limit) != 0) _exit(4);
#endif
        // Nothing may return to gtest from here: an exception would run the remaining tests in the child.
        std::string msg = "accepted";
        int rc = 3;
        try {
            auto g = read_gaussians(p);
            if (!g) msg = g.message(), rc = 0;
        } catch (const std::exception& e) {
            msg = std::string("threw ") + e.what(), rc = 6;
        }
        if (write(fds[1], msg.data(), msg.size()) < 0) _exit(5);
        _exit(rc);
    }
    close(fds[1]);
    std::string msg;
    char buf[512];
    for (ssize_t got; (got = read(fds[0], buf, sizeof buf)) > 0;) msg.append(buf, std::size_t(got));
    close(fds[0]);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << "the reader died (signal " << WTERMSIG(status) << ")";
    EXPECT_EQ(WEXITSTATUS(status), 0) << msg;
    EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("declares 50000000 splats (1000000000 decoded bytes)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1024:1 limit"), std::string::npos) << msg;
}

TEST(GaussianHostile, SpzRatioBoundRefusesZerosAndReadsRealData) {
    // The bound from both sides: incompressible splats are read, 1M splats of zeros (20 MB in ~19 KB,
    // past 1024:1) are refused before anything is inflated.
    std::string varied;
    put32(varied, 0x5053474e), put32(varied, 3), put32(varied, 100'000);
    varied += std::string("\0\x0c\0\0", 4);
    std::mt19937 rng(5);
    for (std::size_t i = 0; i < std::size_t(100'000) * 20; ++i) varied += char(rng() & 0xff);
    write_bytes(temp("varied.spz"), gzip(varied));
    EXPECT_TRUE(read_gaussians(temp("varied.spz")));
    write_bytes(temp("zeros1m.spz"), zero_spz_v3(1'000'000, 1));
    expect_refused(temp("zeros1m.spz"), "1024:1 limit");
}

// --- deformation: the CPU path agrees with the GPU path on non-finite results -----------------------

TEST(GaussianHostile, CpuDeformationDropsAndCountsNonFiniteResults) {
    GaussianCloud g;
    g.sh_degree = 1;
    for (int i = 0; i < 8; ++i) {
        g.positions.emplace_back(0.5e-12f, 0.5e-12f, 1e-12f * float(i + 1) / 9.0f);
        g.scales.emplace_back(1e-13f);
        g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        g.opacities.push_back(0.8f);
        for (int k = 0; k < 12; ++k) g.sh.push_back(0.1f);
    }
    // A 1e-12 box with one control point moved by 1e29: the Jacobian (~1e41) passes the float range.
    Lattice l = make_lattice(
        {0, 0, 0}, {glm::dvec3(1e-12, 0, 0), glm::dvec3(0, 1e-12, 0), glm::dvec3(0, 0, 1e-12)}, {1, 1, 1});
    l.current[l.index(1, 1, 1)] += glm::dvec3(1e29, -1e29, 1e29);
    // Both CPU kernels: the vectorised float one (the GPU pass's arithmetic) and the double reference.
    for (bool reference : {false, true}) {
        GaussianCloud out;
        out.opacities = g.opacities;
        DeformOptions options;
        options.backend = ffd::Backend::reference, options.copy_opacities = false,
        options.reference_shapes = reference;
        auto st = deform(l, g, out, options);
        ASSERT_TRUE(st) << st.message();
        EXPECT_GT(st->not_finite, 0u) << "reference kernel: " << reference;
        std::size_t transparent = 0;
        for (std::size_t i = 0; i < out.size(); ++i) {
            const glm::quat q = out.rotations[i];
            EXPECT_TRUE(std::isfinite(q.w + q.x + q.y + q.z)) << i;
            EXPECT_TRUE(std::isfinite(out.scales[i].x + out.scales[i].y + out.scales[i].z)) << i;
            EXPECT_TRUE(std::isfinite(out.positions[i].x + out.positions[i].y + out.positions[i].z)) << i;
            for (int k = 0; k < 12; ++k) EXPECT_TRUE(std::isfinite(out.sh[i * 12 + std::size_t(k)])) << i;
            transparent += out.opacities[i] == 0.0f;
        }
        EXPECT_EQ(transparent, st->not_finite) << "reference kernel: " << reference;
    }
}

// --- folder confinement of scene entries ------------------------------------------------------------

TEST(GaussianHostile, SceneEntryOutsideTheFolderNeedsAllowOutsideResources) {
    const fs::path root = temp_dir() / "confine";
    fs::create_directories(root / "scene"), fs::create_directories(root / "outside");
    write_ascii_ply(root / "outside" / "g.ply", {kRow});
    write_ascii_ply(root / "scene" / "inside.ply", {kRow});
    // A scene that refers to ../outside/g.ply (saved with the entity loaded from there).
    {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        ASSERT_TRUE(load_scene(r, (root / "outside" / "g.ply").string()));
        ASSERT_TRUE(save_scene(r, root / "scene" / "s.gltf"));
    }
    ASSERT_NE(read_bytes(root / "scene" / "s.gltf").find("../outside/g.ply"), std::string::npos);
    {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        auto s = load_scene(r, (root / "scene" / "s.gltf").string());
        ASSERT_FALSE(s);
        EXPECT_NE(s.message().find("outside the file's folder"), std::string::npos) << s.message();
    }
    set_allow_outside_resources(true);
    {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        auto s = load_scene(r, (root / "scene" / "s.gltf").string());
        EXPECT_TRUE(s) << s.message();
    }
    set_allow_outside_resources(false);
    // A symlink inside the folder that leads out is refused too; one that stays inside is read.
    fs::create_symlink(root / "outside" / "g.ply", root / "scene" / "link.ply");
    std::string text = read_bytes(root / "scene" / "s.gltf");
    const std::string from = "../outside/g.ply";
    text.replace(text.find(from), from.size(), "link.ply");
    write_bytes(root / "scene" / "s_link.gltf", text);
    {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        auto s = load_scene(r, (root / "scene" / "s_link.gltf").string());
        ASSERT_FALSE(s);
        EXPECT_NE(s.message().find("outside the file's folder"), std::string::npos) << s.message();
    }
    text.replace(text.find("link.ply"), 8, "inside.ply");
    write_bytes(root / "scene" / "s_inside.gltf", text);
    {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        auto s = load_scene(r, (root / "scene" / "s_inside.gltf").string());
        EXPECT_TRUE(s) << s.message();
    }
}

// --- automatic camera ------------------------------------------------------------------------------

TEST(GaussianHostile, DefaultCameraStaysOutsideCoincidentOrHugeGaussians) {
    // Three Gaussians at one point, sigma e^0 = 1: the camera must be further than 3 sigma away.
    write_ascii_ply(temp("coincident.ply"), {"2 3 4 0 0 0 0 0 0 0 1 0 0 0", "2 3 4 0 0 0 0 0 0 0 1 0 0 0",
                                             "2 3 4 0 0 0 0 0 0 0 1 0 0 0"});
    ecs::Registry r;
    register_gaussian_scene_hooks(SceneHooks::in(r));
    ASSERT_TRUE(load_scene(r, temp("coincident.ply").string()));
    bool found = false;
    r.view<Camera>().each([&](const Camera& c) {
        found = true;
        const double d = glm::length(c.eye - glm::dvec3(2, 3, 4));
        EXPECT_GT(d, 3.0);
        EXPECT_LT(double(c.near_plane), d - 3.0);
    });
    EXPECT_TRUE(found);
}

// --- outputs: long names, UTF-8 ---------------------------------------------------------------------

TEST(GaussianHostile, AtomicSaveAcceptsAnOutputNameNearNameMax) {
    const fs::path p = temp_dir() / (std::string(246, 'n') + ".ply");  // 250 bytes
    ASSERT_TRUE(write_file_atomic(p, std::string("x"))) << p;
    EXPECT_EQ(read_bytes(p), "x");
    // Saved again: the shortened temporary is still found and replaced cleanly.
    ASSERT_TRUE(write_file_atomic(p, std::string("y")));
    EXPECT_EQ(read_bytes(p), "y");
    std::size_t entries = 0;
    for (const auto& e : fs::directory_iterator(temp_dir()))
        entries += e.path().filename().string().find("sffd-tmp") != std::string::npos;
    EXPECT_EQ(entries, 0u);
}

TEST(GaussianHostile, JsonTextIsValidUtf8) {
    const std::string raw = std::string("a\xff") + "b\xc3\xa9" + "\xed\xa0\x80" + "\"\n" + "\xf0\x9f\x98";
    const std::string quoted = json_quote(raw);
    const nlohmann::json j = nlohmann::json::parse(quoted, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << quoted;
    EXPECT_EQ(j.get<std::string>(),
              "a\xEF\xBF\xBD"
              "b\xc3\xa9"
              "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD"
              "\"\n"
              "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD");
    EXPECT_EQ(valid_utf8("plain \xc3\xa9"), "plain \xc3\xa9");
}

// --- every format truncated at every byte -----------------------------------------------------------

void truncate_everywhere(const fs::path& full, const std::string& ext) {
    const std::string bytes = read_bytes(full);
    ASSERT_FALSE(bytes.empty());
    const fs::path cut = temp("cut" + ext);
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        write_bytes(cut, bytes.substr(0, n));
        auto g = read_gaussians(cut);
        if (g) {
            EXPECT_TRUE(validate(*g, "cut")) << ext << " at " << n;
        } else {
            EXPECT_NE(g.message().find(cut.string()), std::string::npos)
                << ext << " at " << n << ": " << g.message();
        }
    }
}

GaussianCloud small_cloud(int degree) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (int i = 0; i < 3; ++i) {
        g.positions.emplace_back(u(rng), u(rng), u(rng));
        g.scales.emplace_back(0.1f, 0.2f, 0.05f);
        g.rotations.push_back(glm::normalize(glm::quat(1.0f, u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.5f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.3f * u(rng));
    }
    return g;
}

TEST(GaussianHostile, EveryFormatTruncatedAtEveryByte) {
    const GaussianCloud g = small_cloud(1);
    ASSERT_TRUE(write_ply(temp("full.ply"), g));
    truncate_everywhere(temp("full.ply"), ".ply");
    ASSERT_TRUE(write_ply(temp("full_ascii.ply"), g, ply::Format::ascii));
    truncate_everywhere(temp("full_ascii.ply"), ".ply");
    ASSERT_TRUE(write_glb(temp("full.glb"), g));
    truncate_everywhere(temp("full.glb"), ".glb");
    write_bytes(temp("full.gltf"), khr_gltf("[{\"mesh\":0}]", "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"));
    truncate_everywhere(temp("full.gltf"), ".gltf");
    write_bytes(temp("full.spz"), gzip(spz_payload(3, 3)));
    truncate_everywhere(temp("full.spz"), ".spz");
    std::string splat;
    for (int i = 0; i < 3; ++i) {
        const float f[6] = {float(i), 0, 0, 0.1f, 0.1f, 0.1f};
        splat.append(reinterpret_cast<const char*>(f), sizeof f);
        splat += "\x80\x80\x80\xc0\xff\x80\x80\x80";
    }
    write_bytes(temp("full.splat"), splat);
    truncate_everywhere(temp("full.splat"), ".splat");
}

TEST(GaussianHostile, SceneFileTruncatedAtEveryByte) {
    ecs::Registry r;
    register_gaussian_scene_hooks(SceneHooks::in(r));
    const ecs::Entity e = r.create();
    r.emplace<Name>(e, Name{"g"});
    r.emplace<Transform>(e, Transform{});
    r.emplace<GaussianCloud>(e, small_cloud(0));
    const fs::path scene = temp("embedded.glb");
    ASSERT_TRUE(save_scene(r, scene));
    const std::string bytes = read_bytes(scene);
    const fs::path cut = temp("cut_scene.glb");
    for (std::size_t n = 0; n < bytes.size(); n += 1) {
        write_bytes(cut, bytes.substr(0, n));
        ecs::Registry back;
        register_gaussian_scene_hooks(SceneHooks::in(back));
        auto s = load_scene(back, cut.string());
        if (!s) {
            EXPECT_NE(s.message().find(cut.string()), std::string::npos) << n << ": " << s.message();
        }
    }
}

}  // namespace
