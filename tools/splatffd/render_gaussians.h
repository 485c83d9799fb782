// `splatffd render GAUSSIANS --out DIR` (issue 17): a 3D Gaussian file (3DGS PLY, .splat, KHR glb)
// is rendered as one frame through the Gaussian GL renderer (systems/gaussian/gl_render.h) on a headless
// EGL context, framed like the engine's default camera (render::framing_camera around the centres'
// bounding sphere). The colours of 3DGS are display-referred, so they go to the PNG as they are.
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "runtime/scene/camera.h"
#include "systems/gaussian/components.h"

namespace sffd::cli {

// The view `render` and `pick` use for a Gaussian file: render::framing_camera around the bounding sphere
// of the centres. `cloud` must not be empty.
Camera gaussian_file_camera(const GaussianCloud& cloud, double aspect);

// Writes DIR/frame_0000.png. background: sRGB 0..1 (PNG alpha 255), else straight alpha. Exit code.
int render_gaussians(const std::string& in, const std::string& out_dir, int width, int height,
                     std::optional<glm::vec3> background);

}  // namespace sffd::cli
