#include "systems/ffd/operations.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "systems/ffd/deform.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

Selection all_control_points(const Lattice& l) {
    Selection s(l.size());
    for (std::size_t c = 0; c < s.size(); ++c) s[c] = c;
    return s;
}

Selection select_range(const Lattice& l, glm::ivec3 lo, glm::ivec3 hi) {
    lo = glm::max(lo, glm::ivec3(0));
    hi = glm::min(hi, l.divisions);
    Selection s;
    for (int i = lo.x; i <= hi.x; ++i)
        for (int j = lo.y; j <= hi.y; ++j)
            for (int k = lo.z; k <= hi.z; ++k) s.push_back(l.index(i, j, k));
    return s;
}

glm::dvec3 centroid(const Lattice& l, const Selection& sel) {
    glm::dvec3 c(0.0);
    for (std::size_t i : sel) c += l.current[i];
    return sel.empty() ? c : c / double(sel.size());
}

void stretch(Lattice& l, const Selection& sel, const glm::dvec3& v) {
    for (std::size_t i : sel) l.current[i] += v;
}

static glm::dvec3 rotate(const glm::dvec3& p, const glm::dvec3& a, double angle) {
    // Rodrigues, a unit.
    const double c = std::cos(angle), s = std::sin(angle);
    return p * c + glm::cross(a, p) * s + a * glm::dot(a, p) * (1.0 - c);
}

void twist(Lattice& l, const Selection& sel, const glm::dvec3& axis, double angle,
           std::optional<glm::dvec3> pivot) {
    if (glm::length(axis) == 0.0 || sel.empty()) return;
    const glm::dvec3 a = glm::normalize(axis), C = pivot ? *pivot : centroid(l, sel);
    for (std::size_t i : sel) l.current[i] = C + rotate(l.current[i] - C, a, angle);
}

void twist_graded(Lattice& l, const Selection& sel, const glm::dvec3& axis, double rate,
                  std::optional<glm::dvec3> pivot) {
    if (glm::length(axis) == 0.0 || sel.empty()) return;
    const glm::dvec3 a = glm::normalize(axis), C = pivot ? *pivot : centroid(l, sel);
    for (std::size_t i : sel) {
        const double h = glm::dot(l.rest[i] - C, a);
        l.current[i] = C + rotate(l.current[i] - C, a, rate * h);
    }
}

void reset(Lattice& l) { l.current = l.rest; }

Result<Lattice> fit_lattice(const std::vector<glm::vec3>& positions, const glm::dvec3& origin,
                            glm::ivec3 divisions, LatticeBasis basis, double padding) {
    return fit_lattice(positions, origin, FitOptions{divisions, basis, padding, FitShape::box});
}

namespace {

// Eigenvectors (columns) of a symmetric 3x3 matrix by cyclic Jacobi rotations (converges to machine
// precision in a handful of sweeps for 3x3).
glm::dmat3 symmetric_eigenvectors(glm::dmat3 a) {
    glm::dmat3 v(1.0);
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-30 * scale || off == 0.0) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                glm::dmat3 r(1.0);  // rotation in the (p, q) plane: a <- rᵀ a r, v <- v r
                r[p][p] = c, r[q][q] = c, r[q][p] = s, r[p][q] = -s;
                a = glm::transpose(r) * a * r;
                v = v * r;
            }
    }
    return v;
}

// The frame of the oriented box: principal axes of the points, each assigned (sign included) to the
// world axis it is closest to (the permutation with the largest total |cos|).
std::array<glm::dvec3, 3> principal_frame(const std::vector<glm::vec3>& positions) {
    glm::dvec3 mean(0.0);
    for (const glm::vec3& p : positions) mean += glm::dvec3(p);
    mean /= double(positions.size());
    glm::dmat3 cov(0.0);
    for (const glm::vec3& p : positions) {
        const glm::dvec3 d = glm::dvec3(p) - mean;
        cov += glm::outerProduct(d, d);
    }
    const glm::dmat3 v = symmetric_eigenvectors(cov);
    static constexpr int kPerms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int best = 0;
    double best_score = -1.0;
    for (int p = 0; p < 6; ++p) {
        double score = 0.0;
        for (int a = 0; a < 3; ++a)
            score += std::abs(v[kPerms[p][a]][a]);  // eigenvector kPerms[p][a] on world axis a
        if (score > best_score + 1e-12) best_score = score, best = p;
    }
    std::array<glm::dvec3, 3> frame;
    for (int a = 0; a < 3; ++a) {
        glm::dvec3 e = glm::normalize(v[kPerms[best][a]]);
        if (e[a] < 0.0) e = -e;
        frame[std::size_t(a)] = e;
    }
    return frame;
}

}  // namespace

