// Hostile files: resources named by a file resolve only inside its folder, FIFOs are never
// opened for reading, JSON nesting is bounded before any parser, declared sizes are budgeted before
// anything is decoded or expanded, scene fields that cannot be rendered are refused, and saving goes
// through mkstemp temporaries that keep permissions and refuse non-regular outputs. Every case asserts
// on the message (`file: problem`).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <functional>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/ecs/registry.h"
#include "systems/ffd/lattice_io.h"
#include "tests/assets/test_util.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

// A fresh folder per test: <tmp>/sffd_hostile_<pid>/<name>.
fs::path fresh_dir(const std::string& name) { return test::fresh_dir("hostile", name); }
using test::slurp;
using test::write;

// 3 ubyte VEC3 POSITIONs (9 bytes) read from the buffer at `uri`: the issue's exfiltration file.
std::string gltf_with_buffer(const std::string& uri, int byte_length = 9) {
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
  "meshes":[{"primitives":[{"mode":0,"attributes":{"POSITION":0}}]}],
  "accessors":[{"bufferView":0,"componentType":5121,"count":3,"type":"VEC3"}],
  "bufferViews":[{"buffer":0,"byteLength":9}],
  "buffers":[{"uri":")" +
           uri + R"(","byteLength":)" + std::to_string(byte_length) + "}]}";
}

// A glTF whose triangle's material has a base-colour texture from image `uri`, repeated `images` times.
std::string gltf_with_images(const std::string& uri, int images) {
    std::string imgs, texs;
    for (int i = 0; i < images; ++i) {
        imgs += std::string(i ? "," : "") + R"({"uri":")" + uri + R"("})";
        texs += std::string(i ? "," : "") + R"({"source":)" + std::to_string(i) + "}";
    }
    return R"({"asset":{"version":"2.0"},"images":[)" + imgs + R"(],"textures":[)" + texs + R"(],
  "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}]})";
}

std::string secret() { return "SECRET-bytes-123"; }

// A PNG that is only a signature and an IHDR chunk declaring w x h RGBA8 (CRC is not checked by stb's
// header scan): enough for the declared-size budget, and no data to decode.
std::string png_header(std::uint32_t w, std::uint32_t h) {
    std::string s("\x89PNG\r\n\x1a\n", 8);
    auto be32 = [&](std::uint32_t v) {
        for (int k = 3; k >= 0; --k) s.push_back(static_cast<char>((v >> (8 * k)) & 255u));
    };
    be32(13);
    s += "IHDR";
    be32(w);
    be32(h);
    s += std::string("\x08\x06\x00\x00\x00", 5);
    be32(0);  // CRC
    return s;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// glTF buffers and images

TEST(HostileGltf, BufferUriWithDotDotIsRefusedAndNothingIsRead) {
    const fs::path root = fresh_dir("gltf_dotdot");
    write(root / "x" / "secret.txt", secret());
    for (const std::string uri :
         {"../../x/secret.txt", "%2e%2e/%2e%2e/x/secret.txt", "sub/../../../x/secret.txt"}) {
        const fs::path file = root / "a" / "b" / "exfil.gltf";
        write(file, gltf_with_buffer(uri, static_cast<int>(secret().size())));
        auto g = assets::read_gltf_geometry(file);
        ASSERT_FALSE(g.ok()) << uri;
        EXPECT_NE(g.message().find(file.string() + ": resource '"), std::string::npos) << g.message();
        EXPECT_NE(g.message().find("is outside the file's folder"), std::string::npos) << g.message();
    }
}

TEST(HostileGltf, AbsoluteBufferUriIsRefused) {
    const fs::path root = fresh_dir("gltf_abs");
    write(root / "secret.txt", secret());
    const fs::path file = root / "a" / "abs.gltf";
    write(file, gltf_with_buffer((root / "secret.txt").string(), static_cast<int>(secret().size())));
    auto g = assets::read_gltf_geometry(file);
    ASSERT_FALSE(g.ok());
    EXPECT_NE(
        g.message().find("resource '" + (root / "secret.txt").string() + "' is outside the file's folder"),
        std::string::npos)
        << g.message();
    // A wrong byteLength no longer reveals another file's size either.
    EXPECT_EQ(g.message().find("File size mismatch"), std::string::npos) << g.message();
}

TEST(HostileGltf, SymlinkLeadingOutOfTheFolderIsRefused) {
    const fs::path root = fresh_dir("gltf_link");
    write(root / "secret.txt", secret());
    fs::create_directories(root / "a");
    fs::create_symlink(root / "secret.txt", root / "a" / "data.bin");
    const fs::path file = root / "a" / "link.gltf";
    write(file, gltf_with_buffer("data.bin", static_cast<int>(secret().size())));
    auto g = assets::read_gltf_geometry(file);
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.message().find(file.string() + ": resource 'data.bin' is outside the file's folder"),
              std::string::npos)
        << g.message();
}

