// Lattices on an imported cloud in the editor, driven by key events through the input
// system exactly as the window and replays drive it: add (fitted: box / oriented, divisions, basis,
// padding — the same ffd::fit_lattice as `splatffd convert --lattice fit`), several per cloud with their
// order, refit, remove, export / import JSON; each one undo step, undo/redo bit-exact; the scene file keeps
// the lattices and their order.
#include <cmath>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/lattice_manage.h"
#include "systems/ffd/components.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"

using namespace sffd;
using namespace sffd::editor;
namespace fs = std::filesystem;

namespace {

bool same(const Lattice& a, const Lattice& b) {
    auto eq = [](const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& y) {
        return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(glm::dvec3)) == 0;
    };
    return a.origin == b.origin && a.axes == b.axes && a.divisions == b.divisions && a.basis == b.basis &&
           eq(a.rest, b.rest) && eq(a.current, b.current);
}

struct Editor {
    ecs::Registry reg;
    ecs::Entity cloud;
    EditorState* state = nullptr;
    std::uint64_t frame = 0;

    // An imported cloud (no lattice): an ellipsoid of points 2 x 1 x 0.5, rotated 30 degrees about z, far
    // from the world origin (origin 1000, 0, 0).
    Editor() {
        cloud = reg.create();
        reg.emplace<Name>(cloud, Name{"scan"});
        reg.emplace<Transform>(cloud, Transform{});
        SplatCloud& c = reg.emplace<SplatCloud>(cloud);
        c.origin = {1000.0, 0.0, 0.0};
        const double a = 0.5235987755982988;
        for (int i = 0; i < 30; ++i)
            for (int j = 0; j < 15; ++j) {
                const double th = i * 2 * 3.141592653589793 / 30, ph = (j + 0.5) * 3.141592653589793 / 15;
                const glm::dvec3 q(2.0 * std::sin(ph) * std::cos(th), 1.0 * std::sin(ph) * std::sin(th),
                                   0.5 * std::cos(ph));
                c.positions.emplace_back(float(std::cos(a) * q.x - std::sin(a) * q.y),
                                         float(std::sin(a) * q.x + std::cos(a) * q.y), float(q.z));
                c.normals.emplace_back(glm::normalize(glm::vec3(q)));
            }
        Camera& cam = reg.emplace<Camera>(reg.create());
        cam.eye = {1000.0, 0.0, 8.0};
        cam.target = {1000.0, 0.0, 0.0};
        state = &setup_editor(reg, Viewport{800, 600});
    }
    void key(const char* k, std::uint8_t m = 0) {
        InputEvent e;
        e.kind = InputKind::key, e.key = k, e.modifiers = m, e.frame = frame;
        state->events = {e};
        editor_input_system(reg, FrameContext{frame, double(frame) / 60.0, 1 / 60.0});
        ++frame;
    }
    std::vector<ecs::Entity> order() const { return lattices_of(reg, cloud); }
    std::size_t lattice_count() const { return reg.count<Lattice>(); }
};

