// Test scenes for 3D Gaussians: a surface-splat cloud (SplatCloud: discs with tangent axes
// and sRGB colours, e.g. the built-in sphere) converted into flat 3D Gaussians.
#pragma once

#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"

namespace sffd::gaussian {

struct FromSplatsOptions {
    double sigma_per_radius = 0.7;  // in-plane standard deviation = this × the splat's radius per axis
    double thickness = 0.1;         // normal-axis standard deviation = this × the smaller in-plane one
    float opacity = 0.95f;
    SplatMaterial material;  // the cloud's material (its base colour colours a cloud without colours)
};

// One Gaussian per splat: rotation columns (û, n × û, n) with û = axis_u/|axis_u| (normals from the cross
// product of the axes when the cloud has none), scales (σ|axis_u|, σ|axis_v|, thickness), degree-0 SH
// whose colour is the splat's sRGB colour (the 3DGS colour is what is displayed; the material's base
// colour when the cloud has no per-splat colours). Splats without axes get an isotropic scale from
// the mean spacing (cube root of the bounding-box volume per splat).
GaussianCloud gaussians_from_splats(const SplatCloud& cloud, const FromSplatsOptions& options = {});

}  // namespace sffd::gaussian