TEST(HostileGltf, BareUriIsNotLookedUpInTheCurrentDirectory) {
    const fs::path root = fresh_dir("gltf_cwd");
    write(root / "cwd" / "secret.bin", std::string(9, '\x07'));
    const fs::path file = root / "a" / "bare.gltf";
    write(file, gltf_with_buffer("secret.bin"));
    const fs::path before = fs::current_path();
    fs::current_path(root / "cwd");
    auto g = assets::read_gltf_geometry(file);
    fs::current_path(before);
    ASSERT_FALSE(g.ok()) << "the current directory's secret.bin was read";
    EXPECT_NE(g.message().find(file.string() + ": resource 'secret.bin' not found"), std::string::npos)
        << g.message();
}

TEST(HostileGltf, BuffersInsideTheFolderStillLoad) {
    const fs::path root = fresh_dir("gltf_ok");
    write(root / "bin" / "data.bin", std::string("\x01\x02\x03\x04\x05\x06\x07\x08\x09", 9));
    for (const std::string uri :
         {"bin/data.bin", "./bin/data.bin", "bin/../bin/data.bin", "bin%2Fdata.bin"}) {
        write(root / "ok.gltf", gltf_with_buffer(uri));
        auto g = assets::read_gltf_geometry(root / "ok.gltf");
        ASSERT_TRUE(g.ok()) << uri << ": " << g.message();
        ASSERT_EQ(g->positions.size(), 3u);
        EXPECT_EQ(g->positions[2], glm::dvec3(7, 8, 9));
    }
    // The glTF in the current folder, named without a folder: its folder is the current one.
    const fs::path before = fs::current_path();
    fs::current_path(root);
    write("here.gltf", gltf_with_buffer("bin/data.bin"));
    auto g = assets::read_gltf_geometry("here.gltf");
    fs::current_path(before);
    EXPECT_TRUE(g.ok()) << g.message();
}

TEST(HostileGltf, ImageUriOutsideTheFolderIsRefused) {
    const fs::path root = fresh_dir("gltf_image");
    write(root / "evil.png", png_header(2, 2));
    const fs::path file = root / "a" / "img.gltf";
    write(file, gltf_with_images("../evil.png", 1));
    auto c = assets::read_gltf(file);
    ASSERT_FALSE(c.ok());
    EXPECT_NE(c.message().find(file.string() + ": resource '../evil.png' is outside the file's folder"),
              std::string::npos)
        << c.message();
}

TEST(HostileGltf, FifoAsBufferIsRefusedWithoutBlocking) {
    const fs::path root = fresh_dir("gltf_fifo");
    ASSERT_EQ(::mkfifo((root / "data.bin").c_str(), 0600), 0);
    write(root / "fifo.gltf", gltf_with_buffer("data.bin"));
    auto g = assets::read_gltf_geometry(root / "fifo.gltf");  // used to block forever in open()
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.message().find("resource 'data.bin' is a FIFO, not a regular file"), std::string::npos)
        << g.message();
    // The glTF itself as a FIFO, too.
    ASSERT_EQ(::mkfifo((root / "pipe.gltf").c_str(), 0600), 0);
    auto p = assets::read_gltf(root / "pipe.gltf");
    ASSERT_FALSE(p.ok());
    EXPECT_NE(p.message().find((root / "pipe.gltf").string() + ": not a regular file (a FIFO)"),
              std::string::npos)
        << p.message();
}

