#include "systems/profiling/paper_ffd.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "systems/ffd/deform.h"

namespace sffd::profiling {

namespace {

// Evaluated from the definition on every call, as the paper's per-term formula (eq. 10) reads.
double binomial(int n, int k) {
    double r = 1.0;
    for (int i = 1; i <= k; ++i) r = r * static_cast<double>(n - k + i) / static_cast<double>(i);
    return r;
}

double bernstein(int n, int i, double x) {
    if (i < 0 || i > n) return 0.0;
    return binomial(n, i) * std::pow(1.0 - x, n - i) * std::pow(x, i);
}

// ffd-math.md: dB(n,i,x)/dx = n (B(n-1,i-1,x) - B(n-1,i,x)).
double bernstein_derivative(int n, int i, double x) {
    return static_cast<double>(n) * (bernstein(n - 1, i - 1, x) - bernstein(n - 1, i, x));
}

glm::dvec3 rotate(const glm::dvec3& v, const glm::dvec3& axis, double angle) {
    // Rodrigues' formula, axis unit length.
    const double c = std::cos(angle), s = std::sin(angle);
    return v * c + glm::cross(axis, v) * s + axis * glm::dot(axis, v) * (1.0 - c);
}

}  // namespace

Lattice paper_lattice(const SplatCloud& cloud, int divisions) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const auto& p : cloud.positions) {
        const glm::dvec3 x = cloud.origin + glm::dvec3(p);
        lo = glm::min(lo, x);
        hi = glm::max(hi, x);
    }
    if (cloud.positions.empty()) lo = glm::dvec3(0.0), hi = glm::dvec3(1.0);
    glm::dvec3 extent = hi - lo;
    for (int a = 0; a < 3; ++a)
        if (extent[a] <= 0.0) extent[a] = 1e-3;  // flat clouds still get a non-degenerate box
    lo -= 0.02 * extent;
    extent *= 1.04;

    Lattice l =
        make_lattice(lo, {glm::dvec3(extent.x, 0, 0), glm::dvec3(0, extent.y, 0), glm::dvec3(0, 0, extent.z)},
                     glm::ivec3(divisions), LatticeBasis::bernstein);
    return l;
}

std::vector<std::size_t> paper_case_selection(const Lattice& l, const PaperCase& c) {
    std::vector<std::size_t> sel;
    const glm::ivec3 d = l.divisions;
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k) {
                if (c.local) {
                    // Middle five layers in i and j, top three in k: a bump on the upper side.
                    const bool mid_i = std::abs(2 * i - d.x) <= 4 * std::max(1, d.x / 10);
                    const bool mid_j = std::abs(2 * j - d.y) <= 4 * std::max(1, d.y / 10);
                    const bool top_k = k >= d.z - 2;
                    if (!(mid_i && mid_j && top_k)) continue;
                }
                sel.push_back(l.index(i, j, k));
            }
    return sel;
}

void apply_paper_case(Lattice& l, const PaperCase& c, double amount) {
    l.current = l.rest;
    const auto sel = paper_case_selection(l, c);
    if (sel.empty()) return;
    if (!c.twist) {
        const glm::dvec3 vd = amount * 0.3 * l.axes[2];  // eq. (23)
        for (std::size_t i : sel) l.current[i] += vd;
        return;
    }
    glm::dvec3 centroid(0.0);
    for (std::size_t i : sel) centroid += l.rest[i];
    centroid /= static_cast<double>(sel.size());
    const glm::dvec3 axis = glm::normalize(l.axes[2]);
    const double angle = amount * glm::radians(60.0);  // eq. (24), pivot at the selection's centroid
    for (std::size_t i : sel) l.current[i] = centroid + rotate(l.rest[i] - centroid, axis, angle);
}

void paper_ffd_naive(const Lattice& l, const SplatCloud& cloud, std::vector<glm::vec3>& out_positions,
                     std::vector<glm::vec3>& out_normals, std::size_t begin, std::size_t end) {
    const std::size_t count = cloud.size();
    end = std::min(end, count);
    if (out_positions.size() < count) out_positions.resize(count);
    if (out_normals.size() < count) out_normals.resize(count);
    const int L = l.divisions.x, M = l.divisions.y, N = l.divisions.z;
    const glm::dvec3 S = l.axes[0], T = l.axes[1], U = l.axes[2];
    const glm::dvec3 TxU = glm::cross(T, U), SxU = glm::cross(S, U), SxT = glm::cross(S, T);
    // Rows of M^-1 (ffd-math.md, "Local coordinates").
    const glm::dvec3 r0 = TxU / glm::dot(TxU, S), r1 = SxU / glm::dot(SxU, T), r2 = SxT / glm::dot(SxT, U);
    const bool has_normals = cloud.normals.size() == count;

    for (std::size_t p = begin; p < end; ++p) {
        const glm::dvec3 X = cloud.origin + glm::dvec3(cloud.positions[p]);
        const glm::dvec3 d = X - l.origin;
        const double s = glm::dot(r0, d), t = glm::dot(r1, d), u = glm::dot(r2, d);
        const glm::vec3 n_in = has_normals ? cloud.normals[p] : glm::vec3(0, 0, 1);
        if (s < 0.0 || s > 1.0 || t < 0.0 || t > 1.0 || u < 0.0 || u > 1.0) {
            out_positions[p] = cloud.positions[p];
            out_normals[p] = n_in;
            continue;
        }
        glm::dvec3 X1(0.0), Fs(0.0), Ft(0.0), Fu(0.0);
        for (int i = 0; i <= L; ++i)
            for (int j = 0; j <= M; ++j)
                for (int k = 0; k <= N; ++k) {
                    const glm::dvec3& P = l.current[l.index(i, j, k)];
                    const double bs = bernstein(L, i, s), bt = bernstein(M, j, t), bu = bernstein(N, k, u);
                    X1 += P * (bs * bt * bu);                             // eq. (6)
                    Fs += P * (bernstein_derivative(L, i, s) * bt * bu);  // eqs. (11)-(19), corrected
                    Ft += P * (bs * bernstein_derivative(M, j, t) * bu);
                    Fu += P * (bs * bt * bernstein_derivative(N, k, u));
                }
        // J = [Fs Ft Fu] M^-1: column c of J is Fs*r0[c] + Ft*r1[c] + Fu*r2[c].
        glm::dmat3 J;
        for (int col = 0; col < 3; ++col) J[col] = Fs * r0[col] + Ft * r1[col] + Fu * r2[col];
        // cof(J) N through the one copy of that rule; a zero result (singular J) keeps the input normal.
        const glm::dvec3 n = glm::dvec3(n_in);
        glm::dvec3 n1 = ffd::deformed_normal(J, n);
        if (n1 == glm::dvec3(0.0)) n1 = n;
        out_positions[p] = glm::vec3(X1 - cloud.origin);
        out_normals[p] = glm::vec3(n1);
    }
}

}  // namespace sffd::profiling
