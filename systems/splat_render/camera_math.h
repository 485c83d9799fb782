// The renderer's cameras: a framing camera, the scene's default camera and the camera part of the
// FrameBlock. The matrices themselves (view, projection, model) are runtime/scene/camera.h's.
#pragma once

#include <functional>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"
#include "shaders/splat_render/frame_block.h"

namespace sffd::render {

// A camera that frames a bounding sphere: looks at its centre from `direction` (towards the camera),
// distance chosen so the sphere fits the smaller field of view with a margin; near/far around it.
Camera framing_camera(const glm::dvec3& center, double radius, double aspect,
                      glm::dvec3 direction = glm::dvec3(0.0, 0.0, 1.0), float fov_y_degrees = 45.0f);

// The camera a scene is seen through: its first Camera entity, else framing_camera() around the union of
// every non-empty cloud's world-space bounding sphere (bounding_sphere(), model_matrix()). The one
// definition of the default camera, shared by render_system, `splatffd pick` and anything else that must
// see what `splatffd render` draws. `bounds` may supply cached per-cloud spheres (cloud space; a radius
// < 0 skips the cloud); by default bounding_sphere() is computed on each call (O(splats)).
struct BoundingSphere;
using CloudBounds = std::function<BoundingSphere(ecs::Entity, const SplatCloud&)>;
// 3D Gaussian clouds (GaussianCloud) are framed too: `gaussian_bounds` may supply cached spheres (by
// default gaussian_bounding_sphere(), gaussian_pass.h).
using GaussianBounds = std::function<BoundingSphere(ecs::Entity, const GaussianCloud&)>;
Camera scene_camera(const ecs::Registry& registry, double aspect, const CloudBounds& bounds = {},
                    const GaussianBounds& gaussian_bounds = {});

// The sphere scene_camera() frames: around the union of every non-empty cloud's world-space bounding
// sphere (splat and Gaussian clouds), radius at least 1e-9; a unit sphere at the origin when there is none.
struct SceneSphere {
    glm::dvec3 center{0.0};
    double radius = 1.0;
};
SceneSphere scene_sphere(const ecs::Registry& registry, const CloudBounds& bounds = {},
                         const GaussianBounds& gaussian_bounds = {});

// The camera's part of the splat passes' FrameBlock (shaders/splat_render/frame_block.h) for a
// width x height frame: projection, view_to_world, viewport, the pixel-ray map, and model_view /
// normal_view for a cloud whose positions are world positions (render_system replaces those two per cloud).
// params = (visibility_epsilon, max_point_size, culling, 0); lights, material and counts are left zero,
// base_color one (packed colours drawn as they are).
gpu::FrameBlock camera_frame_block(const glm::dmat4& view, const glm::dmat4& projection, int width,
                                   int height, float visibility_epsilon, float max_point_size, bool culling);

}  // namespace sffd::render