TEST(HostileGltf, DeeplyNestedExtrasAreRefusedBeforeParsing) {
    const fs::path root = fresh_dir("gltf_deep");
    const std::string nest = std::string(16000, '[') + std::string(16000, ']');
    const std::string text = R"({"asset":{"version":"2.0"},"materials":[{"extras":)" + nest + "}]}";
    EXPECT_LT(text.size(), 36000u);  // the issue's 35 KB file
    write(root / "deep.gltf", text);
    auto c = assets::read_gltf(root / "deep.gltf");  // used to overflow the stack (SIGSEGV)
    ASSERT_FALSE(c.ok());
    EXPECT_NE(c.message().find((root / "deep.gltf").string() + ": JSON nesting deeper than 256 levels"),
              std::string::npos)
        << c.message();
    // Brackets inside strings do not count.
    EXPECT_TRUE(check_json_depth(R"({"a":")" + std::string(1000, '[') + R"("})", "x").ok());
}

TEST(HostileGltf, DecodedImageSizeIsBudgetedPerFile) {
    // 40 images sharing one PNG that declares 8192 x 8192: 10 GiB decoded. Refused from the headers,
    // before any decoding (this header-only PNG could not even be decoded).
    const fs::path root = fresh_dir("gltf_bomb");
    write(root / "big.png", png_header(8192, 8192));
    write(root / "bomb.gltf", gltf_with_images("big.png", 40));
    auto c = assets::read_gltf(root / "bomb.gltf");
    ASSERT_FALSE(c.ok());
    EXPECT_NE(
        c.message().find((root / "bomb.gltf").string() + ": images decode to more than 1024 MiB in total"),
        std::string::npos)
        << c.message();
    // One image over 8192 x 8192 on its own.
    write(root / "huge.png", png_header(16384, 8193));
    write(root / "huge.gltf", gltf_with_images("huge.png", 1));
    auto h = assets::read_gltf(root / "huge.gltf");
    ASSERT_FALSE(h.ok());
    EXPECT_NE(h.message().find("image 0 is 16384x8193, larger than 8192x8192"), std::string::npos)
        << h.message();
}

// ------------------------------------------------------------------------------------------------
// PLY textures, OBJ material libraries

TEST(HostilePly, TextureFileOutsideTheFolderIsRefused) {
    const fs::path root = fresh_dir("ply_texture");
    write(root / "x.png", png_header(2, 2));
    for (const std::string& tex : {std::string("../x.png"), (root / "x.png").string()}) {
        const fs::path file = root / "a" / "tex.ply";
        write(file, "ply\nformat ascii 1.0\ncomment TextureFile " + tex +
                        "\nelement vertex 1\nproperty float x\nproperty float y\n"
                        "property float z\nend_header\n0 0 0\n");
        auto g = assets::read_ply_geometry(file);
        ASSERT_FALSE(g.ok()) << tex;
        EXPECT_NE(g.message().find(file.string() + ": resource '" + tex + "' is outside the file's folder"),
                  std::string::npos)
            << g.message();
    }
}

TEST(HostilePly, FifoAsTextureOrInputIsRefused) {
    const fs::path root = fresh_dir("ply_fifo");
    ASSERT_EQ(::mkfifo((root / "t.png").c_str(), 0600), 0);
    write(root / "tex.ply",
          "ply\nformat ascii 1.0\ncomment TextureFile t.png\nelement vertex 1\nproperty float x\nproperty "
          "float y\n"
          "property float z\nend_header\n0 0 0\n");
    auto g = assets::read_ply_geometry(root / "tex.ply");
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.message().find("resource 't.png' is a FIFO, not a regular file"), std::string::npos)
        << g.message();
    ASSERT_EQ(::mkfifo((root / "in.ply").c_str(), 0600), 0);
    auto p = assets::read_ply_geometry(root / "in.ply");
    ASSERT_FALSE(p.ok());
    EXPECT_NE(p.message().find((root / "in.ply").string() + ": not a regular file"), std::string::npos)
        << p.message();
}

