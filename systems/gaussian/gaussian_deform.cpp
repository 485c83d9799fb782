#include "systems/gaussian/gaussian_deform.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/scene/point_pages.h"
#include "systems/gaussian/gaussian_deform_fast.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

namespace {
// Jacobians are produced per block so the scratch stays small (36 bytes per Gaussian per block).
// A page (runtime/scene/point_pages.h) is one block, so deform_range() over a page computes exactly what
// deform() computes there.
constexpr std::size_t kBlock = 1 << 16;
static_assert(kBlock == kPagePoints);

using detail::finite3;

// Whether Gaussian i of a deformed cloud is finite everywhere a renderer reads it; `shape_ok`: its scale,
// rotation and SH passed detail::finite_shape().
bool finite_result(const GaussianCloud& g, std::size_t i, bool shape_ok, bool frames) {
    if (!shape_ok || !finite3(g.positions[i])) return false;
    if (frames)
        for (int c = 0; c < 3; ++c)
            if (!finite3(g.sh_frames[i][c])) return false;
    return true;
}

}  // namespace

Result<DeformStats> deform(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                           ffd::Backend backend, bool copy_opacities) {
    return deform(lattice, in, out, DeformOptions{backend, copy_opacities, ShMode::rotate_coefficients});
}

void bake_sh_frames(GaussianCloud& g) {
    if (g.sh_frames.size() != g.size()) return g.sh_frames.clear();
    const std::size_t K = std::size_t(sh_coeffs(g.sh_degree));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              if (K > 1 && g.sh_frames[i] != glm::mat3(1.0f))
                                  sh_rotate(sh_rotation(glm::dmat3(g.sh_frames[i]), g.sh_degree),
                                            &g.sh[i * K * 3], &g.sh[i * K * 3]);
                      });
    g.sh_frames.clear();
}

