// The lattice workflow on the command line, as a user runs it (the built `splatffd`): a fitted lattice
// stored in a scene by `convert --lattice fit…`, exported as lattice JSON by `convert SCENE L.json`, scene
// files as `deform --lattice` sources (bound chain, --lattice-name, the errors for none / several / an
// unknown name), splat axes deformed or created from normals + radius (checked against the double
// reference Jacobian), GLB in and out, and the shared option parsing (--help exits 0, numbers named).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/scene.h"
#include "runtime/assets/splat_estimation.h"
#include "runtime/scene/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "tests/test_util/run_tool.h"

namespace sffd::ffd {
namespace {

namespace fs = std::filesystem;

using sffd::test::CliRun;
using sffd::test::run;

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A small splat cloud: a 12 x 8 x 6 grid of points in [0,3]x[0,2]x[0,1] (so the fitted box is not a cube),
// normals along +z, circular axes of radius 0.05.
SplatCloud grid_cloud() {
    SplatCloud c;
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 6; ++k) {
                c.positions.emplace_back(3.0f * float(i) / 11.0f, 2.0f * float(j) / 7.0f, float(k) / 5.0f);
                c.normals.emplace_back(0.0f, 0.0f, 1.0f);
                c.colors.push_back(0xff0000ffu);
            }
    std::vector<float> r(c.size(), 0.05f);
    assets::make_circular_axes(c.normals, r, c.axis_u, c.axis_v);
    return c;
}

// A lattice around the grid with its far x face moved +3 along x: a 2x stretch of the box in x.
Lattice stretch_x2(const SplatCloud& c) {
    auto l = fit_lattice(c.positions, c.origin,
                         FitOptions{{2, 1, 1}, LatticeBasis::bernstein, 0.0, FitShape::box});
    EXPECT_TRUE(l.ok());
    Lattice out = *l;
    const double len = out.axes[0].x;
    for (int j = 0; j <= 1; ++j)
        for (int k = 0; k <= 1; ++k) {
            out.current[out.index(1, j, k)].x += 0.5 * len;
            out.current[out.index(2, j, k)].x += len;
        }
    return out;
}

struct LatticeCli : testing::Test {
    void SetUp() override {
        if (!fs::exists(fs::path(SFFD_BINARY_DIR) / "tools/splatffd")) GTEST_SKIP() << "splatffd not built";
        dir = fs::temp_directory_path() / ("sffd_lattice_cli_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override {
        if (!dir.empty()) fs::remove_all(dir);
    }
    std::string p(const std::string& name) const { return (dir / name).string(); }

    // A scene: the grid cloud bound to `bound` lattices in order, plus `loose` unbound ones.
    void save_grid_scene(const std::string& name, const std::vector<Lattice>& bound,
                         const std::vector<Lattice>& loose = {}) {
        ecs::Registry r;
        r.set_resource<SceneHooks>();  // assets' own formats only
        const ecs::Entity c = r.create();
        r.emplace<Name>(c, Name{"grid"});
        r.emplace<Transform>(c, Transform{});
        r.emplace<SplatCloud>(c, grid_cloud());
        Deformers d;
        int n = 0;
        for (const auto* list : {&bound, &loose})
            for (const Lattice& l : *list) {
                const ecs::Entity e = r.create();
                std::string label = "L";  // (not "L" + …: GCC 12 -Wrestrict false positive)
                label += std::to_string(n++);
                r.emplace<Name>(e, Name{label});
                r.emplace<Lattice>(e, l);
                if (list == &bound) d.lattices.push_back(e);
            }
        if (!d.lattices.empty()) r.emplace<Deformers>(c, d);
        ASSERT_TRUE(save_scene(r, p(name)).ok());
    }

    fs::path dir;
};

// Runs `args` and expects exit status `code` with `message` in the output (refusals and their wording).
void expect_refusal(const std::string& args, int code, const std::string& message) {
    const CliRun r = run(args);
    EXPECT_EQ(r.code, code) << args;
    EXPECT_TRUE(has(r.out, message)) << r.out;
}

// Writes a PLY whose vertex element has exactly the float properties `names`, columns[k] holding the
// values of property k (the inputs with fewer properties than our own files, which deform completes).
void write_vertex_ply(const std::string& path, const std::vector<const char*>& names,
                      std::vector<std::vector<double>> columns) {
    ply::Header h;
    ply::Element e;
    e.name = "vertex";
    e.count = columns.empty() ? 0 : columns[0].size();
    for (const char* n : names) e.properties.push_back({n, ply::Type::float32});
    h.elements.push_back(e);
    auto w = ply::Writer::create(path, h);
    ASSERT_TRUE(w.ok()) << w.message();
    ply::Chunk c;
    c.reset(e);
    c.rows = e.count;
    for (std::size_t k = 0; k < columns.size(); ++k) c.columns[k].values = std::move(columns[k]);
    ASSERT_TRUE(w->write_rows(c).ok());
    ASSERT_TRUE(w->finish().ok());
}

// x y z nx ny nz of every splat, as columns for write_vertex_ply().
std::vector<std::vector<double>> position_normal_columns(const SplatCloud& cloud) {
    std::vector<std::vector<double>> cols(6);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int a = 0; a < 3; ++a) {
            cols[std::size_t(a)].push_back(cloud.positions[i][a]);
            cols[std::size_t(3 + a)].push_back(cloud.normals[i][a]);
        }
    return cols;
}

// Reads one float-triple property group of every vertex.
std::vector<glm::dvec3> column3(const std::string& file, const char* a, const char* b, const char* c) {
    std::vector<glm::dvec3> out;
    auto rd = ply::Reader::open(file);
    EXPECT_TRUE(rd.ok()) << (rd.ok() ? "" : rd.message());
    if (!rd || !rd->seek_element("vertex").ok()) return out;
    ply::Chunk ch;
    while (true) {
        auto n = rd->read_rows(4096, ch);
        if (!n || *n == 0) break;
        const int ia = ch.find(a), ib = ch.find(b), ic = ch.find(c);
        EXPECT_TRUE(ia >= 0 && ib >= 0 && ic >= 0) << file << " lacks " << a;
        if (ia < 0 || ib < 0 || ic < 0) return out;
        for (std::size_t r = 0; r < *n; ++r)
            out.emplace_back(ch.columns[std::size_t(ia)].values[r], ch.columns[std::size_t(ib)].values[r],
                             ch.columns[std::size_t(ic)].values[r]);
    }
    return out;
}

TEST_F(LatticeCli, ConvertStoresAFittedLatticeAndExportsItAsJson) {
    ASSERT_TRUE(assets::save_splat_cloud(grid_cloud(), p("grid.ply")).ok());
    CliRun r = run("convert " + p("grid.ply") + " " + p("fit.glb") + " --lattice fit:4,3,2,pad=0.1,bspline");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "lattice fit:4,3,2,pad=0.1,bspline bound to it")) << r.out;
    // The scene holds the cloud bound to exactly the lattice fit_lattice makes around the stored cloud.
    ecs::Registry reg;
    reg.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(reg, p("fit.glb")).ok());
    ecs::Entity cloud{}, lattice{};
    reg.each_entity([&](ecs::Entity e) {
        if (reg.has<SplatCloud>(e)) cloud = e;
        if (reg.has<Lattice>(e)) lattice = e;
    });
    ASSERT_TRUE(cloud && lattice);
    ASSERT_TRUE(reg.has<Deformers>(cloud));
    EXPECT_EQ(reg.get<Deformers>(cloud).lattices, std::vector<ecs::Entity>{lattice});
    const SplatCloud& sc = reg.get<SplatCloud>(cloud);
    auto want = fit_lattice(sc.positions, sc.origin,
                            FitOptions{{4, 3, 2}, LatticeBasis::bspline, 0.1, FitShape::box});
    ASSERT_TRUE(want.ok());
    const Lattice& got = reg.get<Lattice>(lattice);
    EXPECT_EQ(got.divisions, glm::ivec3(4, 3, 2));
    EXPECT_EQ(got.basis, LatticeBasis::bspline);
    EXPECT_LT(glm::length(got.origin - want->origin), 1e-6);
    for (int a = 0; a < 3; ++a)
        EXPECT_LT(glm::length(got.axes[std::size_t(a)] - want->axes[std::size_t(a)]), 1e-6);
    // info lists it; convert SCENE L.json writes it; the JSON loads back to the same lattice.
    r = run("info " + p("fit.glb"));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "lattice  'grid.lattice': bspline, divisions 4 x 3 x 2")) << r.out;
    EXPECT_TRUE(has(r.out, "deformed by 'grid.lattice'")) << r.out;
    r = run("convert " + p("fit.glb") + " " + p("l.json"));
    ASSERT_EQ(r.code, 0) << r.out;
    auto json = load_lattice(p("l.json"));
    ASSERT_TRUE(json.ok()) << json.message();
    EXPECT_EQ(json->current, got.current);
    EXPECT_EQ(json->origin, got.origin);
    // A fitted lattice straight to JSON, oriented box.
    r = run("convert " + p("fit.glb") + " " + p("obb.json") + " --lattice fit:2,obb");
    ASSERT_EQ(r.code, 0) << r.out;
    ASSERT_TRUE(load_lattice(p("obb.json")).ok());
    // Refusals: PLY cannot hold a lattice; a bad spec fails before the import; no lattice to export.
    expect_refusal("convert " + p("grid.ply") + " " + p("x.ply") + " --lattice fit", 2,
                   "cannot hold a lattice");
    expect_refusal("convert " + p("grid.ply") + " " + p("x.glb") + " --lattice fit:4,q", 2,
                   "fit:4,q: unknown item 'q'");
    expect_refusal("convert " + p("grid.ply") + " " + p("x.json"), 1, "not a scene file");
    ASSERT_EQ(run("convert " + p("grid.ply") + " " + p("plain.glb")).code, 0);
    expect_refusal("convert " + p("plain.glb") + " " + p("x.json"), 1, "plain.glb: has no lattice");
}