TEST(HostilePly, HugeFaceListsAreRefusedBeforeExpanding) {
    // One face of 2^20 one-byte indices (1 MB) would fan out to a million triangles; the file of the
    // issue had 64 of them (67M triangles, 1.6 GB). Refused at the first face.
    const fs::path root = fresh_dir("ply_faces");
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
        "y\nproperty float z\n"
        "element face 4\nproperty list uint uchar vertex_indices\nend_header\n";
    s += std::string(36, '\0');
    for (int f = 0; f < 4; ++f) {
        const std::uint32_t n = 1u << 20;
        s.append(reinterpret_cast<const char*>(&n), 4);
        s += std::string(n, '\x01');
    }
    write(root / "faces.ply", s);
    auto g = assets::read_ply_geometry(root / "faces.ply");
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.message().find((root / "faces.ply").string() +
                               ": face 0 has 1048576 vertices; at most 65536 per face"),
              std::string::npos)
        << g.message();
}

TEST(HostileObj, MaterialLibraryAndTextureOutsideTheFolderAreRefused) {
    const fs::path root = fresh_dir("obj_mtl");
    write(root / "evil.mtl", "newmtl m\nKd 1 1 1\n");
    write(root / "a" / "b" / "m.obj", "mtllib ../../evil.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    auto g = assets::read_obj_geometry(root / "a" / "b" / "m.obj");
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.message().find((root / "a" / "b" / "m.obj").string() +
                               ": resource '../../evil.mtl' is outside the file's folder"),
              std::string::npos)
        << g.message();

    // A library inside the folder whose map_Kd is an absolute path.
    write(root / "secret.png", png_header(2, 2));
    write(root / "c" / "ok.mtl", "newmtl m\nKd 1 1 1\nmap_Kd " + (root / "secret.png").string() + "\n");
    write(root / "c" / "t.obj", "mtllib ok.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    auto t = assets::read_obj_geometry(root / "c" / "t.obj");
    ASSERT_FALSE(t.ok());
    EXPECT_NE(t.message().find((root / "c" / "ok.mtl").string() + ": resource '" +
                               (root / "secret.png").string() + "' is outside the file's folder"),
              std::string::npos)
        << t.message();

    // Inside the folder and missing: still only a warning, the mesh loads.
    write(root / "c" / "missing.obj", "mtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_TRUE(assets::read_obj_geometry(root / "c" / "missing.obj").ok());
}

TEST(HostileObj, TrustedFilesMayNameResourcesOutsideWithTheFlag) {
    const fs::path root = fresh_dir("obj_allow");
    write(root / "evil.mtl", "newmtl m\nKd 0.5 0.25 1\n");
    write(root / "a" / "m.obj", "mtllib ../evil.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    set_allow_outside_resources(true);
    auto g = assets::read_obj_geometry(root / "a" / "m.obj");
    set_allow_outside_resources(false);
    ASSERT_TRUE(g.ok()) << g.message();
    ASSERT_EQ(g->materials.size(), 1u);
    EXPECT_EQ(g->materials[0].base_color, glm::vec4(0.5f, 0.25f, 1.0f, 1.0f));
}

// ------------------------------------------------------------------------------------------------
// Lattice JSON

TEST(HostileLattice, UnknownKeyHugeControlPointsDeepNestingAndDevicesAreRefused) {
    const std::string base = R"("origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1])";
    auto misspelt = ffd::parse_lattice_json("{" + base + R"(,"controlpoints":[]})", "l.json");
    ASSERT_FALSE(misspelt.ok());
    EXPECT_NE(misspelt.message().find("l.json: unknown key \"controlpoints\""), std::string::npos)
        << misspelt.message();

    std::string cps = "[";
    for (int i = 0; i < 8; ++i) cps += std::string(i ? "," : "") + (i == 7 ? "[1e308,1,1]" : "[0,0,0]");
    cps += "]";
    auto huge = ffd::parse_lattice_json("{" + base + R"(,"control_points":)" + cps + "}", "l.json");
    ASSERT_FALSE(huge.ok());
    EXPECT_NE(huge.message().find("l.json: control_points[7] is larger than 1e30 in magnitude"),
              std::string::npos)
        << huge.message();

    auto deep = ffd::parse_lattice_json(std::string(20000, '[') + std::string(20000, ']'), "deep.json");
    ASSERT_FALSE(deep.ok());
    EXPECT_NE(deep.message().find("deep.json: JSON nesting deeper than 256 levels"), std::string::npos)
        << deep.message();

    auto dev = ffd::load_lattice("/dev/zero");  // used to read until std::bad_alloc
    ASSERT_FALSE(dev.ok());
    EXPECT_NE(dev.message().find("/dev/zero: not a regular file (a character device)"), std::string::npos)
        << dev.message();
}

// ------------------------------------------------------------------------------------------------
// SFFD_scene fields and splat nodes

namespace {

// A saved one-cloud scene (nodes[0] the cloud's node, nodes[1] its mesh node, one lattice, one camera)
// whose glTF JSON `edit` changes before loading.
Status load_edited(const std::string& name, const std::function<void(nlohmann::json&)>& edit) {
    const fs::path dir = fresh_dir("scene_" + name);
    SplatCloud c;
    c.positions = {glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)};
    c.normals.assign(3, glm::vec3(0, 0, 1));
    c.axis_u.assign(3, glm::vec3(0.1f, 0, 0));
    c.axis_v.assign(3, glm::vec3(0, 0.1f, 0));
    assets::GltfCloudOut out;
    out.name = "cloud";
    out.id = 0;
    out.cloud = &c;
    const std::string ext =
        R"({"version":1,"lattices":[{"id":1,"name":"l","origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],)"
        R"("divisions":[1,1,1],"rest":[0,0,0,0,0,1,0,1,0,0,1,1,1,0,0,1,0,1,1,1,0,1,1,1],)"
        R"("transform":{"translation":[0,0,0],"rotation":[0,0,0,1],"scale":[1,1,1]}}],)"
        R"("cameras":[{"eye":[0,0,3],"target":[0,0,0]}]})";
    EXPECT_TRUE(assets::write_gltf(dir / "s.gltf", {out}, ext).ok());
    nlohmann::json doc = nlohmann::json::parse(slurp(dir / "s.gltf"));
    edit(doc);
    write(dir / "s.gltf", doc.dump());
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    return load_scene(r, (dir / "s.gltf").string());
}

}  // namespace

