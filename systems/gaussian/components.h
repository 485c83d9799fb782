// 3D Gaussian splat components: plain data. Owned by systems/gaussian; other systems read them.
//
// A GaussianCloud is the authored cloud as loaded (3DGS PLY, .splat, or converted from a surface cloud);
// the deformation writes a separate DeformedGaussians, the authored cloud is never overwritten.
//
// Conventions (every importer and exporter converts to and from these, see gaussian_io.h):
// - positions relative to `origin` (double), like SplatCloud, so far-away scenes keep float precision;
// - scales: LINEAR standard deviations along the Gaussian's local x, y, z axes (3DGS PLY stores log);
// - rotations: unit quaternions, glm::quat (construct with glm::quat(w, x, y, z); 3DGS PLY stores
//   rot_0..3 = w, x, y, z; glTF stores x, y, z, w). The covariance is Σ = R S Sᵀ Rᵀ with R = mat3_cast(q)
//   and S = diag(scale);
// - opacities: LINEAR in [0, 1] (3DGS PLY stores the logit);
// - sh: spherical-harmonic colour coefficients in the 3DGS basis (systems/gaussian/sh.h), degree
//   `sh_degree` (0..3), K = (sh_degree+1)² coefficients per channel, stored per splat coefficient-major
//   with RGB interleaved: sh[(i*K + k)*3 + c] for splat i, coefficient k (k = 0 is the DC term), channel c.
//   The colour seen along direction d (from the camera to the splat) is max(0, 0.5 + Σ_k sh_k Y_k(d)).
//   (3DGS PLY stores f_dc_0..2 = k 0 for R,G,B, then f_rest per CHANNEL: all R coefficients k=1..K-1,
//   then G, then B.)
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "systems/ffd/components.h"  // DeformInputStamps

namespace sffd {

struct GaussianCloud {
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> scales;
    std::vector<glm::quat> rotations;
    std::vector<float> opacities;
    int sh_degree = 0;
    std::vector<float> sh;  // size() * sh_coeffs(sh_degree) * 3
    // Derived clouds only (deformation with ShMode::rotate_view): when not empty, the colour of splat i
    // along d is evaluated at sh_frames[i]ᵀ d (its SH coefficients were left unrotated; the frame is the
    // orthogonal polar factor of the deformation, a reflection when the cell inverted). Authored clouds
    // and files never carry frames (writers refuse them: bake_sh_frames() first).
    std::vector<glm::mat3> sh_frames;

    std::size_t size() const { return positions.size(); }
};

// Coefficients per channel for a degree: 1, 4, 9, 16.
constexpr int sh_coeffs(int degree) { return (degree + 1) * (degree + 1); }

// Derived output of the Gaussian deformation (gaussian_deform_system) on a GaussianCloud entity that has
// Deformers: same layout as GaussianCloud (opacities are unchanged by a deformation and not copied).
// Covariance Σ' = J Σ Jᵀ stored back as scale + rotation; SH rotated by the polar rotation of J.
struct DeformedGaussians {
    GaussianCloud cloud;            // opacities left empty (read the authored cloud's) unless some
                                    // results were not finite (then theirs are 0); EMPTY when on_gpu
    bool on_gpu = false;            // the GPU pass wrote GpuGaussianStore::clouds[e].deformed (+ frames)
                                    // and no CPU copy exists (gpu_deform.h read_back() makes one)
    bool seen_force_cpu = false;    // the backend choice this output was made with (a switch re-runs)
    std::uint8_t seen_sh_mode = 0;  // the gaussian::ShMode it used (GaussianDeformSettings; a switch re-runs)
    // Statistics (summed over the deformers). GPU path: they arrive a few frames after the deformation
    // (fenced, never waited for) and stay 0 with stats_arrived false until then.
    std::size_t inverted = 0;    // Gaussians whose Jacobian has det < 0
    std::size_t degenerate = 0;  // Gaussians whose Jacobian is (near) singular
    std::size_t not_finite = 0;  // results that were not finite (written transparent, CPU and GPU)
    bool stats_arrived = false;
    std::uint64_t version = 0;  // bumped on every rewrite

    // Change stamps this output was computed from (the system skips unchanged clouds).
    DeformInputStamps seen;

    // Budgeted preview (systems/ffd/preview_budget.h): the last run deformed only `subset.indices` into
    // the GPU store (state preview_cpu); `cloud` is then EMPTY and the next frame that is not a budgeted
    // preview deforms every Gaussian again.
    bool preview = false;
    PreviewSubset subset;
};

}  // namespace sffd