namespace {

// Gaussians [begin, end) of `in` into `out` (sized, set up for the range), in blocks of kBlock from `begin`.
Result<DeformStats> deform_blocks(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                                  const DeformOptions& options, std::size_t begin, std::size_t end) {
    const ffd::Backend backend = options.backend;
    const bool view_mode = options.sh == ShMode::rotate_view;
    const std::size_t n = in.size();
    const int K = sh_coeffs(in.sh_degree);
    const bool frames_in = in.sh_frames.size() == n;
    DeformStats total;
    const std::size_t span = end - begin;
    std::vector<glm::mat3> jac(std::min(span, kBlock));
    std::vector<glm::vec3> centres(
        std::min(span, kBlock));  // the block's input centres (in-place overwrites them)
    const bool drop_opacity = out.opacities.size() == n;
    std::vector<std::uint8_t> to_drop(options.reference_shapes ? 0 : std::min(span, kBlock));
    for (std::size_t first = begin; first < end; first += kBlock) {
        const std::size_t count = std::min(kBlock, end - first);
        std::copy(in.positions.begin() + std::ptrdiff_t(first),
                  in.positions.begin() + std::ptrdiff_t(first + count), centres.begin());
        ffd::PointsIn pin{in.positions.data() + first, nullptr, nullptr, nullptr, count, in.origin};
        pin.weights = options.weights ? options.weights + first : nullptr;  // J_w, the centre's w D
        ffd::PointsOut pout{out.positions.data() + first, nullptr, nullptr, nullptr};
        pout.jacobians = jac.data();
        auto stats = ffd::deform(lattice, pin, pout, backend);
        if (!stats) return stats.error();
        total.inside += stats->inside;
        total.inverted += stats->inverted;
        // One Gaussian: its shape from the Jacobian, its SH rotated by the polar rotation.
        auto deform_one = [&](std::size_t i, std::size_t b, std::size_t& bad) {
            const float* sh_in = &in.sh[i * std::size_t(K) * 3];
            float* sh_out = &out.sh[i * std::size_t(K) * 3];
            if (jac[b] == glm::mat3(1.0f)) {  // outside the lattice or not moved by it
                if (&out != &in) {
                    out.scales[i] = in.scales[i], out.rotations[i] = in.rotations[i];
                    std::copy(sh_in, sh_in + K * 3, sh_out);
                }
                return;
            }
            const glm::dmat3 j(jac[b]);
            double n2 = 0.0;
            for (int c = 0; c < 3; ++c) n2 += glm::dot(j[c], j[c]);
            const bool singular =
                !(std::abs(glm::determinant(j)) > 1e-12 * n2 * std::sqrt(n2));  // as polar_decomposition
            bad += singular;
            const glm::dmat3 rq = glm::mat3_cast(glm::dquat(in.rotations[i]));
            const glm::dvec3 s(in.scales[i]);
            const glm::dmat3 a =
                j * glm::dmat3(rq[0] * s.x, rq[1] * s.y, rq[2] * s.z);  // deformed axes J R S
            // Σ' = (JRS)(JRS)ᵀ; the deformed axes, orthonormalised, are a close guess of its eigenvectors.
            const ScaleRotation sr = decompose_covariance(a * glm::transpose(a), orthonormalize(j * rq));
            out.scales[i] = glm::vec3(sr.scale);
            out.rotations[i] = glm::quat(sr.rotation);
            if (K == 1) {
                if (&out != &in) std::copy(sh_in, sh_in + 3, sh_out);
                return;
            }
            const Polar p = polar_decomposition(j);
            if (!p.ok || view_mode) {
                if (&out != &in) std::copy(sh_in, sh_in + K * 3, sh_out);
                if (p.ok && view_mode)
                    out.sh_frames[i] =
                        glm::mat3(p.rotation) * (frames_in ? in.sh_frames[i] : glm::mat3(1.0f));
                return;
            }
            sh_rotate(sh_rotation(p.rotation, in.sh_degree), sh_in, sh_out);
        };
        std::atomic<std::size_t> degenerate{0}, not_finite{0};
        // As the GPU pass does (deform.comp): a result that is not finite is never left for the renderer; the
        // Gaussian keeps its input centre (the origin if that is not finite) with scale 0 and opacity 0, and
        // is counted. Both CPU kernels pass here. J is tested too, as the shader does: a non-finite J can
        // still give a finite-looking shape.
        auto drop = [&](std::size_t i, std::size_t b) {
            out.positions[i] = finite3(centres[b]) ? centres[b] : glm::vec3(0.0f);  // never a NaN to sort
            out.scales[i] = glm::vec3(0.0f);
            out.rotations[i] = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
            std::fill_n(&out.sh[i * std::size_t(K) * 3], K * 3, 0.0f);
            if (view_mode) out.sh_frames[i] = glm::mat3(1.0f);
            if (drop_opacity) out.opacities[i] = 0.0f;
        };
        auto drop_if_not_finite = [&](std::size_t i, std::size_t b, bool shape_ok) -> std::size_t {
            const glm::mat3& j = jac[b];
            if (finite3(j[0]) && finite3(j[1]) && finite3(j[2]) && finite_result(out, i, shape_ok, view_mode))
                return 0;
            drop(i, b);
            return 1;
        };
        if (!options.reference_shapes) {
            // The vectorised float kernel (the GPU pass's arithmetic); ranges split on whole vectors.
            const detail::FastShapeArgs args{&in,       &out,      jac.data(),    first,
                                             view_mode, frames_in, to_drop.data()};
            const std::size_t w = std::size_t(detail::shape_lane_width());
            const std::size_t groups = (count + w - 1) / w;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 64),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  const std::size_t b0 = r.begin() * w, b1 = std::min(count, r.end() * w);
                                  degenerate += detail::deform_shapes_fast(args, b0, b1);
                                  std::size_t dropped = 0;
                                  for (std::size_t b = b0; b < b1; ++b)
                                      if (to_drop[b]) drop(first + b, b), ++dropped;
                                  not_finite += dropped;
                              });
            total.degenerate += degenerate.load();
            total.not_finite += not_finite.load();
            continue;
        }
        // The reference: double precision per Gaussian (the fast kernel and the GPU pass are tested against
        // it).
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, count, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
                std::size_t bad = 0, dropped = 0;
                for (std::size_t b = r.begin(); b != r.end(); ++b) {
                    const std::size_t i = first + b;
                    deform_one(i, b, bad);
                    const float* sh = &out.sh[i * std::size_t(K) * 3];
                    const bool shape_ok =
                        detail::finite_shape(out.scales[i], out.rotations[i], sh, std::size_t(K) * 3);
                    dropped += drop_if_not_finite(i, b, shape_ok);
                }
                degenerate += bad;
                not_finite += dropped;
            });
        total.degenerate += degenerate.load();
        total.not_finite += not_finite.load();
    }
    return total;
}

}  // namespace

