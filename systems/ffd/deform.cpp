#include "systems/ffd/deform.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

const char* backend_name(Backend b) {
    switch (b) {
        case Backend::automatic: return "automatic";
        case Backend::fast: return "fast";
        case Backend::sparse: return "sparse";
        case Backend::reference: return "reference";
    }
    return "?";
}

std::size_t moved_count(const Lattice& l) {
    std::size_t n = 0;
    for (std::size_t c = 0; c < l.current.size() && c < l.rest.size(); ++c) n += l.current[c] != l.rest[c];
    return n;
}

Backend choose_backend(const Lattice& l) {
    // The sparse Bernstein path costs ~18 vector ops per moved control point, the dense one ~7 per
    // control point: sparse wins below ~1/3 moved; stay well below that. B-spline is local already.
    if (l.basis == LatticeBasis::bspline) return Backend::fast;
    return moved_count(l) * 4 <= l.size() ? Backend::sparse : Backend::fast;
}

// --- double-precision reference ----------------------------------------------------------------------

static double binomial(int n, int k) {
    double r = 1.0;
    for (int i = 1; i <= k; ++i) r = r * double(n - k + i) / double(i);
    return r;
}
static double bernstein(int n, int i, double s) {
    if (i < 0 || i > n) return 0.0;
    return binomial(n, i) * std::pow(1.0 - s, n - i) * std::pow(s, i);
}
static double bernstein_d(int n, int i, double s) {
    return n * (bernstein(n - 1, i - 1, s) - bernstein(n - 1, i, s));
}
// Uniform cubic B-spline centred at 0 (support -2..2) and its derivative.
static double bspline_n(double x) {
    const double a = std::abs(x);
    if (a < 1.0) return (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0;
    if (a < 2.0) return (2.0 - a) * (2.0 - a) * (2.0 - a) / 6.0;
    return 0.0;
}
static double bspline_nd(double x) {
    const double a = std::abs(x), sg = x < 0 ? -1.0 : 1.0;
    if (a < 1.0) return sg * (-12.0 * a + 9.0 * a * a) / 6.0;
    if (a < 2.0) return sg * -(2.0 - a) * (2.0 - a) / 2.0;
    return 0.0;
}

ReferencePoint reference_point(const Lattice& l, const glm::dvec3& world, double weight) {
    ReferencePoint r;
    r.position = world;
    glm::dvec3 stu = local_coords(l, world);
    if (!inside(stu)) return r;
    r.inside = true;
    if (!(weight > 0.0)) return r;  // a weight-0 point stays at rest (J = I)
    stu = glm::clamp(stu, glm::dvec3(0.0), glm::dvec3(1.0));
    // Per-axis weights from the closed forms (independent of the fast path's recurrences).
    std::vector<double> w[3], dw[3];
    for (int a = 0; a < 3; ++a) {
        const int n = l.divisions[a];
        w[a].resize(std::size_t(n) + 1);
        dw[a].resize(std::size_t(n) + 1);
        for (int i = 0; i <= n; ++i) {
            if (l.basis == LatticeBasis::bernstein) {
                w[a][i] = bernstein(n, i, stu[a]);
                dw[a][i] = bernstein_d(n, i, stu[a]);
            } else {
                w[a][i] = bspline_n(n * stu[a] - i);
                dw[a][i] = n * bspline_nd(n * stu[a] - i);
            }
        }
    }
    glm::dvec3 D(0.0), Ds(0.0), Dt(0.0), Du(0.0);
    for_each_moved(l, [&](int i, int j, int k, const glm::dvec3& d) {
        const double bs = w[0][i], bt = w[1][j], bu = w[2][k];
        D += d * (bs * bt * bu);
        Ds += d * (dw[0][i] * bt * bu);
        Dt += d * (bs * dw[1][j] * bu);
        Du += d * (bs * bt * dw[2][k]);
    });
    // Weighted (PointsIn::weights): X + w D, J_w = I + w (J - I), i.e. D and its derivatives scaled by w.
    r.position = world + weight * D;
    r.jacobian = glm::dmat3(1.0) + weight * (glm::dmat3(Ds, Dt, Du) * inverse_axes(l));
    return r;
}

glm::dvec3 deformed_normal(const glm::dmat3& J, const glm::dvec3& n) {
    const glm::dvec3 a = J[0], b = J[1], c = J[2];
    const glm::dvec3 nn = glm::cross(b, c) * n.x + glm::cross(c, a) * n.y + glm::cross(a, b) * n.z;
    const double len = glm::length(nn);
    return len > 0.0 ? nn / len : nn;
}

static DeformStats run_reference(const Lattice& l, const PointsIn& in, const PointsOut& out) {
    std::atomic<std::size_t> inside_count{0}, inverted{0};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, in.count, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
            std::size_t n_in = 0, n_inv = 0;
            for (std::size_t p = r.begin(); p != r.end(); ++p) {
                const glm::dvec3 local(in.positions[p]);
                const double w = in.weights ? double(in.weights[p]) : 1.0;
                const ReferencePoint rp = reference_point(l, in.origin + local, w);
                const glm::dvec3 moved = local + (rp.position - (in.origin + local));
                out.positions[p] = glm::vec3(moved);
                if (!rp.inside || !(w > 0.0)) {  // outside, or weight 0: unchanged
                    n_in += rp.inside;
                    if (in.normals && out.normals) out.normals[p] = in.normals[p];
                    if (in.axis_u && out.axis_u) out.axis_u[p] = in.axis_u[p];
                    if (in.axis_v && out.axis_v) out.axis_v[p] = in.axis_v[p];
                    if (out.jacobians) out.jacobians[p] = glm::mat3(1.0f);
                    continue;
                }
                ++n_in;
                if (out.jacobians) out.jacobians[p] = glm::mat3(rp.jacobian);
                const double det = glm::determinant(rp.jacobian);
                n_inv += det < 0.0;
                if (in.normals && out.normals) {
                    out.normals[p] = glm::vec3(deformed_normal(rp.jacobian, glm::dvec3(in.normals[p])));
                }
                if (in.axis_u && out.axis_u)
                    out.axis_u[p] = glm::vec3(rp.jacobian * glm::dvec3(in.axis_u[p]));
                if (in.axis_v && out.axis_v)
                    out.axis_v[p] = glm::vec3(rp.jacobian * glm::dvec3(in.axis_v[p]));
            }
            inside_count += n_in;
            inverted += n_inv;
        });
    return DeformStats{inside_count.load(), inverted.load(), Backend::reference};
}

Result<DeformStats> deform(const Lattice& lattice, const PointsIn& in, const PointsOut& out,
                           Backend backend) {
    if (Status s = validate(lattice); !s) return s.error();
    if (in.count > 0 && (!in.positions || !out.positions))
        return make_error("deform(): positions are required");
    for (const glm::dvec3& o : {in.origin})
        if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.z))
            return make_error("deform(): point-cloud origin is not finite");
    if (backend == Backend::automatic) backend = choose_backend(lattice);
    if (backend == Backend::reference) return run_reference(lattice, in, out);
    const detail::Prepared prepared = detail::prepare(lattice, in.origin);
    DeformStats stats = detail::run_fast(prepared, in, out, backend == Backend::sparse);
    stats.backend = backend;
    return stats;
}

}  // namespace sffd::ffd
