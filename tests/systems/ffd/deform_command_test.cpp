// End-to-end tests of `splatffd deform`: the PyGeM case through the command (every backend that exists
// here), other properties and order kept, ASCII / big-endian input, --bench JSON, refusals of bad input.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "tests/assets/textured_box.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "tests/systems/ffd/test_util.h"
#include "tests/test_util/gl_required.h"

namespace sffd::ffd {
namespace {

namespace fs = std::filesystem;

const std::string kTool = SFFD_BINARY_DIR "/tools/splatffd";

struct RunResult {
    int code = -1;
    std::string out, err;
};

RunResult run(const std::string& args) {
    const fs::path dir = fs::temp_directory_path();
    // Per-process names: test binaries of several build trees may run at once on one machine.
    const std::string id = std::to_string(::getpid());
    const std::string o = (dir / ("ffd_cmd_stdout_" + id + ".txt")).string(),
                      e = (dir / ("ffd_cmd_stderr_" + id + ".txt")).string();
    const int status = std::system((kTool + " deform " + args + " >" + o + " 2>" + e).c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream fo(o), fe(e);
    std::stringstream so, se;
    so << fo.rdbuf();
    se << fe.rdbuf();
    r.out = so.str(), r.err = se.str();
    return r;
}

struct Rows {
    std::vector<double> x, y, z, nx, ny, nz, red;
};

// Writes x y z (double) nx ny nz (float) red (uchar) rows.
void write_ply(const fs::path& path, const Rows& rows, ply::Format format) {
    ply::Header h;
    h.format = format;
    ply::Element e;
    e.name = "vertex";
    e.count = rows.x.size();
    for (const char* n : {"x", "y", "z"}) e.properties.push_back({n, ply::Type::float64});
    for (const char* n : {"nx", "ny", "nz"}) e.properties.push_back({n, ply::Type::float32});
    e.properties.push_back({"red", ply::Type::uint8});
    h.elements.push_back(e);
    auto w = ply::Writer::create(path, h);
    ASSERT_TRUE(w.ok()) << w.message();
    ply::Chunk c;
    c.reset(e);
    c.rows = rows.x.size();
    c.columns[0].values = rows.x, c.columns[1].values = rows.y, c.columns[2].values = rows.z;
    c.columns[3].values = rows.nx, c.columns[4].values = rows.ny, c.columns[5].values = rows.nz;
    c.columns[6].values = rows.red;
    ASSERT_TRUE(w->write_rows(c).ok());
    ASSERT_TRUE(w->finish().ok());
}

Rows read_ply(const fs::path& path, ply::Header* header = nullptr) {
    Rows r;
    auto rd = ply::Reader::open(path);
    EXPECT_TRUE(rd.ok()) << (rd.ok() ? "" : rd.message());
    if (!rd) return r;
    if (header) *header = rd->header();
    EXPECT_TRUE(rd->seek_element("vertex").ok());
    ply::Chunk c;
    while (true) {
        auto n = rd->read_rows(4096, c);
        if (!n || *n == 0) break;
        auto col = [&](const char* name) { return c.columns[std::size_t(c.find(name))].values; };
        auto app = [](std::vector<double>& dst, const std::vector<double>& src) {
            dst.insert(dst.end(), src.begin(), src.end());
        };
        app(r.x, col("x")), app(r.y, col("y")), app(r.z, col("z"));
        app(r.nx, col("nx")), app(r.ny, col("ny")), app(r.nz, col("nz"));
        app(r.red, col("red"));
    }
    return r;
}

struct PyGeM {
    std::vector<double> orig, mod;
    std::size_t n = 0;
};

PyGeM pygem() {
    PyGeM p;
    std::vector<std::size_t> shape;
    EXPECT_TRUE(test::read_npy_f64(SFFD_TEST_DATA_DIR "/pygem/meshpoints_sphere_orig.npy", p.orig, shape));
    EXPECT_TRUE(test::read_npy_f64(SFFD_TEST_DATA_DIR "/pygem/meshpoints_sphere_mod.npy", p.mod, shape));
    p.n = p.orig.size() / 3;
    return p;
}

class DeformCommand : public testing::Test {
protected:
    void SetUp() override {
        if (!fs::exists(kTool)) GTEST_SKIP() << kTool << " not built";
        dir = fs::temp_directory_path() / ("ffd_cmd_test_" + std::to_string(::getpid()));
        fs::create_directories(dir);
        const PyGeM p = pygem();
        Rows rows;
        for (std::size_t i = 0; i < p.n; ++i) {
            const glm::dvec3 x(p.orig[3 * i], p.orig[3 * i + 1], p.orig[3 * i + 2]), n = glm::normalize(x);
            rows.x.push_back(x.x), rows.y.push_back(x.y), rows.z.push_back(x.z);
            rows.nx.push_back(float(n.x)), rows.ny.push_back(float(n.y)), rows.nz.push_back(float(n.z));
            rows.red.push_back(double(i % 251));
        }
        input = rows;
        write_ply(dir / "in.ply", rows, ply::Format::binary_little_endian);
        write_ply(dir / "in_ascii.ply", rows, ply::Format::ascii);
        write_ply(dir / "in_be.ply", rows, ply::Format::binary_big_endian);
        ASSERT_TRUE(save_lattice(dir / "lattice.json", test::pygem_lattice()).ok());
    }
    void TearDown() override {
        if (!dir.empty()) fs::remove_all(dir);
    }
    std::string p(const char* name) const { return (dir / name).string(); }

    double max_error(const Rows& out) const {
        const PyGeM g = pygem();
        double worst = 0.0;
        for (std::size_t i = 0; i < g.n; ++i)
            worst =
                std::max(worst, glm::length(glm::dvec3(out.x[i], out.y[i], out.z[i]) -
                                            glm::dvec3(g.mod[3 * i], g.mod[3 * i + 1], g.mod[3 * i + 2])));
        return worst;
    }

    fs::path dir;
    Rows input;
};

TEST_F(DeformCommand, PyGeMCaseReferenceAndCpu) {
    RunResult r = run(p("in.ply") + " " + p("out_ref.ply") + " --lattice " + p("lattice.json") +
                      " --backend reference");
    ASSERT_EQ(r.code, 0) << r.err;
    Rows out = read_ply(p("out_ref.ply"));
    ASSERT_EQ(out.x.size(), input.x.size());
    EXPECT_LT(max_error(out), 1e-9);  // PyGeM's own test checks 6 decimals
    EXPECT_EQ(out.red, input.red);    // other properties kept, same order
    for (const auto* in : {"in.ply", "in_ascii.ply", "in_be.ply"}) {
        r = run(p(in) + " " + p("out_cpu.ply") + " --lattice " + p("lattice.json"));
        ASSERT_EQ(r.code, 0) << r.err;
        out = read_ply(p("out_cpu.ply"));
        EXPECT_LT(max_error(out), 1e-4) << in;  // float path: 1e-6 of the 100-unit box
        EXPECT_EQ(out.red, input.red);
    }
    // Normals: unit length; unchanged outside the lattice.
    for (std::size_t i = 0; i < out.x.size(); ++i) {
        EXPECT_NEAR(glm::length(glm::dvec3(out.nx[i], out.ny[i], out.nz[i])), 1.0, 1e-5);
        if (out.x[i] == input.x[i] && out.y[i] == input.y[i] && out.z[i] == input.z[i]) {
            EXPECT_EQ(out.nx[i], input.nx[i]);
        }
    }
}

TEST_F(DeformCommand, AsciiOutputAndBenchJson) {
    const RunResult r =
        run(p("in.ply") + " " + p("out.ply") + " --lattice " + p("lattice.json") + " --ascii --bench 3");
    ASSERT_EQ(r.code, 0) << r.err;
    ply::Header h;
    const Rows out = read_ply(p("out.ply"), &h);
    EXPECT_EQ(h.format, ply::Format::ascii);
    EXPECT_LT(max_error(out), 1e-4);
    EXPECT_NE(r.out.find("\"points\":7200"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"backend\":\"cpu\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"median_ms\":"), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1);
}

TEST_F(DeformCommand, GpuBackendMatchesReference) {
    const RunResult r =
        run(p("in.ply") + " " + p("out_gpu.ply") + " --lattice " + p("lattice.json") + " --backend gpu");
    if (r.code != 0 && r.err.find("EGL") != std::string::npos) SFFD_GL_UNAVAILABLE("no EGL here: " << r.err);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_LT(max_error(read_ply(p("out_gpu.ply"))), 1e-4);
}

TEST_F(DeformCommand, BadInputIsRefused) {
    // Missing lattice option: usage.
    EXPECT_EQ(run(p("in.ply") + " " + p("o.ply")).code, 2);
    EXPECT_EQ(
        run(p("in.ply") + " " + p("o.ply") + " --lattice " + p("lattice.json") + " --backend cuda").code, 2);
    // Bad lattice: wrong count.
    {
        std::ofstream f(p("bad.json"));
        f << R"({"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1],"control_points":[[0,0,0]]})";
    }
    RunResult r = run(p("in.ply") + " " + p("o.ply") + " --lattice " + p("bad.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("bad.json: expected 8 control_points"), std::string::npos) << r.err;
    // Zero-volume box.
    {
        std::ofstream f(p("flat.json"));
        f << R"({"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,0]],"divisions":[1,1,1]})";
    }
    r = run(p("in.ply") + " " + p("o.ply") + " --lattice " + p("flat.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("flat.json: zero-volume box"), std::string::npos) << r.err;
    // Malformed and truncated PLY.
    {
        std::ofstream f(p("junk.ply"));
        f << "not a ply file\n";
    }
    r = run(p("junk.ply") + " " + p("o.ply") + " --lattice " + p("lattice.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("junk.ply"), std::string::npos) << r.err;
    fs::copy_file(p("in.ply"), p("trunc.ply"));
    fs::resize_file(p("trunc.ply"), fs::file_size(p("trunc.ply")) - 100);
    r = run(p("trunc.ply") + " " + p("o.ply") + " --lattice " + p("lattice.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("trunc.ply"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(p("o.ply")));  // atomic: no half-written output
    // No x y z.
    {
        std::ofstream f(p("noxyz.ply"));
        f << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n";
    }
    r = run(p("noxyz.ply") + " " + p("o.ply") + " --lattice " + p("lattice.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("noxyz.ply: vertex element has no x, y, z"), std::string::npos) << r.err;
}

// Outputs that would be wrong or destructive, hostile lattices, and interruptions.
TEST_F(DeformCommand, WrongExtensionSameFileAndNonRegularPathsAreRefused) {
    const std::string lat = " --lattice " + p("lattice.json");
    // The format follows the extension: .glb used to get PLY bytes; now it is a binary glTF.
    RunResult r = run(p("in.ply") + " " + p("out.glb") + lat);
    EXPECT_EQ(r.code, 0) << r.err;
    {
        std::ifstream f(p("out.glb"), std::ios::binary);
        char magic[4] = {};
        f.read(magic, 4);
        EXPECT_EQ(std::string(magic, 4), "glTF");
    }
    r = run(p("in.ply") + " " + p("out.xyz") + lat);  // an extension no writer has is refused
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(p("out.xyz") + ": deform writes .ply, .glb or .gltf files (got '.xyz')"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(p("out.xyz")));

    const auto before = fs::file_size(p("in.ply"));
    for (const std::string& out : {p("in.ply"), (dir / "." / "in.ply").string()}) {
        r = run(p("in.ply") + " " + out + lat);
        EXPECT_EQ(r.code, 1);
        EXPECT_NE(r.err.find(": output is the input file"), std::string::npos) << r.err;
    }
    fs::create_hard_link(p("in.ply"), p("hard.ply"));
    r = run(p("in.ply") + " " + p("hard.ply") + lat);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(p("hard.ply") + ": output is the input file"), std::string::npos) << r.err;
    EXPECT_EQ(fs::file_size(p("in.ply")), before);
    EXPECT_EQ(read_ply(p("in.ply")).x, input.x);

    // A FIFO as lattice, /dev/zero as lattice, /dev/null as output: refused at once (used to hang,
    // abort with std::bad_alloc, or replace /dev/null).
    ASSERT_EQ(::mkfifo(p("fifo.json").c_str(), 0600), 0);
    r = run(p("in.ply") + " " + p("o.ply") + " --lattice " + p("fifo.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(p("fifo.json") + ": not a regular file (a FIFO)"), std::string::npos) << r.err;
    r = run(p("in.ply") + " " + p("o.ply") + " --lattice /dev/zero");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("/dev/zero: not a regular file (a character device)"), std::string::npos) << r.err;
    fs::create_directories(dir / "dev");
    fs::create_symlink("/dev/null", dir / "dev" / "null.ply");
    r = run(p("in.ply") + " " + (dir / "dev" / "null.ply").string() + lat);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("not a regular file (a character device); refusing to replace it"),
              std::string::npos)
        << r.err;
}

TEST_F(DeformCommand, HugeControlPointsAndMisspeltKeysFailInsteadOfWritingNonsense) {
    std::string cps = "[";
    for (int i = 0; i < 8; ++i)
        cps += std::string(i ? "," : "") + "[" + (i == 7 ? "1e308" : std::to_string(100 * (i & 1))) + "," +
               std::to_string(100 * ((i >> 1) & 1)) + "," + std::to_string(100 * ((i >> 2) & 1)) + "]";
    cps += "]";
    {
        std::ofstream f(p("huge.json"));
        f << R"({"origin":[0,0,0],"axes":[[100,0,0],[0,100,0],[0,0,100]],"divisions":[1,1,1],"control_points":)"
          << cps << "}";
    }
    RunResult r =
        run(p("in.ply") + " " + p("o.ply") + " --lattice " + p("huge.json"));  // used to exit 0 writing inf
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(p("huge.json") + ": control_points[7] is larger than 1e30 in magnitude"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(p("o.ply")));
    {
        std::ofstream f(p("typo.json"));
        f << R"({"origin":[0,0,0],"axes":[[100,0,0],[0,100,0],[0,0,100]],"divisions":[1,1,1],"controlpoints":[]})";
    }
    r = run(p("in.ply") + " " + p("o.ply") + " --lattice " +
            p("typo.json"));  // used to deform nothing and exit 0
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find(p("typo.json") + ": unknown key \"controlpoints\""), std::string::npos) << r.err;
}

// Runs `splatffd deform` with --bench (the deformation repeated many times keeps it busy), sends `sig`
// once its temporary exists, and returns the exit code; stderr goes to `err`.
int deform_and_signal(const std::string& args, const fs::path& dir, int sig, const fs::path& err) {
    const pid_t pid = ::fork();
    if (pid == 0) {
        const std::string cmd = "exec " + kTool + " deform " + args + " 2>" + err.string() + " >/dev/null";
        ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    bool sent = false;
    for (int i = 0; i < 20000 && !sent; ++i) {  // up to 20 s for the temporary to appear
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().filename().string().find(".sffd-tmp-") != std::string::npos) {
                ::kill(pid, sig);
                sent = true;
                break;
            }
        if (!sent) ::usleep(1000);
        int status = 0;
        if (!sent && ::waitpid(pid, &status, WNOHANG) == pid)
            return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : (WIFSIGNALED(status) ? 1000 + WTERMSIG(status) : -1);
}

TEST_F(DeformCommand, SigintAndSigtermRemoveTheTemporaryAndKeepTheOldOutput) {
    const std::string args = p("in.ply") + " " + p("res.ply") + " --lattice " + p("lattice.json") +
                             " --backend reference --bench 100000";
    for (const auto& [sig, code, word] : {std::tuple{SIGINT, 130, "interrupted (SIGINT)"},
                                          std::tuple{SIGTERM, 143, "terminated (SIGTERM)"}}) {
        { std::ofstream(p("res.ply")) << "old output"; }
        const int rc = deform_and_signal(args, dir, sig, dir / "err.txt");
        std::ifstream in(dir / "err.txt");
        const std::string err((std::istreambuf_iterator<char>(in)), {});
        EXPECT_EQ(rc, code) << err;
        EXPECT_NE(err.find(std::string("splatffd deform: ") + word + "; unfinished output removed"),
                  std::string::npos)
            << err;
        for (const auto& e : fs::directory_iterator(dir))
            EXPECT_EQ(e.path().filename().string().find("sffd-tmp"), std::string::npos) << e.path();
        std::ifstream old(p("res.ply"));
        EXPECT_EQ(std::string((std::istreambuf_iterator<char>(old)), {}), "old output");
    }
}

// A textured cloud's uv frame rides on its axes: deform maps the axes by the Jacobian and keeps
// the frame (du/ds ... per axis) as it is, streamed PLY -> PLY and in memory PLY/GLB -> GLB.
TEST_F(DeformCommand, UvFrameOfATexturedCloudRidesOnTheDeformedAxes) {
    auto g = assets::read_geometry(sffd::test::write_textured_box(dir / "box"));
    ASSERT_TRUE(g.ok()) << g.message();
    assets::ImportOptions opt;
    opt.splats = 1500;
    auto cloud = assets::make_splat_cloud(*g, opt);
    ASSERT_TRUE(cloud.ok()) << cloud.message();
    ASSERT_EQ(cloud->uv_axes.size(), cloud->size());
    ASSERT_TRUE(assets::save_splat_cloud(*cloud, dir / "box.ply").ok());
    ASSERT_TRUE(assets::save_splat_cloud(*cloud, dir / "box.glb").ok());
    // x' = 2x: a 2x2x2 Bernstein lattice around the box with its control points scaled along x.
    Lattice l =
        make_lattice(glm::dvec3(-1.5, -1.0, -1.0),
                     {glm::dvec3(3, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, glm::ivec3(2, 2, 2));
    for (glm::dvec3& c : l.current) c.x *= 2.0;
    ASSERT_TRUE(save_lattice(dir / "stretch.json", l).ok());
    for (const auto& [in, out] : {std::pair{"box.ply", "out.ply"}, std::pair{"box.ply", "out_ply.glb"},
                                  std::pair{"box.glb", "out.glb"}}) {
        const RunResult r = run(p(in) + " " + p(out) + " --lattice " + p("stretch.json"));
        ASSERT_EQ(r.code, 0) << in << " -> " << out << ": " << r.err;
        auto d = assets::import_splat_cloud(dir / out);
        ASSERT_TRUE(d.ok()) << d.message();
        ASSERT_EQ(d->size(), cloud->size()) << out;
        ASSERT_EQ(d->uv_axes.size(), cloud->size()) << out;
        EXPECT_EQ(d->texture.width, 256) << out;  // the texture still found (PLY: the TextureFile beside it)
        std::size_t bad = 0;
        for (std::size_t i = 0; i < d->size(); ++i) {
            // Axes doubled along x, the frame and uv unchanged: the point x' + s J a_u has the uv of x + s
            // a_u.
            const glm::vec3 au = cloud->axis_u[i], av = cloud->axis_v[i];
            const bool ok = glm::length(d->axis_u[i] - glm::vec3(2 * au.x, au.y, au.z)) < 1e-5f &&
                            glm::length(d->axis_v[i] - glm::vec3(2 * av.x, av.y, av.z)) < 1e-5f &&
                            d->uv_axes[i] == cloud->uv_axes[i] && d->uvs[i] == cloud->uvs[i];
            if (!ok && bad++ < 3) ADD_FAILURE() << out << ": splat " << i;
        }
        EXPECT_EQ(bad, 0u) << out;
    }
}

}  // namespace
}  // namespace sffd::ffd
