// ffd::stream_deform(): the chunk size never changes the bytes written; the streamed result equals the
// in-memory deformation of the same points by the same kernels (ffd::deform, gaussian::deform) to the
// bit; bad input names the file and leaves no output behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/surface/ply.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/stream_deform.h"
#include "systems/gaussian/gaussian_deform.h"
#include "tests/systems/ffd/test_util.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

struct StreamDeformTest : ::testing::Test {
    fs::path dir;
    void SetUp() override {
        dir = fs::temp_directory_path() / ("stream_deform_test_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const std::string& name) const { return (dir / name).string(); }
};

std::string bytes_of(const std::string& file) {
    std::ifstream f(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// Files in `dir` (a failed run must leave no temporary behind either).
std::size_t files_in(const fs::path& dir) {
    return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// A twisted, jittered 3x3x3 lattice over [-1, 1]³ whose box leaves the points with x > 1 outside.
Lattice bent_lattice(LatticeBasis basis = LatticeBasis::bernstein) {
    Lattice l = make_lattice(
        glm::dvec3(-1.0), {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 3, 3}, basis);
    ffd::test::twist_about_t(l, 0.8);
    ffd::test::jitter(l, 0.05, 3, 2);
    return l;
}

// Surface splats as a PLY: x y z (float), nx ny nz, axis_u*/axis_v* when `axes`, radius when `radius`, a
// uchar `red` the stream must copy, and a trailing `face` element with a list.
struct SurfaceFile {
    ffd::test::Cloud cloud;
    std::vector<std::uint8_t> red;
};
SurfaceFile write_surface_ply(const std::string& file, std::size_t n, bool axes, bool radius,
                              ply::Format format = ply::Format::binary_little_endian) {
    SurfaceFile s{ffd::test::random_cloud(n, -1.0, 1.4, 11), {}};
    ply::Element ve{"vertex", n, {}};
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz"}) ve.properties.push_back({p, ply::Type::float32});
    if (axes)
        for (const char* p : {"axis_ux", "axis_uy", "axis_uz", "axis_vx", "axis_vy", "axis_vz"})
            ve.properties.push_back({p, ply::Type::float32});
    if (radius) ve.properties.push_back({"radius", ply::Type::float32});
    ve.properties.push_back({"red", ply::Type::uint8});
    ply::Element fe{"face", 2, {{"vertex_indices", ply::Type::int32, true, ply::Type::uint8}}};
    ply::Header h;
    h.format = format;
    h.elements = {ve, fe};
    auto w = ply::Writer::create(file, h);
    EXPECT_TRUE(w) << w.message();
    ply::Chunk c;
    c.reset(ve);
    c.rows = n;
    for (std::size_t i = 0; i < n; ++i) {
        std::size_t k = 0;
        auto put = [&](const glm::vec3& v) {
            for (int a = 0; a < 3; ++a) c.columns[k + std::size_t(a)].values.push_back(double(v[a]));
            k += 3;
        };
        put(s.cloud.p[i]), put(s.cloud.n[i]);
        if (axes) put(s.cloud.u[i]), put(s.cloud.v[i]);
        if (radius) c.columns[k++].values.push_back(0.01 + 0.001 * double(i % 7));
        s.red.push_back(std::uint8_t(i * 37));
        c.columns[k].values.push_back(double(s.red.back()));
    }
    EXPECT_TRUE(w->write_rows(c));
    c.reset(fe);
    c.rows = 2;
    c.columns[0].values = {0, 1, 2, 2, 3, 4};
    c.columns[0].offsets = {0, 3, 6};
    EXPECT_TRUE(w->write_rows(c));
    EXPECT_TRUE(w->finish());
    return s;
}

// Every column of the vertex element, as read.
ply::Chunk read_vertices(const std::string& file) {
    auto r = ply::Reader::open(file);
    EXPECT_TRUE(r) << r.message();
    ply::Chunk c;
    if (!r) return c;
    EXPECT_TRUE(r->seek_element("vertex"));
    const std::uint64_t n = r->header().elements[std::size_t(r->header().find("vertex"))].count;
    auto rows = r->read_rows(std::size_t(std::max<std::uint64_t>(n, 1)), c);
    EXPECT_TRUE(rows && *rows == n);
    return c;
}

Result<ffd::StreamDeformResult> stream(const std::string& in, const std::string& out, const Lattice& l,
                                       std::size_t chunk_rows,
                                       ffd::StreamBackend backend = ffd::StreamBackend::cpu) {
    ffd::StreamDeformRequest req;
    req.input = in;
    req.output = out;
    req.lattices = std::span<const Lattice>(&l, 1);
    req.backend = backend;
    req.chunk_rows = chunk_rows;
    return ffd::stream_deform(req);
}

TEST_F(StreamDeformTest, ChunkSizeDoesNotChangeTheBytes) {
    const std::size_t n = 5000;
    const std::string in = path("in.ply");
    write_surface_ply(in, n, true, false);
    for (const LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline})
        for (const auto backend : {ffd::StreamBackend::cpu, ffd::StreamBackend::reference}) {
            const Lattice l = bent_lattice(basis);
            std::string first;
            for (const std::size_t rows : {std::size_t(1), std::size_t(7), std::size_t(4096), n}) {
                const std::string out = path("out_" + std::to_string(rows) + ".ply");
                auto r = stream(in, out, l, rows, backend);
                ASSERT_TRUE(r) << r.message();
                EXPECT_EQ(r->points, n);
                ASSERT_EQ(r->inside.size(), 1u);
                EXPECT_GT(r->inside[0], n / 2);  // most points are inside, some outside (x > 1)
                EXPECT_LT(r->inside[0], n);
                EXPECT_EQ(r->axes, ffd::StreamAxes::deformed);
                const std::string b = bytes_of(out);
                if (first.empty()) first = b;
                else
                    EXPECT_TRUE(b == first)
                        << "chunk of " << rows << " rows, " << ffd::stream_backend_name(backend);
            }
        }
}

TEST_F(StreamDeformTest, AxesCreatedFromRadiusDoNotDependOnTheChunkSize) {
    const std::string in = path("in.ply");
    write_surface_ply(in, 300, false, true);
    const Lattice l = bent_lattice();
    auto a = stream(in, path("a.ply"), l, 1);
    auto b = stream(in, path("b.ply"), l, 0);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->axes, ffd::StreamAxes::from_radius);
    EXPECT_TRUE(bytes_of(path("a.ply")) == bytes_of(path("b.ply")));
    const ply::Chunk c = read_vertices(path("a.ply"));
    EXPECT_GE(c.find("axis_ux"), 0);
    EXPECT_GE(c.find("axis_vz"), 0);
}

// The streamed points are ffd::deform's output for the same float input (relative to the lattice origin,
// as the stream feeds it), written back through double: equal to the bit, other columns copied as read.
TEST_F(StreamDeformTest, EqualsTheInMemoryDeformationToTheBit) {
    const std::size_t n = 3000;
    const std::string in = path("in.ply");
    const SurfaceFile file = write_surface_ply(in, n, true, false);
    const Lattice l = bent_lattice();
    auto r = stream(in, path("out.ply"), l, 7);
    ASSERT_TRUE(r) << r.message();

    std::vector<glm::vec3> p(n), np(n), nn(n), nu(n), nv(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = glm::vec3(glm::dvec3(file.cloud.p[i]) - l.origin);
    auto stats =
        ffd::deform(l, {p.data(), file.cloud.n.data(), file.cloud.u.data(), file.cloud.v.data(), n, l.origin},
                    {np.data(), nn.data(), nu.data(), nv.data()});
    ASSERT_TRUE(stats);
    EXPECT_EQ(r->inside[0], stats->inside);
    EXPECT_EQ(r->inverted, stats->inverted);

    const ply::Chunk c = read_vertices(path("out.ply"));
    ASSERT_EQ(c.rows, n);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const bool same = np[i] == p[i];
        moved += !same;
        for (int a = 0; a < 3; ++a) {
            // Unchanged points keep the file's value; moved ones are origin + deformed, rounded once.
            const float want = same ? file.cloud.p[i][a] : float(l.origin[a] + double(np[i][a]));
            ASSERT_EQ(float(c.columns[std::size_t(a)].values[i]), want) << "point " << i;
            ASSERT_EQ(float(c.columns[std::size_t(3 + a)].values[i]), nn[i][a]) << "normal " << i;
            ASSERT_EQ(float(c.columns[std::size_t(6 + a)].values[i]), nu[i][a]) << "axis u " << i;
            ASSERT_EQ(float(c.columns[std::size_t(9 + a)].values[i]), nv[i][a]) << "axis v " << i;
        }
        ASSERT_EQ(c.columns[12].values[i], double(file.red[i]));
    }
    EXPECT_GT(moved, n / 2);
}

// The reference backend is double in, double out: equal to ffd::reference_point and deformed_normal.
TEST_F(StreamDeformTest, ReferenceEqualsTheDoublePrecisionEvaluation) {
    const std::size_t n = 500;
    const std::string in = path("in.ply");
    const SurfaceFile file = write_surface_ply(in, n, true, false);
    const Lattice l = bent_lattice(LatticeBasis::bspline);
    auto r = stream(in, path("out.ply"), l, 7, ffd::StreamBackend::reference);
    ASSERT_TRUE(r) << r.message();
    const ply::Chunk c = read_vertices(path("out.ply"));
    for (std::size_t i = 0; i < n; ++i) {
        const ffd::ReferencePoint rp = ffd::reference_point(l, glm::dvec3(file.cloud.p[i]));
        const glm::dvec3 normal = rp.inside ? ffd::deformed_normal(rp.jacobian, glm::dvec3(file.cloud.n[i]))
                                            : glm::dvec3(file.cloud.n[i]);
        for (int a = 0; a < 3; ++a) {
            ASSERT_EQ(float(c.columns[std::size_t(a)].values[i]), float(rp.position[a])) << i;
            ASSERT_EQ(float(c.columns[std::size_t(3 + a)].values[i]), float(normal[a])) << i;
        }
    }
}

// A 3DGS file streamed equals its vertex element deformed whole by gaussian::deform, column for column.
TEST_F(StreamDeformTest, GaussiansEqualTheInMemoryDeformation) {
    const std::size_t n = 700;
    GaussianCloud g;
    g.sh_degree = 1;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> pos(-1.0f, 1.4f), unit(-1.0f, 1.0f), s(0.005f, 0.05f),
        o(0.1f, 0.9f);
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.push_back({pos(rng), pos(rng), pos(rng)});
        g.scales.push_back({s(rng), s(rng), s(rng)});
        g.rotations.push_back(glm::normalize(glm::quat(unit(rng), unit(rng), unit(rng), unit(rng))));
        g.opacities.push_back(o(rng));
        for (int k = 0; k < sh_coeffs(1) * 3; ++k) g.sh.push_back(0.3f * unit(rng));
    }
    const std::string in = path("g.ply");
    ASSERT_TRUE(gaussian::write_ply(in, g));
    auto kind = ffd::inspect_stream_input(in);
    ASSERT_TRUE(kind);
    EXPECT_EQ(kind->kind, ffd::StreamKind::gaussians);

    const Lattice l = bent_lattice();
    std::string first;
    for (const std::size_t rows : {std::size_t(1), std::size_t(7), std::size_t(4096), n}) {
        auto r = stream(in, path("out.ply"), l, rows);
        ASSERT_TRUE(r) << r.message();
        EXPECT_EQ(r->kind, ffd::StreamKind::gaussians);
        EXPECT_EQ(r->sh_degree, 1);
        const std::string b = bytes_of(path("out.ply"));
        if (first.empty()) first = b;
        else EXPECT_TRUE(b == first) << rows;
    }

    ply::Chunk whole = read_vertices(in);
    auto reader = ply::Reader::open(in);
    ASSERT_TRUE(reader);
    auto layout = gaussian::ply_layout(reader->header().elements[0], in);
    ASSERT_TRUE(layout);
    GaussianCloud mem;
    mem.sh_degree = layout->degree;
    ASSERT_TRUE(gaussian::append_from_chunk(whole, *layout, 0, in, mem));
    auto st = gaussian::deform(l, mem, mem, ffd::Backend::automatic, false);
    ASSERT_TRUE(st);
    EXPECT_GT(st->inside, n / 2);
    gaussian::store_to_chunk(mem, *layout, false, whole);
    const ply::Chunk streamed = read_vertices(path("out.ply"));
    ASSERT_EQ(streamed.columns.size(), whole.columns.size());
    for (std::size_t k = 0; k < whole.columns.size(); ++k)
        for (std::size_t i = 0; i < n; ++i)
            ASSERT_EQ(float(streamed.columns[k].values[i]), float(whole.columns[k].values[i]))
                << whole.element.properties[k].name << " of Gaussian " << i;
}

TEST_F(StreamDeformTest, TruncatedInputNamesTheFileAndWritesNothing) {
    const Lattice l = bent_lattice();
    // Binary: the declared rows do not fit in what is left of the file (refused when opened).
    const std::string bin = path("cut.ply");
    write_surface_ply(bin, 400, true, false);
    fs::resize_file(bin, fs::file_size(bin) - 100);
    // ASCII: cut in the middle of the vertex rows, found while streaming, after chunks were written.
    const std::string text = path("cut_ascii.ply");
    write_surface_ply(text, 400, true, false, ply::Format::ascii);
    fs::resize_file(text, fs::file_size(text) / 2);
    for (const auto& [in, problem] : {std::pair<std::string, std::string>{bin, "more than the file's"},
                                      std::pair<std::string, std::string>{text, "truncated data"}}) {
        const std::size_t before = files_in(dir);
        const std::string out = path("out.ply");
        auto r = stream(in, out, l, 7);
        ASSERT_FALSE(r) << in;
        EXPECT_NE(r.message().find(in), std::string::npos) << r.message();
        EXPECT_NE(r.message().find(problem), std::string::npos) << r.message();
        EXPECT_FALSE(fs::exists(out)) << r.message();
        EXPECT_EQ(files_in(dir), before) << "a temporary was left behind";
    }
}

TEST_F(StreamDeformTest, ErrorsLeaveAnOldOutputUntouched) {
    const std::string in = path("in.ply"), out = path("out.ply");
    write_surface_ply(in, 50, true, false);
    { std::ofstream(out) << "old"; }
    Lattice bad = bent_lattice();
    bad.current[0].x = std::numeric_limits<double>::quiet_NaN();
    ffd::StreamDeformRequest req;
    req.input = in;
    req.output = out;
    req.lattices = std::span<const Lattice>(&bad, 1);
    req.lattice_label = "bent.json";
    auto r = ffd::stream_deform(req);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.message().rfind("bent.json: lattice", 0), 0u) << r.message();
    EXPECT_EQ(bytes_of(out), "old");

    // No vertex element, and a missing file: named.
    auto missing = ffd::inspect_stream_input(path("nope.ply"));
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.message().find("nope.ply"), std::string::npos);
}