TEST(HostileScene, UnrenderableFieldsAreRefusedNamingFileAndField) {
    using nlohmann::json;
    const Status ok = load_edited("ok", [](json&) {});
    ASSERT_TRUE(ok.ok()) << ok.message();
    struct Case {
        const char* name;
        std::function<void(json&)> edit;
        const char* expect;
    };
    auto lattice = [](json& d) -> json& { return d["extensions"]["SFFD_scene"]["lattices"][0]; };
    const Case cases[] = {
        {"transform", [&](json& d) { lattice(d)["transform"] = "abc"; },
         "SFFD_scene lattice: 'transform' must be an object"},
        {"quat",
         [&](json& d) {
             lattice(d)["transform"]["rotation"] = {0, 0, 0, 0};
         },
         "SFFD_scene lattice: 'transform' 'rotation' is a zero quaternion"},
        {"scale",
         [&](json& d) {
             lattice(d)["transform"]["scale"] = {1, 0, 1};
         },
         "SFFD_scene lattice: 'transform' 'scale' has a zero component"},
        {"eye",
         [](json& d) {
             d["extensions"]["SFFD_scene"]["cameras"][0]["eye"] = {0, 0, 0};
         },
         "SFFD_scene camera: 'eye' equals 'target'"},
        {"up",
         [](json& d) {
             d["extensions"]["SFFD_scene"]["cameras"][0]["up"] = {0, 0, 2};
         },
         "SFFD_scene camera: 'up' is zero or parallel to the view direction"},
        {"mesh", [](json& d) { d["nodes"][1]["mesh"] = 99; },
         "splat node 'cloud': mesh index 99 out of range (1 meshes)"},
        {"nodequat",
         [](json& d) {
             d["nodes"][0]["rotation"] = {0, 0, 0, 0};
         },
         "splat node 'cloud': rotation is a zero or non-finite quaternion"},
        {"nodescale",
         [](json& d) {
             d["nodes"][0]["scale"] = {0, 1, 1};
         },
         "splat node 'cloud': scale has a zero or non-finite component"},
    };
    for (const Case& c : cases) {
        const Status s = load_edited(c.name, c.edit);
        ASSERT_FALSE(s.ok()) << c.name;
        EXPECT_NE(s.message().find("s.gltf: "), std::string::npos) << s.message();
        EXPECT_NE(s.message().find(c.expect), std::string::npos) << c.name << ": " << s.message();
    }
}

