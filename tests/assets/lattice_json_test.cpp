// One JSON form of a lattice (runtime/scene/lattice_json.h) for scene files and lattice files: a lattice
// round-trips bit for bit through both, the scene entry is the lattice file's object plus id/name/transform,
// both point shapes and both key names (older scene files) read in both places, and the same refusals
// (unknown keys, magnitudes above 1e30) apply in both.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice_json.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "tests/assets/test_util.h"

namespace fs = std::filesystem;
using namespace sffd;
using nlohmann::json;

namespace {

fs::path fresh_dir(const std::string& name) { return test::fresh_dir("lattice_json", name); }
using test::slurp;

template <class T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}
bool same_bits(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

void expect_bit_exact(const Lattice& a, const Lattice& b, const std::string& via) {
    EXPECT_TRUE(same_bits(a.origin, b.origin)) << via;
    EXPECT_TRUE(same_bits(a.axes, b.axes)) << via;
    EXPECT_EQ(a.divisions, b.divisions) << via;
    EXPECT_EQ(a.basis, b.basis) << via;
    EXPECT_TRUE(same_bits(a.rest, b.rest)) << via;
    EXPECT_TRUE(same_bits(a.current, b.current)) << via;
}

// A scene holding only `lattice` (named "L", with a transform), saved to `path`.
Status save_lattice_scene(const fs::path& path, const Lattice& lattice) {
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    const ecs::Entity e = r.create();
    r.emplace<Name>(e, Name{"L"});
    r.emplace<Transform>(e, Transform{glm::dvec3(0.5, 0, 0), glm::dquat(1, 0, 0, 0), glm::dvec3(1)});
    r.emplace<Lattice>(e, lattice);
    return save_scene(r, path);
}

Result<Lattice> load_lattice_scene(const fs::path& path) {
    ecs::Registry r;
    r.set_resource<SceneHooks>();  // assets' own formats only
    if (Status s = load_scene(r, path.string()); !s) return s.error();
    std::vector<ecs::Entity> found;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<Lattice>(e)) found.push_back(e);
    });
    if (found.size() != 1) return make_error("expected one lattice, got " + std::to_string(found.size()));
    return r.get<Lattice>(found[0]);
}

// A glTF scene file whose SFFD_scene holds one lattice entry `entry` (no clouds).
fs::path scene_with_entry(const fs::path& dir, const json& entry) {
    const json ext = {{"version", 1},
                      {"lattices", json::array({entry})},
                      {"cameras", json::array({{{"eye", {0, 0, 3}}, {"target", {0, 0, 0}}}})}};
    const fs::path p = dir / "s.gltf";
    EXPECT_TRUE(assets::write_gltf(p, {}, ext.dump()).ok());
    return p;
}

// Everything after "WHERE: " in a message.
std::string problem(const std::string& message, const std::string& where) {
    return message.rfind(where + ": ", 0) == 0 ? message.substr(where.size() + 2)
                                               : "(no '" + where + ": ' prefix) " + message;
}

const json kUnitBox = {
    {"origin", {0, 0, 0}}, {"axes", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}, {"divisions", {1, 1, 1}}};

}  // namespace

TEST(LatticeJson, RoundTripsBitExactlyThroughSceneAndLatticeFiles) {
    const fs::path dir = fresh_dir("round_trip");
    // Awkward doubles on purpose: an origin far from 0, thirds, 0.1 + 0.2, a negative zero, a rest that
    // differs from the uniform grid by one ulp (within the 1e-12 tolerance of rest_is_uniform, which the
    // old lattice writer used to leave the rest out), then a baked (apply_as_rest) rest.
    Lattice l = make_lattice({1e6 + 0.1, -2.0 / 3.0, 3.0},
                             {glm::dvec3(2, 0.1, 0), glm::dvec3(0, 3, 1.0 / 7), glm::dvec3(0.2, 0, 1)},
                             {3, 2, 4}, LatticeBasis::bspline);
    ffd::twist(l, ffd::all_control_points(l), {0, 1, 0}, 0.3);
    l.current[0].x = 0.1 + 0.2;
    l.current[1].y = -0.0;
    l.rest[5].z = std::nextafter(l.rest[5].z, 1e300);

    for (int pass = 0; pass < 2; ++pass) {
        SCOPED_TRACE(pass == 0 ? "rest one ulp off the grid" : "baked rest");
        if (pass == 1) {
            ASSERT_TRUE(ffd::apply_as_rest(l).ok());
            l.current[2] += glm::dvec3(1.0 / 3.0, 0, -1e-17);
        }
        ASSERT_TRUE(save_lattice_scene(dir / "a.gltf", l).ok());
        auto from_scene = load_lattice_scene(dir / "a.gltf");
        ASSERT_TRUE(from_scene.ok()) << from_scene.message();
        expect_bit_exact(l, *from_scene, "scene");

        ASSERT_TRUE(ffd::save_lattice(dir / "a.json", l).ok());
        auto from_file = ffd::load_lattice(dir / "a.json");
        ASSERT_TRUE(from_file.ok()) << from_file.message();
        expect_bit_exact(l, *from_file, "lattice file");

        // Across: scene -> lattice file -> scene.
        ASSERT_TRUE(ffd::save_lattice(dir / "b.json", *from_scene).ok());
        auto b = ffd::load_lattice(dir / "b.json");
        ASSERT_TRUE(b.ok()) << b.message();
        ASSERT_TRUE(save_lattice_scene(dir / "b.gltf", *b).ok());
        auto c = load_lattice_scene(dir / "b.gltf");
        ASSERT_TRUE(c.ok()) << c.message();
        expect_bit_exact(l, *c, "scene -> file -> scene");

        // One form: the scene entry is the lattice file's object plus the entry's own keys.
        json entry = json::parse(slurp(dir / "a.gltf"))["extensions"]["SFFD_scene"]["lattices"][0];
        EXPECT_EQ(entry["name"], "L");
        EXPECT_TRUE(entry.contains("id") && entry.contains("transform"));
        for (const char* key : {"id", "name", "transform"}) entry.erase(key);
        EXPECT_EQ(entry, json::parse(slurp(dir / "a.json")));
        EXPECT_TRUE(
            entry.contains("rest_control_points"));  // the rest is not the uniform grid in either pass
    }

    // A rest exactly on the grid is left out and rebuilt exactly.
    const Lattice at_rest =
        make_lattice({0.1, 0.2, 0.3},
                     {glm::dvec3(1.0 / 3, 0, 0), glm::dvec3(0, 0.7, 0), glm::dvec3(0, 0, 0.9)}, {5, 3, 2});
    const json j = lattice_to_json(at_rest);
    EXPECT_FALSE(j.contains("rest_control_points"));
    auto back = lattice_from_json(j, "x");
    ASSERT_TRUE(back.ok()) << back.message();
    expect_bit_exact(at_rest, *back, "lattice_to_json at rest");
}

