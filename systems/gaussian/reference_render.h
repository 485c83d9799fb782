// CPU reference renderer of 3D Gaussians, written for clarity, not speed: the tests' ground
// truth for the deformation and for a future GPU renderer. It follows the 3DGS rasterizer
// (graphdeco-inria/diff-gaussian-rasterization, forward.cu) in our camera convention:
//   - camera: sffd::Camera (eye, target, up, vertical fov), looking down its −Z; pinhole with square
//     pixels, focal f = height / (2 tan(fov/2)), principal point at the image centre; pixel (x, y) has
//     its centre at (x + 0.5, y + 0.5), row 0 at the top;
//   - EWA: Σ₂ = J W Σ Wᵀ Jᵀ + 0.3 I (the 0.3 px² low-pass), J the Jacobian of the perspective projection
//     at the centre with the view-space x/z and y/z clamped to 1.3 × the half field of view (as 3DGS);
//     Gaussians closer than `near` are dropped; footprint radius 3 sqrt(λmax(Σ₂));
//   - colour: SH along the unit direction from the camera to the centre (sh_color: 0.5 + Σ, clamped ≥ 0);
//   - sort by view depth (stable), front-to-back blending: α = min(0.99, o · exp(−½ dᵀ Σ₂⁻¹ d)), skipped
//     below 1/255, a pixel stops once its transmittance would fall below 1e-4;
//     C = Σ cᵢ αᵢ Tᵢ + T_final · background.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"

namespace sffd::gaussian {

struct ReferenceImage {
    int width = 0, height = 0;
    std::vector<glm::vec3> color;      // final colour (background blended in), row 0 at the top
    std::vector<float> transmittance;  // T_final per pixel (1 = nothing drawn)
    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
};

struct ReferenceOptions {
    int width = 256, height = 256;
    glm::vec3 background{0.0f};
    double near_plane = 0.01;
};

// `opacities` overrides cloud.opacities when non-null (a DeformedGaussians cloud has none of its own).
ReferenceImage render_reference(const GaussianCloud& cloud, const Camera& camera,
                                const ReferenceOptions& options,
                                const std::vector<float>* opacities = nullptr);

// Peak signal-to-noise ratio of two same-size images in dB (colours in [0,1]); +inf when identical.
double psnr(const ReferenceImage& a, const ReferenceImage& b);

}  // namespace sffd::gaussian