Result<DeformStats> deform(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                           const DeformOptions& options) {
    const bool copy_opacities = options.copy_opacities;
    const bool view_mode = options.sh == ShMode::rotate_view;
    if (!view_mode && !in.sh_frames.empty())
        return make_error(
            "gaussian::deform(): the cloud carries SH frames (view-direction mode): bake_sh_frames() first");
    const std::size_t n = in.size();
    const int K = sh_coeffs(in.sh_degree);
    if (in.scales.size() != n || in.rotations.size() != n || in.sh.size() != n * std::size_t(K) * 3)
        return make_error("gaussian::deform(): cloud arrays differ in size");
    if (&out != &in) {
        out.origin = in.origin;
        out.sh_degree = in.sh_degree;
        out.positions.resize(n), out.scales.resize(n), out.rotations.resize(n), out.sh.resize(in.sh.size());
        if (copy_opacities) out.opacities = in.opacities;
        out.sh_frames = in.sh_frames;
    }
    // Frames are kept when present; the view mode starts them at identity.
    if (view_mode && out.sh_frames.size() != n) out.sh_frames.assign(n, glm::mat3(1.0f));
    return deform_blocks(lattice, in, out, options, 0, n);
}

Result<DeformStats> deform_range(const Lattice& lattice, const GaussianCloud& in, GaussianCloud& out,
                                 const DeformOptions& options, std::size_t first, std::size_t count) {
    const bool view_mode = options.sh == ShMode::rotate_view;
    if (!view_mode && !in.sh_frames.empty())
        return make_error(
            "gaussian::deform(): the cloud carries SH frames (view-direction mode): bake_sh_frames() first");
    const std::size_t n = in.size();
    const std::size_t K3 = std::size_t(sh_coeffs(in.sh_degree)) * 3;
    if (in.scales.size() != n || in.rotations.size() != n || in.sh.size() != n * K3)
        return make_error("gaussian::deform(): cloud arrays differ in size");
    if (out.positions.size() != n || out.scales.size() != n || out.rotations.size() != n ||
        out.sh.size() != n * K3 || (view_mode && out.sh_frames.size() != n) || first % kBlock != 0 ||
        first + count > n)
        return make_error(
            "gaussian::deform_range(): the output is not sized as the cloud, or the range is "
            "not on a block boundary");
    if (&out != &in) {  // what deform() sets up for the whole cloud, for the range
        if (view_mode)
            for (std::size_t i = first; i < first + count; ++i)
                out.sh_frames[i] = in.sh_frames.size() == n ? in.sh_frames[i] : glm::mat3(1.0f);
        if (options.copy_opacities && out.opacities.size() == n && in.opacities.size() == n)
            std::copy_n(in.opacities.begin() + std::ptrdiff_t(first), count,
                        out.opacities.begin() + std::ptrdiff_t(first));
    }
    return deform_blocks(lattice, in, out, options, first, first + count);
}

}  // namespace sffd::gaussian