// The fit along `frame` (shape box: the world axes, projected exactly as an AABB).
static Result<Lattice> fit_in_frame(const std::vector<glm::vec3>& positions, const glm::dvec3& origin,
                                    const FitOptions& options, const std::array<glm::dvec3, 3>& frame) {
    const bool box = options.shape == FitShape::box;
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : positions) {
        const glm::dvec3 w = box ? origin + glm::dvec3(p) : glm::dvec3(p);
        for (int a = 0; a < 3; ++a) {
            const double d = box ? w[a] : glm::dot(w, frame[std::size_t(a)]);
            lo[a] = std::min(lo[a], d), hi[a] = std::max(hi[a], d);
        }
    }
    glm::dvec3 extent = hi - lo;
    const double largest = std::max({extent.x, extent.y, extent.z});
    const double thickness = largest > 0.0 ? 1e-3 * largest : 1e-3;
    for (int a = 0; a < 3; ++a)
        if (extent[a] < thickness) {  // flat or collinear along this axis: grow it symmetrically
            lo[a] -= 0.5 * (thickness - extent[a]);
            extent[a] = thickness;
        }
    const double pad = options.padding * std::max({extent.x, extent.y, extent.z});
    const glm::dvec3 start = lo - pad, size = extent + 2.0 * pad;
    glm::dvec3 corner = box ? start : origin;
    if (!box)
        for (int a = 0; a < 3; ++a) corner += start[a] * frame[std::size_t(a)];
    Lattice l = make_lattice(corner, {frame[0] * size.x, frame[1] * size.y, frame[2] * size.z},
                             options.divisions, options.basis);
    if (Status s = validate(l, "fit_lattice()"); !s) return s.error();
    return l;
}

static double box_volume(const Lattice& l) {
    return std::abs(glm::determinant(glm::dmat3(l.axes[0], l.axes[1], l.axes[2])));
}

