#include "systems/gaussian/sh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_math.h"

namespace sffd::gaussian {

namespace {

template <class T, class V>
void basis(int degree, const V& d, T* out) {
    const T x = d.x, y = d.y, z = d.z;
    out[0] = T(kShC0);
    if (degree < 1) return;
    out[1] = T(-kShC1) * y;
    out[2] = T(kShC1) * z;
    out[3] = T(-kShC1) * x;
    if (degree < 2) return;
    const T xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
    out[4] = T(kShC2[0]) * xy;
    out[5] = T(kShC2[1]) * yz;
    out[6] = T(kShC2[2]) * (T(2) * zz - xx - yy);
    out[7] = T(kShC2[3]) * xz;
    out[8] = T(kShC2[4]) * (xx - yy);
    if (degree < 3) return;
    out[9] = T(kShC3[0]) * y * (T(3) * xx - yy);
    out[10] = T(kShC3[1]) * xy * z;
    out[11] = T(kShC3[2]) * y * (T(4) * zz - xx - yy);
    out[12] = T(kShC3[3]) * z * (T(2) * zz - T(3) * xx - T(3) * yy);
    out[13] = T(kShC3[4]) * x * (T(4) * zz - xx - yy);
    out[14] = T(kShC3[5]) * z * (xx - yy);
    out[15] = T(kShC3[6]) * x * (xx - T(3) * yy);
}

// 2l+1 fixed sample directions per band: band 1 the coordinate axes (its evaluation matrix is a signed
// permutation), bands 2 and 3 generic directions without symmetries (a symmetric set, e.g. a Fibonacci
// spiral of 7 points, makes odd bands singular). Conditioning is checked by a test.
std::vector<glm::dvec3> sample_dirs(int band) {
    if (band == 1) return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    std::vector<glm::dvec3> d;
    const int n = 2 * band + 1;
    for (int i = 0; i < n; ++i)
        d.push_back(glm::normalize(glm::dvec3(std::sin(1.7 * i + 0.3 * band), std::cos(2.3 * i + 1.1),
                                              std::sin(3.1 * i + 0.7 + 0.2 * band))));
    return d;
}

// Gauss–Jordan inverse with partial pivoting (n <= 7).
std::vector<double> invert(std::vector<double> a, int n) {
    std::vector<double> inv(std::size_t(n * n), 0.0);
    for (int i = 0; i < n; ++i) inv[std::size_t(i * n + i)] = 1.0;
    for (int c = 0; c < n; ++c) {
        int piv = c;
        for (int r = c + 1; r < n; ++r)
            if (std::abs(a[std::size_t(r * n + c)]) > std::abs(a[std::size_t(piv * n + c)])) piv = r;
        for (int k = 0; k < n; ++k) {
            std::swap(a[std::size_t(c * n + k)], a[std::size_t(piv * n + k)]);
            std::swap(inv[std::size_t(c * n + k)], inv[std::size_t(piv * n + k)]);
        }
        const double p = a[std::size_t(c * n + c)];
        for (int k = 0; k < n; ++k) a[std::size_t(c * n + k)] /= p, inv[std::size_t(c * n + k)] /= p;
        for (int r = 0; r < n; ++r) {
            if (r == c) continue;
            const double f = a[std::size_t(r * n + c)];
            for (int k = 0; k < n; ++k) {
                a[std::size_t(r * n + k)] -= f * a[std::size_t(c * n + k)];
                inv[std::size_t(r * n + k)] -= f * inv[std::size_t(c * n + k)];
            }
        }
    }
    return inv;
}

// Evaluation matrix A[j][m] = Y_{l,m}(d_j) of band l at its sample directions.
std::vector<double> band_matrix(int band, const std::vector<glm::dvec3>& dirs) {
    const int n = 2 * band + 1, first = band * band;
    std::vector<double> a(std::size_t(n * n));
    double y[16];
    for (int j = 0; j < n; ++j) {
        sh_basis(band, dirs[std::size_t(j)], y);
        for (int m = 0; m < n; ++m) a[std::size_t(j * n + m)] = y[first + m];
    }
    return a;
}

struct Tables {
    std::vector<glm::dvec3> dirs[4];
    std::vector<double> inv[4];  // A_l⁻¹
    Tables() {
        for (int l = 1; l <= 3; ++l) {
            dirs[l] = sample_dirs(l);
            inv[l] = invert(band_matrix(l, dirs[l]), 2 * l + 1);
        }
    }
};
const Tables& tables() {
    static const Tables t;
    return t;
}

template <int N>
void band_rotation(int band, const glm::dmat3& rt, float (&out)[N][N]) {
    // B[j][m] = Y_{l,m}(Rᵀ d_j); the rotated function's values at d_j are B c, so D = A⁻¹ B.
    // Fixed-size arrays: this runs once per deformed Gaussian, no heap allocation.
    const Tables& t = tables();
    const int first = band * band;
    double b[N][N];
    double y[16];
    for (int j = 0; j < N; ++j) {
        sh_basis(band, rt * t.dirs[band][std::size_t(j)], y);
        for (int m = 0; m < N; ++m) b[j][m] = y[first + m];
    }
    const double* ainv = t.inv[band].data();
    for (int r = 0; r < N; ++r)
        for (int c = 0; c < N; ++c) {
            double sum = 0.0;
            for (int k = 0; k < N; ++k) sum += ainv[r * N + k] * b[k][c];
            out[r][c] = float(sum);
        }
}

template <int N>
void apply(const float (&d)[N][N], const float* in, float* out) {
    float tmp[N][3];
    for (int r = 0; r < N; ++r)
        for (int ch = 0; ch < 3; ++ch) {
            float s = 0.0f;
            for (int k = 0; k < N; ++k) s += d[r][k] * in[k * 3 + ch];
            tmp[r][ch] = s;
        }
    for (int r = 0; r < N; ++r)
        for (int ch = 0; ch < 3; ++ch) out[r * 3 + ch] = tmp[r][ch];
}

}  // namespace

void sh_basis(int degree, const glm::dvec3& d, double* out) { basis<double>(degree, d, out); }
void sh_basis(int degree, const glm::vec3& d, float* out) { basis<float>(degree, d, out); }

glm::vec3 sh_color(int degree, const float* c, const glm::vec3& d) {
    float y[16];
    basis<float>(degree, d, y);
    glm::vec3 col(0.5f);
    for (int k = 0; k < sh_coeffs(degree); ++k) col += y[k] * glm::vec3(c[k * 3], c[k * 3 + 1], c[k * 3 + 2]);
    return glm::max(col, glm::vec3(0.0f));
}

ShRotation sh_rotation(const glm::dmat3& r, int degree) {
    ShRotation s;
    s.degree = degree;
    const glm::dmat3 rt = glm::transpose(r);
    if (degree >= 1) band_rotation(1, rt, s.band1);
    if (degree >= 2) band_rotation(2, rt, s.band2);
    if (degree >= 3) band_rotation(3, rt, s.band3);
    return s;
}

void sh_rotate(const ShRotation& s, const float* in, float* out) {
    for (int ch = 0; ch < 3; ++ch) out[ch] = in[ch];
    if (s.degree >= 1) apply(s.band1, in + 3, out + 3);
    if (s.degree >= 2) apply(s.band2, in + 12, out + 12);
    if (s.degree >= 3) apply(s.band3, in + 27, out + 27);
}

void sh_sample_tables(int band, glm::dvec3* dirs, double* inverse) {
    const Tables& t = tables();
    std::copy(t.dirs[band].begin(), t.dirs[band].end(), dirs);
    std::copy(t.inv[band].begin(), t.inv[band].end(), inverse);
}

double sh_sample_condition(int band) {
    // Frobenius norms of A and A⁻¹: an upper bound of the 2-norm condition number times n.
    const Tables& t = tables();
    const std::vector<double> a = band_matrix(band, t.dirs[band]);
    double na = 0.0, ni = 0.0;
    for (double v : a) na += v * v;
    for (double v : t.inv[band]) ni += v * v;
    return std::sqrt(na * ni);
}

}  // namespace sffd::gaussian