TEST_F(LatticeCli, DeformTakesTheLatticeFromASceneFile) {
    const SplatCloud cloud = grid_cloud();
    const Lattice L = stretch_x2(cloud);
    ASSERT_TRUE(save_lattice(p("L.json"), L).ok());
    ASSERT_TRUE(assets::save_splat_ply(cloud, p("grid.ply")).ok());
    save_grid_scene("one.glb", {L});
    CliRun r = run("deform " + p("grid.ply") + " " + p("a.ply") + " --lattice " + p("L.json"));
    ASSERT_EQ(r.code, 0) << r.out;
    r = run("deform " + p("grid.ply") + " " + p("b.ply") + " --lattice " + p("one.glb"));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "deformed by 1 lattice 'L0'")) << r.out;
    const auto a = column3(p("a.ply"), "x", "y", "z"), b = column3(p("b.ply"), "x", "y", "z");
    ASSERT_EQ(a.size(), cloud.size());
    EXPECT_EQ(a, b);  // the same lattice, whichever file it came in
    // The deformation really is the 2x stretch in x (linear precision: exact up to float rounding).
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i].x, 2.0 * double(cloud.positions[i].x), 1e-5);

    // Several unbound lattices: a name is needed; with it, that one is used.
    Lattice other = L;
    reset(other);
    save_grid_scene("two.glb", {}, {L, other});
    expect_refusal("deform " + p("grid.ply") + " " + p("c.ply") + " --lattice " + p("two.glb"), 1,
                   "two.glb: 2 lattices ('L0', 'L1'); choose one with --lattice-name NAME");
    r = run("deform " + p("grid.ply") + " " + p("c.ply") + " --lattice " + p("two.glb") +
            " --lattice-name L0");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(column3(p("c.ply"), "x", "y", "z"), a);
    expect_refusal(
        "deform " + p("grid.ply") + " " + p("c.ply") + " --lattice " + p("two.glb") + " --lattice-name nope",
        1, "two.glb: no lattice named 'nope' (lattices: 'L0', 'L1')");
    save_grid_scene("none.glb", {});
    expect_refusal("deform " + p("grid.ply") + " " + p("c.ply") + " --lattice " + p("none.glb"), 1,
                   "none.glb: has no lattice");

    // A bound chain applies in order (the engine's order): stretch, then the rest lattice (identity).
    save_grid_scene("chain.glb", {L, other});
    r = run("deform " + p("grid.ply") + " " + p("d.ply") + " --lattice " + p("chain.glb"));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "deformed by 2 lattices 'L0', 'L1'")) << r.out;
    EXPECT_EQ(column3(p("d.ply"), "x", "y", "z"), a);

    // Scene in, scene out, without --lattice: the scene's own bound lattice; the output cloud is deformed.
    r = run("deform " + p("one.glb") + " " + p("e.glb"));
    ASSERT_EQ(r.code, 0) << r.out;
    ecs::Registry reg;
    reg.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(reg, p("e.glb")).ok());
    std::size_t clouds = 0;
    reg.view<const SplatCloud>().each([&](ecs::Entity, const SplatCloud& c) {
        ++clouds;
        ASSERT_EQ(c.size(), cloud.size());
        for (std::size_t i = 0; i < c.size(); ++i)
            EXPECT_NEAR(c.origin.x + double(c.positions[i].x), 2.0 * double(cloud.positions[i].x), 1e-5);
    });
    EXPECT_EQ(clouds, 1u);
}

