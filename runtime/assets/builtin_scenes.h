// Built-in scenes: the paper's two objects.
//   sphere: unit sphere, exactly 59,650 splats on a Fibonacci spiral (even spacing, no pole clusters),
//           uv-mapped (u = longitude, v = colatitude), procedural texture: a 16x8 black/white checker
//           whose light cells carry a hue per latitude band, with dark grid lines every cell, so stretching
//           (cells change size) and twisting (meridian lines turn into spirals) are obvious. Splat axes
//           follow the texture directions (axis_u east, axis_v south). 11x11x11 Bernstein lattice
//           (divisions 10) around it.
//   face:   a real head scan (npm `snowden`, MIT) converted at set-up time by tools/fetch_content.sh into
//           paths::cache_dir()/face.glb with exactly 40,880 splats; 11x11x11 Bernstein lattice around it.
// Each also gets a Camera and a DirectionalLight + AmbientLight.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/assets/import.h"
#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"

namespace sffd::assets {

constexpr std::size_t kSphereSplats = 59650;
constexpr std::size_t kFaceSplats = 40880;
constexpr int kBuiltinLatticeDivisions = 10;  // 11 control points per axis

SplatCloud make_sphere_cloud(std::size_t splats = kSphereSplats);
Image make_sphere_texture(int width = 1024, int height = 512);
// Where the converted face lives (tools/fetch_content.sh writes it).
std::filesystem::path face_cache_path();
// The script that fills that cache, as a path the user can run: <data root>/tools/fetch_content.sh (the
// source tree's, or <prefix>/share/splatffd/tools/ in an installed copy).
std::string fetch_script();

// A rest lattice (current == rest) spanning the box [lo, hi] with the given divisions.
Lattice make_box_lattice(const glm::dvec3& lo, const glm::dvec3& hi, glm::ivec3 divisions,
                         LatticeBasis basis);

// Creates the scene's entities in `registry`. Errors name the scene (and the missing cache file).
Status load_builtin_scene(ecs::Registry& registry, const std::string& name);
bool is_builtin_scene(const std::string& name);

// Adds a camera framing world-space box [lo, hi] and default lights (used for imported files too).
void add_default_view(ecs::Registry& registry, const glm::dvec3& lo, const glm::dvec3& hi,
                      const glm::dvec3& view_dir);

}  // namespace sffd::assets
