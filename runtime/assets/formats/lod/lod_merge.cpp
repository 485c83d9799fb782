#include "runtime/assets/formats/lod/lod_merge.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <glm/gtc/quaternion.hpp>

namespace sffd::lod {

double merge_weight(const glm::vec3& scale, float opacity) {
    double s[3] = {std::abs(double(scale.x)), std::abs(double(scale.y)), std::abs(double(scale.z))};
    std::sort(s, s + 3);
    return double(opacity) * s[1] * s[2];
}

namespace {

double surface(const double s[3]) {
    double t[3] = {s[0], s[1], s[2]};
    std::sort(t, t + 3);
    return t[1] * t[2];
}

}  // namespace

void symmetric_eigen(const double cov[9], double values[3], double vectors[9]) {
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[r][c] = 0.5 * (cov[r * 3 + c] + cov[c * 3 + r]);
    for (int sweep = 0; sweep < 64; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-30 * diag || off == 0.0) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) {  // A ← Jᵀ A J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq, a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk, a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq, v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int x, int y) { return a[x][x] < a[y][y]; });
    for (int j = 0; j < 3; ++j) {
        values[j] = a[order[j]][order[j]];
        for (int k = 0; k < 3; ++k) vectors[k * 3 + j] = v[k][order[j]];
    }
    // Right-handed: the third column is the cross product of the first two.
    const double x = vectors[3] * vectors[7] - vectors[6] * vectors[4];
    const double y = vectors[6] * vectors[1] - vectors[0] * vectors[7];
    const double z = vectors[0] * vectors[4] - vectors[3] * vectors[1];
    const double det = x * vectors[2] + y * vectors[5] + z * vectors[8];
    if (det < 0)
        for (int k = 0; k < 3; ++k) vectors[k * 3 + 2] = -vectors[k * 3 + 2];
}

void merge_gaussians(const GaussianCloud& in, std::span<const std::uint32_t> members, GaussianCloud& out) {
    const std::size_t K3 = std::size_t(sh_coeffs(in.sh_degree)) * 3;
    double wsum = 0;
    for (const std::uint32_t i : members) wsum += merge_weight(in.scales[i], in.opacities[i]);
    const bool uniform = !(wsum > 0);
    if (uniform) wsum = double(members.size());
    const auto weight = [&](std::uint32_t i) {
        return uniform ? 1.0 : merge_weight(in.scales[i], in.opacities[i]);
    };
    glm::dvec3 mean(0.0);
    for (const std::uint32_t i : members) mean += weight(i) * (in.origin + glm::dvec3(in.positions[i]));
    mean /= wsum;
    double cov[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    const std::size_t first_sh = out.sh.size();
    out.sh.resize(first_sh + K3, 0.0f);
    std::vector<double> sh(K3, 0.0);
    double covered = 0, max_opacity = 0;
    for (const std::uint32_t i : members) {
        const double w = weight(i) / wsum;
        const glm::dquat q(in.rotations[i]);
        const glm::dmat3 r = glm::mat3_cast(q);  // column-major: r[c][row]
        const double s[3] = {in.scales[i].x, in.scales[i].y, in.scales[i].z};
        const glm::dvec3 d = in.origin + glm::dvec3(in.positions[i]) - mean;
        for (int row = 0; row < 3; ++row)
            for (int col = 0; col < 3; ++col) {
                double sum = d[row] * d[col];
                for (int k = 0; k < 3; ++k) sum += r[k][row] * s[k] * s[k] * r[k][col];
                cov[row * 3 + col] += w * sum;
            }
        for (std::size_t j = 0; j < K3; ++j) sh[j] += w * double(in.sh[std::size_t(i) * K3 + j]);
        covered += double(in.opacities[i]) * surface(s);
        max_opacity = std::max(max_opacity, double(in.opacities[i]));
    }
    double values[3], vectors[9];
    symmetric_eigen(cov, values, vectors);
    double scale[3];
    for (int k = 0; k < 3; ++k) scale[k] = std::sqrt(std::max(0.0, values[k]));
    glm::dmat3 frame;
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) frame[c][row] = vectors[row * 3 + c];
    glm::dquat q = glm::normalize(glm::quat_cast(frame));
    if (q.w < 0) q = -q;
    const double s_parent = surface(scale);
    const double opacity = s_parent > 0 ? std::min(1.0, covered / s_parent) : max_opacity;
    out.positions.push_back(glm::vec3(mean - out.origin));
    out.scales.push_back(glm::vec3(float(scale[0]), float(scale[1]), float(scale[2])));
    out.rotations.push_back(glm::quat(q));
    out.opacities.push_back(float(std::clamp(opacity, 0.0, 1.0)));
    for (std::size_t j = 0; j < K3; ++j) out.sh[first_sh + j] = float(sh[j]);
}

}  // namespace sffd::lod