// Axes: J·axis for every splat (J the world Jacobian of the double reference), when the file has axes and
// when it has only normals and a radius (circular axes created first, as import makes them).
TEST_F(LatticeCli, DeformWritesDeformedSplatAxes) {
    const SplatCloud cloud = grid_cloud();
    const Lattice L = stretch_x2(cloud);
    ASSERT_TRUE(save_lattice(p("L.json"), L).ok());
    ASSERT_TRUE(assets::save_splat_ply(cloud, p("axes.ply")).ok());
    {  // x y z nx ny nz radius
        auto cols = position_normal_columns(cloud);
        cols.emplace_back(cloud.size(), 0.05);
        ASSERT_NO_FATAL_FAILURE(
            write_vertex_ply(p("radius.ply"), {"x", "y", "z", "nx", "ny", "nz", "radius"}, std::move(cols)));
    }
    for (const std::string in : {"axes.ply", "radius.ply"}) {
        for (const std::string backend : {"cpu", "reference"}) {
            const CliRun r = run("deform " + p(in) + " " + p("out.ply") + " --lattice " + p("L.json") +
                                 " --backend " + backend);
            ASSERT_EQ(r.code, 0) << r.out;
            EXPECT_TRUE(has(r.out, in == "radius.ply" ? "splat axes (created from normals and radius)"
                                                      : "normals, splat axes deformed"))
                << r.out;
            const auto u = column3(p("out.ply"), "axis_ux", "axis_uy", "axis_uz");
            const auto v = column3(p("out.ply"), "axis_vx", "axis_vy", "axis_vz");
            ASSERT_EQ(u.size(), cloud.size());
            double mean_before = 0.0, mean_after = 0.0;
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                const ReferencePoint rp = reference_point(L, glm::dvec3(cloud.positions[i]));
                ASSERT_TRUE(rp.inside);
                const glm::dvec3 want_u = rp.jacobian * glm::dvec3(cloud.axis_u[i]),
                                 want_v = rp.jacobian * glm::dvec3(cloud.axis_v[i]);
                EXPECT_LT(glm::length(u[i] - want_u), 1e-6) << in << " " << backend << " splat " << i;
                EXPECT_LT(glm::length(v[i] - want_v), 1e-6) << in << " " << backend << " splat " << i;
                mean_before += double(glm::length(cloud.axis_u[i])) + double(glm::length(cloud.axis_v[i]));
                mean_after += glm::length(u[i]) + glm::length(v[i]);
            }
            // A 2x stretch in x of splats lying in xy: the axes grow (by 1.5x on average over the two).
            EXPECT_GT(mean_after, 1.4 * mean_before) << in;
        }
    }
    // Normals but no radius: radii estimated from neighbour spacing exactly as import does (identity fit,
    // so the written axes are the created ones: lengths = assets::estimate_radii).
    {
        ASSERT_NO_FATAL_FAILURE(write_vertex_ply(p("normals.ply"), {"x", "y", "z", "nx", "ny", "nz"},
                                                 position_normal_columns(cloud)));
        const CliRun est = run("deform " + p("normals.ply") + " " + p("est.ply") + " --lattice fit:2");
        ASSERT_EQ(est.code, 0) << est.out;
        EXPECT_TRUE(
            has(est.out, "splat axes (created from normals and radii estimated from neighbour spacing)"))
            << est.out;
        std::vector<glm::vec3> rel;
        for (const glm::vec3& q : cloud.positions) rel.push_back(q - cloud.positions[0]);
        const std::vector<float> radii = assets::estimate_radii(assets::find_neighbours(rel, 6), 6, 1.0f);
        // --estimate-radii (needed beyond 4M points) gives the same file below the limit.
        ASSERT_EQ(
            run("deform " + p("normals.ply") + " " + p("est2.ply") + " --lattice fit:2 --estimate-radii")
                .code,
            0);
        EXPECT_EQ(column3(p("est2.ply"), "axis_ux", "axis_uy", "axis_uz"),
                  column3(p("est.ply"), "axis_ux", "axis_uy", "axis_uz"));
        const auto u = column3(p("est.ply"), "axis_ux", "axis_uy", "axis_uz");
        ASSERT_EQ(u.size(), radii.size());
        for (std::size_t i = 0; i < u.size(); ++i) {
            EXPECT_NEAR(glm::length(u[i]), double(radii[i]), 1e-6) << i;
            EXPECT_NEAR(glm::dot(u[i], glm::dvec3(cloud.normals[i])), 0.0, 1e-6) << i;  // tangent
        }
    }
    // Positions only (no normals): said plainly.
    ASSERT_NO_FATAL_FAILURE(
        write_vertex_ply(p("xyz.ply"), {"x", "y", "z"}, {{0, 1, 0}, {0, 0, 1}, {0, 0, 0}}));
    const CliRun r = run("deform " + p("xyz.ply") + " " + p("o.ply") + " --lattice fit:2");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "positions (no normals in the input); no splat axes (the input has no normals"))
        << r.out;
    EXPECT_TRUE(has(r.out, "deformed by 1 lattice 'fit:2,2,2,pad=0.05'")) << r.out;
}