// Progress after each vertex chunk: rows done so far, rising to the element's count.
TEST_F(StreamDeformTest, ProgressFollowsTheVertexChunks) {
    const std::string in = path("in.ply");
    write_surface_ply(in, 1000, true, false);
    const Lattice l = bent_lattice();
    ffd::StreamDeformRequest req;
    req.input = in;
    req.output = path("out.ply");
    req.lattices = std::span<const Lattice>(&l, 1);
    req.chunk_rows = 300;
    std::vector<std::uint64_t> seen;
    auto r = ffd::stream_deform(req, [&](std::uint64_t done, std::uint64_t total) {
        EXPECT_EQ(total, 1000u);
        seen.push_back(done);
    });
    ASSERT_TRUE(r) << r.message();
    EXPECT_EQ(seen, (std::vector<std::uint64_t>{300, 600, 900, 1000}));
}

// Two lattices both run (the first sees the file as it is), and a 3DGS file refuses more than one.
TEST_F(StreamDeformTest, LatticesApplyInOrder) {
    const std::size_t n = 400;
    const std::string in = path("in.ply");
    write_surface_ply(in, n, true, false);
    const std::vector<Lattice> two = {bent_lattice(), bent_lattice(LatticeBasis::bspline)};
    ffd::StreamDeformRequest req;
    req.input = in;
    req.output = path("both.ply");
    req.lattices = two;
    auto both = ffd::stream_deform(req);
    ASSERT_TRUE(both) << both.message();
    ASSERT_EQ(both->inside.size(), 2u);
    auto one = stream(in, path("first.ply"), two[0], 0);
    ASSERT_TRUE(one);
    EXPECT_EQ(both->inside[0], one->inside[0]);
    EXPECT_FALSE(bytes_of(path("both.ply")) == bytes_of(path("first.ply")));  // the second one moved them

    GaussianCloud g;
    g.positions = {glm::vec3(0.0f)};
    g.scales = {glm::vec3(0.01f)};
    g.rotations = {glm::quat(1, 0, 0, 0)};
    g.opacities = {0.5f};
    g.sh = {0.1f, 0.2f, 0.3f};
    ASSERT_TRUE(gaussian::write_ply(path("g.ply"), g));
    req.input = path("g.ply");
    req.output = path("g_out.ply");
    auto refused = ffd::stream_deform(req);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.message().find("one lattice at a time (got 2)"), std::string::npos)
        << refused.message();
    EXPECT_FALSE(fs::exists(path("g_out.ply")));
}

}  // namespace