TEST(LatticeManage, AddSeveralReorderRefitRemoveEachOneUndoStep) {
    Editor ed;
    EXPECT_FALSE(ed.reg.valid(ed.state->active_lattice));  // "no lattice" until one is added
    EXPECT_EQ(ed.lattice_count(), 0u);

    // shift+a: the default fit (axis-aligned, 10 divisions, Bernstein, 5% padding) around the cloud.
    ed.key("a", mods::shift);
    ASSERT_EQ(ed.lattice_count(), 1u);
    const ecs::Entity first = ed.state->active_lattice;
    ASSERT_EQ(ed.order(), std::vector<ecs::Entity>{first});
    const SplatCloud& c = ed.reg.get<SplatCloud>(ed.cloud);
    EXPECT_STREQ(entity_kind(ed.reg, ed.cloud), "surface");
    auto want = ffd::fit_lattice(c.positions, c.origin, ffd::FitOptions{});
    ASSERT_TRUE(want.ok());
    EXPECT_TRUE(same(ed.reg.get<Lattice>(first), *want));
    EXPECT_EQ(ed.reg.get<Name>(first).value, "scan.lattice");
    EXPECT_EQ(ed.state->undo.size(), 1u);
    EXPECT_EQ(ed.state->undo.at(0).label(), "add lattice");

    // A second, oriented B-spline lattice with other divisions: last in the order, active.
    LatticeFitSettings& fit = lattice_fit_settings(ed.reg);
    fit.fit = ffd::FitOptions{{3, 2, 1}, LatticeBasis::bspline, 0.1, ffd::FitShape::oriented};
    ed.key("a", mods::shift);
    ecs::Entity second = ed.state->active_lattice;
    ASSERT_NE(second, first);
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{first, second}));
    EXPECT_EQ(ed.reg.get<Name>(second).value, "scan.lattice2");
    const Lattice& obb = ed.reg.get<Lattice>(second);
    EXPECT_EQ(obb.divisions, glm::ivec3(3, 2, 1));
    EXPECT_EQ(obb.basis, LatticeBasis::bspline);
    // The oriented box follows the cloud's 30-degree rotation: its first axis is (cos 30, sin 30, 0).
    const glm::dvec3 s = glm::normalize(obb.axes[0]);
    EXPECT_NEAR(s.x, std::cos(0.5235987755982988), 1e-3);
    EXPECT_NEAR(s.y, std::sin(0.5235987755982988), 1e-3);
    EXPECT_EQ(ed.state->undo.size(), 2u);

    // Undoing the second add destroys its entity and makes the first active again (not "no lattice"); redo
    // brings it back as a new entity (a new generation), which the undo stack maps the old id to.
    const std::size_t alive = ed.reg.alive();
    ed.key("z", mods::ctrl);
    EXPECT_EQ(ed.lattice_count(), 1u);
    EXPECT_FALSE(ed.reg.valid(second));
    EXPECT_EQ(ed.reg.alive(), alive - 1);
    EXPECT_EQ(ed.state->active_lattice, first);
    ed.key("z", mods::ctrl | mods::shift);
    EXPECT_EQ(ed.lattice_count(), 2u);
    second = ed.state->undo.resolve(second);
    ASSERT_TRUE(ed.reg.valid(second));
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{first, second}));
    EXPECT_EQ(ed.reg.get<Name>(second).value, "scan.lattice2");
    ed.state->active_lattice = second;
    // pageup: the active (second) lattice moves first; undo puts it back; redo again.
    ed.key("pageup");
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{second, first}));
    ed.key("z", mods::ctrl);
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{first, second}));
    ed.key("z", mods::ctrl | mods::shift);
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{second, first}));
    ed.key("pageup");  // already first: nothing recorded
    EXPECT_EQ(ed.state->undo.size(), 3u);

    // tab cycles the active lattice (not an undo step).
    ed.key("tab");
    EXPECT_NE(ed.state->active_lattice, second);
    ed.key("tab");
    EXPECT_EQ(ed.state->active_lattice, second);
    EXPECT_EQ(ed.state->undo.size(), 3u);

    // shift+f refits the active lattice with the current settings: an axis-aligned 2x2x2 box now.
    const Lattice before_refit = ed.reg.get<Lattice>(second);
    fit.fit = ffd::FitOptions{{2, 2, 2}, LatticeBasis::bernstein, 0.0, ffd::FitShape::box};
    ed.key("f", mods::shift);
    auto box = ffd::fit_lattice(c.positions, c.origin, fit.fit);
    ASSERT_TRUE(box.ok());
    EXPECT_TRUE(same(ed.reg.get<Lattice>(second), *box));
    ed.key("z", mods::ctrl);
    EXPECT_TRUE(same(ed.reg.get<Lattice>(second), before_refit));
    ed.key("y", mods::ctrl);
    EXPECT_TRUE(same(ed.reg.get<Lattice>(second), *box));

    // delete removes the active lattice and unbinds it; undo brings it back bit for bit, in its place.
    ed.key("delete");
    EXPECT_EQ(ed.lattice_count(), 1u);
    EXPECT_FALSE(ed.reg.valid(second)) << "the entity goes with its components";
    EXPECT_EQ(ed.order(), std::vector<ecs::Entity>{first});
    EXPECT_EQ(ed.state->active_lattice, first);
    ed.key("z", mods::ctrl);
    EXPECT_EQ(ed.lattice_count(), 2u);
    second = ed.state->undo.resolve(second);
    EXPECT_EQ(ed.order(), (std::vector<ecs::Entity>{second, first}));
    EXPECT_TRUE(same(ed.reg.get<Lattice>(second), *box));
    EXPECT_EQ(ed.reg.get<Name>(second).value, "scan.lattice2");

    // Undo everything: no lattice left (and no empty entity), the cloud follows none (Deformers stays,
    // empty).
    while (ed.state->undo.can_undo()) ed.key("z", mods::ctrl);
    EXPECT_EQ(ed.lattice_count(), 0u);
    EXPECT_TRUE(ed.order().empty());
    ASSERT_TRUE(ed.reg.has<Deformers>(ed.cloud));
    EXPECT_TRUE(ed.reg.get<Deformers>(ed.cloud).lattices.empty());
}