// ------------------------------------------------------------------------------------------------
// Saving

TEST(AtomicSave, PlantedSymlinkAtTheOldTemporaryNameIsNotFollowed) {
    const fs::path dir = fresh_dir("save_planted");
    write(dir / "victim.txt", "precious");
    // The old scheme wrote `<out>.tmp-<pid>`: a link planted there made a save overwrite its target.
    fs::create_symlink(dir / "victim.txt", dir / ("res.ply.tmp-" + std::to_string(::getpid())));
    ASSERT_TRUE(write_file_atomic(dir / "res.ply", "new contents").ok());
    EXPECT_EQ(slurp(dir / "victim.txt"), "precious");
    EXPECT_EQ(slurp(dir / "res.ply"), "new contents");
}

TEST(AtomicSave, KeepsPermissionsRefusesNonRegularOutputsAndReplacesALinksTarget) {
    const fs::path dir = fresh_dir("save_modes");
    write(dir / "out.txt", "old");
    ASSERT_EQ(::chmod((dir / "out.txt").c_str(), 0640), 0);
    ASSERT_TRUE(write_file_atomic(dir / "out.txt", "new").ok());
    struct stat st {};
    ASSERT_EQ(::stat((dir / "out.txt").c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 07777, 0640u);
    EXPECT_EQ(slurp(dir / "out.txt"), "new");

    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
    Status f = write_file_atomic(dir / "fifo", "x");
    ASSERT_FALSE(f.ok());
    EXPECT_NE(
        f.message().find((dir / "fifo").string() + ": not a regular file (a FIFO); refusing to replace it"),
        std::string::npos)
        << f.message();
    Status n = write_file_atomic("/dev/null", "x");
    ASSERT_FALSE(n.ok());
    EXPECT_NE(n.message().find("/dev/null: not a regular file (a character device)"), std::string::npos)
        << n.message();

    write(dir / "real" / "target.txt", "old");
    fs::create_symlink(dir / "real" / "target.txt", dir / "link.txt");
    ASSERT_TRUE(write_file_atomic(dir / "link.txt", "through the link").ok());
    EXPECT_TRUE(fs::is_symlink(dir / "link.txt"));
    EXPECT_EQ(slurp(dir / "real" / "target.txt"), "through the link");
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find("sffd-tmp"), std::string::npos) << e.path();
}

TEST(AtomicSave, StaleTemporariesOfDeadProcessesAreRemovedOthersKept) {
    const fs::path dir = fresh_dir("save_stale");
    // pid 2^22 + 1 is above the default pid_max... but pid_max may be raised: find a pid that is not running.
    long dead = 4194000;
    while (::kill(static_cast<pid_t>(dead), 0) == 0 || errno == EPERM) ++dead;
    const std::string d = std::to_string(dead);
    write(dir / ("out.ply.tmp-" + d), "old scheme, dead");
    write(dir / (".out.ply.sffd-tmp-" + d + "-abcdef"), "new scheme, dead");
    write(dir / (".out.ply.sffd-tmp-1-abcdef"), "pid 1 is alive");
    write(dir / (".other.ply.sffd-tmp-" + d + "-abcdef"), "another output's");
    write(dir / "out.ply.tmp-notapid", "not ours");
    ASSERT_TRUE(write_file_atomic(dir / "out.ply", "fresh").ok());
    EXPECT_FALSE(fs::exists(dir / ("out.ply.tmp-" + d)));
    EXPECT_FALSE(fs::exists(dir / (".out.ply.sffd-tmp-" + d + "-abcdef")));
    EXPECT_TRUE(fs::exists(dir / ".out.ply.sffd-tmp-1-abcdef"));
    EXPECT_TRUE(fs::exists(dir / (".other.ply.sffd-tmp-" + d + "-abcdef")));
    EXPECT_TRUE(fs::exists(dir / "out.ply.tmp-notapid"));
}