TEST_F(LatticeCli, OptionErrorsNameTheOption) {
    CliRun r = run("deform --help");
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(has(r.out, "usage: splatffd deform")) << r.out;
    ASSERT_TRUE(assets::save_splat_ply(grid_cloud(), p("g.ply")).ok());
    r = run("convert " + p("g.ply") + " " + p("x.glb") + " --splats -5");
    EXPECT_EQ(r.code, 2);
    EXPECT_TRUE(has(r.out, "--splats: expected an integer in 1..1000000000, got '-5'")) << r.out;
    EXPECT_FALSE(has(r.out, "18446744073709551611")) << r.out;
    r = run("convert " + p("g.ply") + " " + p("x.glb") + " --splats abc");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1)
        << r.out;  // one line, not two contradicting ones
    EXPECT_TRUE(has(r.out, "--splats: expected an integer")) << r.out;
    expect_refusal("deform " + p("g.ply") + " " + p("o.ply") + " --lattice fit --bench 1x", 2,
                   "--bench: expected an integer in 0..1000000, got '1x'");
    expect_refusal("deform " + p("g.ply") + " " + p("o.ply") + " --lattice fit:99", 1,
                   "fit:99: divisions must be integers in 1..64");
    expect_refusal("view sphere --frames -3", 2,
                   "--frames: expected an integer N (frames 0..N-1) or a range A:B");
    expect_refusal("pick sphere --at 1,1 --tolerance abc", 2,
                   "--tolerance: expected a number in 0..1e+06, got 'abc'");
    // profile checks its paths before measuring: one line, the file named, nothing measured.
    r = run("profile sphere --compare " + p("nosuch.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(r.out, "splatffd profile: " + p("nosuch.json") + ": cannot read the baseline report\n");
    r = run("profile sphere --json " + p("no/such/folder/p.json"));
    EXPECT_EQ(r.code, 1);
    EXPECT_TRUE(has(r.out, "does not exist")) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    // Built-in scene names are accepted by convert like by the other commands.
    r = run("convert sphere " + p("s.ply") + " --splats 500");
    EXPECT_EQ(r.code, 0) << r.out;
    r = run("convert face " + p("f.ply"));
    EXPECT_FALSE(has(r.out, "unknown file type")) << r.out;
}

}  // namespace
}  // namespace sffd::ffd