TEST(LatticeManage, ExportImportJsonAndSceneRoundTrip) {
    const fs::path dir = fs::temp_directory_path() / ("sffd_lattice_manage_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    Editor ed;
    LatticeFitSettings& settings = lattice_fit_settings(ed.reg);
    settings.fit.divisions = {4, 3, 2};
    settings.json_path = (dir / "l.json").string();
    ed.key("a", mods::shift);
    const ecs::Entity l = ed.state->active_lattice;
    // An edit, then ctrl+e: the JSON holds exactly the edited lattice.
    ffd::stretch(ed.reg.patch<Lattice>(l), ffd::select_range(ed.reg.get<Lattice>(l), {1, 1, 1}, {2, 2, 1}),
                 {0.1, -0.2, 0.3});
    const Lattice edited = ed.reg.get<Lattice>(l);
    ed.key("e", mods::ctrl);
    auto json = ffd::load_lattice(settings.json_path);
    ASSERT_TRUE(json.ok()) << json.message();
    EXPECT_TRUE(same(*json, edited));
    // Reset, then ctrl+i: the edit comes back from the file as one undo step.
    ed.key("home");
    EXPECT_FALSE(same(ed.reg.get<Lattice>(l), edited));
    const std::size_t steps = ed.state->undo.size();
    ed.key("i", mods::ctrl);
    EXPECT_TRUE(same(ed.reg.get<Lattice>(l), edited));
    EXPECT_EQ(ed.state->undo.size(), steps + 1);
    EXPECT_EQ(ed.state->undo.at(steps).label(), "import lattice");
    ed.key("z", mods::ctrl);
    EXPECT_EQ(ed.reg.get<Lattice>(l).current, ed.reg.get<Lattice>(l).rest);  // back to the reset lattice
    ed.key("z", mods::ctrl | mods::shift);
    // A bad file: a message, nothing changes, no step.
    settings.json_path = (dir / "missing.json").string();
    ed.key("i", mods::ctrl);
    EXPECT_NE(ed.state->status.find("missing.json"), std::string::npos) << ed.state->status;
    EXPECT_EQ(ed.state->undo.size(), steps + 1);

    // A second lattice, then save: the scene reloads with both, bound in the same order, bit for bit.
    ed.key("a", mods::shift);
    SceneHooks::in(ed.reg);  // assets' own formats only
    ASSERT_TRUE(save_scene(ed.reg, dir / "s.glb").ok());
    ecs::Registry back;
    back.set_resource<SceneHooks>();  // assets' own formats only
    ASSERT_TRUE(load_scene(back, (dir / "s.glb").string()).ok());
    std::vector<ecs::Entity> order;
    back.view<const SplatCloud, const Deformers>().each(
        [&](ecs::Entity, const SplatCloud&, const Deformers& d) { order = d.lattices; });
    ASSERT_EQ(order.size(), 2u);
    EXPECT_TRUE(same(back.get<Lattice>(order[0]), edited));
    EXPECT_EQ(back.get<Name>(order[1]).value, "scan.lattice2");
    fs::remove_all(dir);
}

}  // namespace