Result<Lattice> fit_lattice(const std::vector<glm::vec3>& positions, const glm::dvec3& origin,
                            const FitOptions& options) {
    if (positions.empty()) return make_error("fit_lattice(): no points");
    if (!(options.padding >= 0.0) || !std::isfinite(options.padding))
        return make_error("fit_lattice(): padding must be >= 0");
    for (const glm::vec3& p : positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return make_error("fit_lattice(): a point is not finite");
    const std::array<glm::dvec3, 3> world{glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};
    FitOptions aligned = options;
    aligned.shape = FitShape::box;
    if (options.shape == FitShape::box || positions.size() < 2)
        return fit_in_frame(positions, origin, aligned, world);
    // Near-isotropic clouds (a sphere) have no meaningful principal axes: the oriented box is kept only
    // when its tight box (no padding) is at least 5% smaller than the axis-aligned one.
    const std::array<glm::dvec3, 3> frame = principal_frame(positions);
    FitOptions tight = options;
    tight.padding = 0.0;
    aligned.padding = 0.0;
    auto tight_oriented = fit_in_frame(positions, origin, tight, frame);
    auto tight_box = fit_in_frame(positions, origin, aligned, world);
    if (!tight_oriented || !tight_box) return tight_box ? tight_oriented : tight_box;
    if (box_volume(*tight_oriented) < 0.95 * box_volume(*tight_box))
        return fit_in_frame(positions, origin, options, frame);
    aligned.padding = options.padding;
    return fit_in_frame(positions, origin, aligned, world);
}

bool is_fit_spec(std::string_view text) { return text == "fit" || text.rfind("fit:", 0) == 0; }

Result<FitOptions> parse_fit_spec(std::string_view text) {
    const std::string whole(text);
    if (!is_fit_spec(text))
        return make_error(whole + ": a fit spec reads fit[:L,M,N][,pad=P][,obb][,bspline]");
    FitOptions o;
    if (text == "fit") return o;
    std::string_view rest = text.substr(4);
    std::vector<int> divs;
    bool seen_words = false;
    while (!rest.empty() || (divs.empty() && !seen_words)) {
        const std::size_t comma = rest.find(',');
        const std::string part(rest.substr(0, comma));
        rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
        if (part.empty()) return make_error(whole + ": empty item (fit[:L,M,N][,pad=P][,obb][,bspline])");
        if (std::isdigit(static_cast<unsigned char>(part[0])) || part[0] == '-' || part[0] == '+') {
            if (seen_words || divs.size() == 3)
                return make_error(whole + ": divisions come first, at most three (L,M,N)");
            char* end = nullptr;
            const long v = std::strtol(part.c_str(), &end, 10);
            if (*end != '\0' || v < 1 || v > kMaxDivisions)
                return make_error(whole + ": divisions must be integers in 1.." +
                                  std::to_string(kMaxDivisions) + ", got '" + part + "'");
            divs.push_back(int(v));
        } else if (part.rfind("pad=", 0) == 0) {
            seen_words = true;
            const std::string v = part.substr(4);
            char* end = nullptr;
            const double d = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != '\0' || !std::isfinite(d) || d < 0.0 || d > 10.0)
                return make_error(whole + ": pad must be a number in 0..10 (× the largest extent), got '" +
                                  v + "'");
            o.padding = d;
        } else if (part == "obb" || part == "oriented") {
            seen_words = true, o.shape = FitShape::oriented;
        } else if (part == "box" || part == "aabb") {
            seen_words = true, o.shape = FitShape::box;
        } else if (part == "bspline") {
            seen_words = true, o.basis = LatticeBasis::bspline;
        } else if (part == "bernstein") {
            seen_words = true, o.basis = LatticeBasis::bernstein;
        } else {
            return make_error(whole + ": unknown item '" + part + "' (fit[:L,M,N][,pad=P][,obb][,bspline])");
        }
        if (rest.empty()) break;
    }
    if (divs.size() == 1) o.divisions = glm::ivec3(divs[0]);
    else if (divs.size() == 3) o.divisions = glm::ivec3(divs[0], divs[1], divs[2]);
    else if (!divs.empty()) return make_error(whole + ": give one division count (D) or three (L,M,N)");
    return o;
}

std::string fit_spec_string(const FitOptions& o) {
    char pad[64];
    for (int digits = 1; digits <= 17; ++digits) {  // shortest text that reads back to the same double
        std::snprintf(pad, sizeof pad, "%.*g", digits, o.padding);
        if (std::strtod(pad, nullptr) == o.padding) break;
    }
    return "fit:" + std::to_string(o.divisions.x) + "," + std::to_string(o.divisions.y) + "," +
           std::to_string(o.divisions.z) + ",pad=" + pad + (o.shape == FitShape::oriented ? ",obb" : "") +
           (o.basis == LatticeBasis::bspline ? ",bspline" : "");
}

Status apply_as_rest(Lattice& l, const BakeTarget* bake) {
    if (Status s = validate(l); !s) return s;
    if (bake && bake->positions) {
        const std::size_t n = bake->positions->size();
        auto ptr = [n](std::vector<glm::vec3>* v) { return v && v->size() == n ? v->data() : nullptr; };
        const PointsIn in{bake->positions->data(),
                          ptr(bake->normals),
                          ptr(bake->axis_u),
                          ptr(bake->axis_v),
                          n,
                          bake->origin};
        const PointsOut out{bake->positions->data(), ptr(bake->normals), ptr(bake->axis_u),
                            ptr(bake->axis_v)};
        auto r = deform(l, in, out);  // in place
        if (!r) return r.error();
    }
    l.rest = l.current;
    return {};
}

// --- resolution changes: per-axis linear operators on the control grid ----------------------------

using Matrix = std::vector<std::vector<double>>;  // rows x cols

static double binom(int n, int k) {
    if (k < 0 || k > n) return 0.0;
    double r = 1.0;
    for (int i = 1; i <= k; ++i) r = r * double(n - k + i) / double(i);
    return r;
}

// Degree elevation n -> m (m >= n): P'_i = Σ_j C(n,j) C(m-n,i-j) / C(m,i) P_j.
static Matrix elevation(int n, int m) {
    Matrix E(std::size_t(m) + 1, std::vector<double>(std::size_t(n) + 1, 0.0));
    for (int i = 0; i <= m; ++i)
        for (int j = 0; j <= n; ++j) E[i][j] = binom(n, j) * binom(m - n, i - j) / binom(m, i);
    return E;
}