TEST(LatticeJson, UnknownKeysAndHugeNumbersAreRefusedInSceneEntriesLikeInLatticeFiles) {
    const fs::path dir = fresh_dir("refusals");
    struct Case {
        const char* name;
        json lattice;  // the lattice object, without the scene entry's own keys
        const char* expect;
    };
    // Values are not empty: tinygltf drops empty arrays, empty objects and nulls from extension JSON, so a
    // scene file's `"controlpoints": []` never reaches the reader.
    json misspelt = kUnitBox;
    misspelt["controlpoints"] = {{0, 0, 0}};
    json huge = kUnitBox;
    huge["control_points"] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 1},
                              {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1e308, 1, 1}};
    json huge_flat = kUnitBox;  // the older scene form
    huge_flat["current"] = {0, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0, 1, 1, -1e31};
    json both = kUnitBox;
    both["rest"] = {0, 0, 0};
    both["rest_control_points"] = {{0, 0, 0}};
    const Case cases[] = {
        {"misspelt", misspelt,
         "unknown key \"controlpoints\" (expected origin, axes, divisions, basis, rest_control_points, "
         "control_points)"},
        {"huge", huge, "control_points[7] is larger than 1e30 in magnitude"},
        {"huge_flat", huge_flat, "current[7] is larger than 1e30 in magnitude"},
        {"both_names", both, "both \"rest_control_points\" and \"rest\" given"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        auto file = ffd::parse_lattice_json(c.lattice.dump(), "l.json");
        ASSERT_FALSE(file.ok());
        EXPECT_EQ(problem(file.message(), "l.json").rfind(c.expect, 0), 0u) << file.message();

        json entry = c.lattice;
        entry["id"] = 0;
        entry["name"] = "L";
        const fs::path p = scene_with_entry(dir, entry);
        ecs::Registry r;
        r.set_resource<SceneHooks>();  // assets' own formats only
        const Status s = load_scene(r, p.string());
        ASSERT_FALSE(s.ok());
        // The same problem, after the scene's prefix; nothing was added.
        EXPECT_EQ(problem(s.message(), p.string() + ": SFFD_scene lattice"),
                  problem(file.message(), "l.json"));
        EXPECT_EQ(r.alive(), 0u);
    }
}

TEST(LatticeJson, BothPointShapesAndBothKeyNamesReadInScenesAndLatticeFiles) {
    const fs::path dir = fresh_dir("shapes");
    Lattice want =
        make_lattice({0, 0, 0}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}, {1, 1, 1});
    want.current[7] = glm::dvec3(1.5, 1.25, 1);
    // What the old scene writer wrote (flat "rest" and "current"), and the lattice file form.
    json old_scene = kUnitBox;
    old_scene["basis"] = "bernstein";
    old_scene["rest"] = {0, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0, 1, 1, 1};
    old_scene["current"] = {0, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0, 1.5, 1.25, 1};
    json file_form = kUnitBox;
    file_form["control_points"] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 1},
                                   {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1.5, 1.25, 1}};
    // Divisions written as 1.0 (older scene files were read that way) still count as integers.
    json float_divisions = file_form;
    float_divisions["divisions"] = {1.0, 1.0, 1.0};
    for (const json& form : {old_scene, file_form, float_divisions}) {
        SCOPED_TRACE(form.dump());
        auto file = ffd::parse_lattice_json(form.dump(), "l.json");
        ASSERT_TRUE(file.ok()) << file.message();
        expect_bit_exact(want, *file, "lattice file");
        json entry = form;
        entry["id"] = 3;
        auto scene = load_lattice_scene(scene_with_entry(dir, entry));
        ASSERT_TRUE(scene.ok()) << scene.message();
        expect_bit_exact(want, *scene, "scene");
    }
}