// 3D Gaussian clouds get lattices like point clouds: shift+a fits one around the Gaussian
// centres and binds it; editing the lattice deforms the Gaussians (gaussian_deform_system).
TEST(LatticeManage, GaussianCloudGetsAFittedLatticeThatDeformsIt) {
    ecs::Registry reg;
    const ecs::Entity g = reg.create();
    reg.emplace<Name>(g, Name{"gaussians"});
    reg.emplace<Transform>(g, Transform{});
    GaussianCloud& c = reg.emplace<GaussianCloud>(g);
    c.origin = {5.0, 0.0, 0.0};
    for (int i = 0; i < 200; ++i) {
        const float t = float(i) / 199.0f;
        c.positions.emplace_back(2.0f * t - 1.0f, 0.5f * std::sin(6.0f * t), 0.25f * std::cos(9.0f * t));
        c.scales.emplace_back(0.05f);
        c.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        c.opacities.push_back(0.9f);
        c.sh.insert(c.sh.end(), {0.1f, 0.2f, 0.3f});
    }
    Camera& cam = reg.emplace<Camera>(reg.create());
    cam.eye = {5.0, 0.0, 8.0};
    cam.target = {5.0, 0.0, 0.0};
    EditorState& state = setup_editor(reg, Viewport{800, 600});
    InputEvent e;
    e.kind = InputKind::key, e.key = "a", e.modifiers = mods::shift;
    state.events = {e};
    editor_input_system(reg, FrameContext{0, 0.0, 1 / 60.0});
    ASSERT_EQ(reg.count<Lattice>(), 1u);
    ASSERT_TRUE(reg.has<Deformers>(g));
    ASSERT_EQ(reg.get<Deformers>(g).lattices.size(), 1u);
    const ecs::Entity l = reg.get<Deformers>(g).lattices[0];
    EXPECT_EQ(l, state.active_lattice);
    // The fitted box holds every centre (world coordinates: origin + position).
    const Lattice& lat = reg.get<Lattice>(l);
    for (const glm::vec3& p : c.positions) {
        const glm::dvec3 w = c.origin + glm::dvec3(p) - lat.origin;
        for (int a = 0; a < 3; ++a) {
            const double s = glm::dot(w, lat.axes[std::size_t(a)]) /
                             glm::dot(lat.axes[std::size_t(a)], lat.axes[std::size_t(a)]);
            EXPECT_GE(s, 0.0);
            EXPECT_LE(s, 1.0);
        }
    }
    // The Lattice panel counts the control points inside the Gaussians' box (not 0: Gaussians are the
    // object too), and the Outliner tags each entity with its type.
    const std::size_t inside = control_points_inside_object(reg, lat);
    EXPECT_GT(inside, 0u);
    EXPECT_LT(inside, lat.size());
    EXPECT_STREQ(entity_kind(reg, g), "Gaussians");
    EXPECT_STREQ(entity_kind(reg, l), "lattice");
    EXPECT_STREQ(entity_kind(reg, state.camera), "camera");
    // Export is named after the active lattice once a folder is set (two lattices, two files).
    lattice_fit_settings(reg).json_folder = "dir";
    EXPECT_EQ(lattice_json_path(reg, state), (fs::path("dir") / "gaussians.lattice.json").string());
    state.events = {e};
    editor_input_system(reg, FrameContext{1, 1 / 60.0, 1 / 60.0});
    ASSERT_EQ(reg.count<Lattice>(), 2u);
    EXPECT_EQ(lattice_json_path(reg, state), (fs::path("dir") / "gaussians.lattice2.json").string());
    reg.patch<Deformers>(g).lattices.pop_back();  // back to one lattice for the deformation below
    // Moving every control point by +y moves every Gaussian by +y.
    gaussian_deform_system(reg, {});
    for (glm::dvec3& p : reg.patch<Lattice>(l).current) p.y += 0.5;
    gaussian_deform_system(reg, {});
    const DeformedGaussians& d = reg.get<DeformedGaussians>(g);
    ASSERT_EQ(d.cloud.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        EXPECT_NEAR(d.cloud.positions[i].y, c.positions[i].y + 0.5f, 1e-4f) << i;
}
