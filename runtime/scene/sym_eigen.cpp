#include "runtime/scene/sym_eigen.h"

#include <algorithm>
#include <cmath>

namespace sffd {

Eigen3 jacobi_eigen(const glm::dmat3& input, const glm::dmat3& v0, const JacobiRule& rule, EigenOrder order) {
    double a[3][3], v[3][3];  // row-major copies (glm is column-major: m[col][row])
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r][c] = input[c][r], v[r][c] = v0[c][r];
    double norm = 0.0;
    if (!rule.relative_to_diagonal)
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) norm += a[r][c] * a[r][c];
    for (int sweep = 0; sweep < rule.max_sweeps; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double scale =
            rule.relative_to_diagonal ? a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2] : norm;
        if (off <= rule.relative * scale || off < rule.floor) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                const double apq = a[p][q];
                if (std::abs(apq) < rule.skip_below) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                // A ← Jᵀ A J with J the rotation in the (p, q) plane; V ← V J.
                for (int k = 0; k < 3; ++k) {
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int idx[3] = {0, 1, 2};
    if (order == EigenOrder::ascending)
        std::sort(idx, idx + 3, [&](int x, int y) { return a[x][x] < a[y][y]; });
    else std::sort(idx, idx + 3, [&](int x, int y) { return a[x][x] > a[y][y]; });
    Eigen3 e;
    for (int i = 0; i < 3; ++i) {
        e.values[i] = a[idx[i]][idx[i]];
        e.vectors[i] = glm::dvec3(v[0][idx[i]], v[1][idx[i]], v[2][idx[i]]);
    }
    return e;
}

}  // namespace sffd