// B-spline doubling n -> 2n: d'_p = Σ_i w_(p−2i) d_i, w = (1,4,6,4,1)/8 at −2..2.
static Matrix doubling(int n) {
    const double w[5] = {1.0 / 8, 4.0 / 8, 6.0 / 8, 4.0 / 8, 1.0 / 8};
    Matrix D(std::size_t(2 * n) + 1, std::vector<double>(std::size_t(n) + 1, 0.0));
    for (int p = 0; p <= 2 * n; ++p)
        for (int i = 0; i <= n; ++i) {
            const int r = p - 2 * i;
            if (r >= -2 && r <= 2) D[p][i] = w[r + 2];
        }
    return D;
}

static Matrix identity(int n) {
    Matrix I(std::size_t(n) + 1, std::vector<double>(std::size_t(n) + 1, 0.0));
    for (int i = 0; i <= n; ++i) I[i][i] = 1.0;
    return I;
}

static double basis_value(LatticeBasis b, int n, int i, double s) {
    if (b == LatticeBasis::bernstein) return binom(n, i) * std::pow(1.0 - s, n - i) * std::pow(s, i);
    const double a = std::abs(n * s - i);
    if (a < 1.0) return (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0;
    if (a < 2.0) return (2.0 - a) * (2.0 - a) * (2.0 - a) / 6.0;
    return 0.0;
}

// Least-squares operator old (n) -> new (m): T = (A_mᵀ A_m)⁻¹ A_mᵀ A_n on samples s_q in [0,1].
static Result<Matrix> least_squares(LatticeBasis b, int n, int m) {
    const int S = std::max(4 * (n + 1), 4 * (m + 1));
    Matrix An(S, std::vector<double>(std::size_t(n) + 1)), Am(S, std::vector<double>(std::size_t(m) + 1));
    for (int q = 0; q < S; ++q) {
        const double s = double(q) / double(S - 1);
        for (int i = 0; i <= n; ++i) An[q][i] = basis_value(b, n, i, s);
        for (int i = 0; i <= m; ++i) Am[q][i] = basis_value(b, m, i, s);
    }
    const int M1 = m + 1, N1 = n + 1;
    // Normal equations [AmᵀAm | AmᵀAn], Gauss-Jordan with partial pivoting.
    Matrix aug(M1, std::vector<double>(std::size_t(M1 + N1), 0.0));
    for (int r = 0; r < M1; ++r)
        for (int q = 0; q < S; ++q) {
            for (int c = 0; c < M1; ++c) aug[r][c] += Am[q][r] * Am[q][c];
            for (int c = 0; c < N1; ++c) aug[r][M1 + c] += Am[q][r] * An[q][c];
        }
    for (int col = 0; col < M1; ++col) {
        int piv = col;
        for (int r = col + 1; r < M1; ++r)
            if (std::abs(aug[r][col]) > std::abs(aug[piv][col])) piv = r;
        if (std::abs(aug[piv][col]) < 1e-300)
            return make_error("lower_resolution(): singular least-squares system");
        std::swap(aug[piv], aug[col]);
        const double inv = 1.0 / aug[col][col];
        for (double& v : aug[col]) v *= inv;
        for (int r = 0; r < M1; ++r)
            if (r != col && aug[r][col] != 0.0) {
                const double f = aug[r][col];
                for (int c = 0; c < M1 + N1; ++c) aug[r][c] -= f * aug[col][c];
            }
    }
    Matrix T(M1, std::vector<double>(N1));
    for (int r = 0; r < M1; ++r)
        for (int c = 0; c < N1; ++c) T[r][c] = aug[r][M1 + c];
    return T;
}

// Applies ops[a] along axis a to a (d.x+1)(d.y+1)(d.z+1) grid; returns the grid of the new divisions.
static std::vector<glm::dvec3> apply_ops(const std::vector<glm::dvec3>& grid, glm::ivec3 d,
                                         const Matrix ops[3]) {
    std::vector<glm::dvec3> g = grid;
    glm::ivec3 dims = d + 1;
    for (int a = 0; a < 3; ++a) {
        const Matrix& T = ops[a];
        glm::ivec3 nd = dims;
        nd[a] = int(T.size());
        std::vector<glm::dvec3> out(std::size_t(nd.x) * nd.y * nd.z, glm::dvec3(0.0));
        for (int i = 0; i < nd.x; ++i)
            for (int j = 0; j < nd.y; ++j)
                for (int k = 0; k < nd.z; ++k) {
                    glm::ivec3 idx(i, j, k);
                    const int r = idx[a];
                    glm::dvec3 sum(0.0);
                    for (int c = 0; c < dims[a]; ++c) {
                        idx[a] = c;
                        sum += T[r][c] * g[(std::size_t(idx.x) * dims.y + idx.y) * dims.z + idx.z];
                    }
                    out[(std::size_t(i) * nd.y + j) * nd.z + k] = sum;
                }
        g = std::move(out);
        dims = nd;
    }
    return g;
}

static std::vector<glm::dvec3> displacements(const Lattice& l) {
    std::vector<glm::dvec3> d(l.size());
    for (std::size_t c = 0; c < d.size(); ++c) d[c] = l.current[c] - l.rest[c];
    return d;
}

Result<Lattice> raise_resolution(const Lattice& l, glm::ivec3 div, bool* exact) {
    if (Status s = validate(l); !s) return s.error();
    if (exact) *exact = true;
    Matrix ops[3];
    for (int a = 0; a < 3; ++a) {
        const int n = l.divisions[a], m = div[a];
        if (m < n)
            return make_error("raise_resolution(): divisions must not decrease (use lower_resolution)");
        if (m > kMaxDivisions)
            return make_error("raise_resolution(): at most " + std::to_string(kMaxDivisions) + " divisions");
        if (l.basis == LatticeBasis::bernstein) {
            ops[a] = elevation(n, m);
        } else {
            if (m != n && m != 2 * n)
                return make_error("raise_resolution(): a B-spline axis can only be kept or doubled");
            ops[a] = m == n ? identity(n) : doubling(n);
        }
    }
    Lattice out = l;
    out.divisions = div;
    if (l.basis == LatticeBasis::bernstein) {
        // Degree elevation is linear: elevate rest and current alike (exact for any rest).
        out.rest = apply_ops(l.rest, l.divisions, ops);
        out.current = apply_ops(l.current, l.divisions, ops);
        return out;
    }
    const std::vector<glm::dvec3> d = displacements(l);
    if (exact)
        for (int a = 0; a < 3; ++a) {
            if (div[a] == l.divisions[a]) continue;
            for (int i = 0; i <= l.divisions.x; ++i)
                for (int j = 0; j <= l.divisions.y; ++j)
                    for (int k = 0; k <= l.divisions.z; ++k) {
                        const int idx[3] = {i, j, k};
                        if ((idx[a] == 0 || idx[a] == l.divisions[a]) &&
                            d[l.index(i, j, k)] != glm::dvec3(0.0))
                            *exact = false;
                    }
        }
    const std::vector<glm::dvec3> nd = apply_ops(d, l.divisions, ops);
    out.rest = rest_grid(l.origin, l.axes, div);
    out.current.resize(out.rest.size());
    for (std::size_t c = 0; c < nd.size(); ++c) out.current[c] = out.rest[c] + nd[c];
    return out;
}

Result<Lattice> lower_resolution(const Lattice& l, glm::ivec3 div) {
    if (Status s = validate(l); !s) return s.error();
    Matrix ops[3];
    for (int a = 0; a < 3; ++a) {
        if (div[a] < 1) return make_error("lower_resolution(): divisions must be at least 1");
        if (div[a] == l.divisions[a]) {
            ops[a] = identity(div[a]);
            continue;
        }
        auto T = least_squares(l.basis, l.divisions[a], div[a]);
        if (!T) return T.error();
        ops[a] = std::move(*T);
    }
    Lattice out = l;
    out.divisions = div;
    const std::vector<glm::dvec3> nd = apply_ops(displacements(l), l.divisions, ops);
    out.rest = rest_grid(l.origin, l.axes, div);
    out.current.resize(out.rest.size());
    for (std::size_t c = 0; c < nd.size(); ++c) out.current[c] = out.rest[c] + nd[c];
    return out;
}

}  // namespace sffd::ffd
