// Image quality metrics between two rendered frames (e.g. a splat render and the ground truth of
// ground_truth.h): PSNR and SSIM over the object.
//
// Both are computed on sRGB-encoded colour in [0, 1] (linear colour clamped, then encoded: what a viewer
// sees), premultiplied by alpha so uncovered pixels count as black. The mask (`object_only`) is the pixels
// covered (alpha > 0) in either image: a silhouette that is too large or too small counts against it.
//   PSNR = 10 log10(1 / MSE), MSE over the masked pixels and the three channels (+inf when identical).
//   SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) on luma Y = 0.299 R + 0.587 G + 0.114 B, 11 x 11 Gaussian
//   window (sigma 1.5, cut at the image border and renormalised), C1 = 0.01^2, C2 = 0.03^2; the mean of
//   the SSIM map over the masked pixels (1 when identical).
#pragma once

#include <cstddef>

#include "runtime/core/result.h"
#include "systems/splat_render/image_io.h"

namespace sffd::render {

struct ImageComparison {
    double mse = 0.0;
    double psnr = 0.0;  // dB, +inf for identical images
    double ssim = 1.0;
    std::size_t pixels = 0;  // pixels compared (the mask)
    // Diagnostics: the part of the mask covered in both images (shading and texture, no silhouette error),
    // and the pixels covered in exactly one (silhouette disagreement).
    double psnr_both = 0.0;
    std::size_t pixels_both = 0, pixels_one = 0;
    // The interior: pixels whose 5 x 5 neighbourhood is covered in both images, where the second image's
    // normals (the reference's; needed) turn by less than 10 degrees and the first image's (when it has
    // them) are within 10 degrees of them: away from silhouettes and creases and from places where the
    // first image shows another surface (discs overshooting a crease), so texture filtering and smooth
    // shading only (inf and 0 pixels when there is none).
    double psnr_interior = 0.0;
    std::size_t pixels_interior = 0;
};

// Errors: sizes differ ("images differ in size: WxH vs WxH"); an empty mask gives pixels = 0, psnr = inf.
Result<ImageComparison> compare_images(const FrameImage& a, const FrameImage& b, bool object_only = true);

}  // namespace sffd::render
