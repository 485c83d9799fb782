#include "systems/gaussian/reference_render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/gtc/matrix_transform.hpp>

#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

namespace {

struct Splat2D {
    glm::dvec2 center;
    glm::dvec3 conic;  // inverse of Σ₂: (a, b, c) for [[a b][b c]]
    glm::vec3 color;
    float opacity;
    double depth;
    int x0, x1, y0, y1;  // pixel bounds (inclusive)
};

}  // namespace

ReferenceImage render_reference(const GaussianCloud& g, const Camera& cam, const ReferenceOptions& o,
                                const std::vector<float>* opacity_override) {
    ReferenceImage img;
    img.width = o.width, img.height = o.height;
    img.color.assign(std::size_t(o.width) * std::size_t(o.height), glm::vec3(0.0f));
    img.transmittance.assign(img.color.size(), 1.0f);
    const std::vector<float>& opac = opacity_override ? *opacity_override : g.opacities;
    const glm::dmat4 view = glm::lookAt(cam.eye, cam.target, cam.up);
    const glm::dmat3 w(view);
    const double tan_half = std::tan(glm::radians(double(cam.fov_y_degrees)) * 0.5);
    const double f = o.height / (2.0 * tan_half);
    const double cx = o.width * 0.5, cy = o.height * 0.5;
    const double lim_x = 1.3 * tan_half * o.width / o.height, lim_y = 1.3 * tan_half;
    const int K = sh_coeffs(g.sh_degree);

    std::vector<Splat2D> splats;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dvec3 world = g.origin + glm::dvec3(g.positions[i]);
        const glm::dvec3 t = glm::dvec3(view * glm::dvec4(world, 1.0));
        const double depth = -t.z;
        if (depth < o.near_plane) continue;
        const double px = cx + f * t.x / depth, py = cy - f * t.y / depth;
        // Projection Jacobian (rows: pixel x, pixel y; columns: view x, y, z), with clamped x/z, y/z.
        const double tx = std::clamp(t.x / depth, -lim_x, lim_x) * depth,
                     ty = std::clamp(t.y / depth, -lim_y, lim_y) * depth;
        const glm::dvec3 jx(f / depth, 0.0, f * tx / (depth * depth));
        const glm::dvec3 jy(0.0, -f / depth, -f * ty / (depth * depth));
        const glm::dmat3 sigma_view =
            w * covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i])) * glm::transpose(w);
        double a = glm::dot(jx, sigma_view * jx) + 0.3, b = glm::dot(jx, sigma_view * jy),
               c = glm::dot(jy, sigma_view * jy) + 0.3;
        const double det = a * c - b * b;
        if (!(det > 0.0)) continue;
        const double mid = 0.5 * (a + c), lmax = mid + std::sqrt(std::max(0.1, mid * mid - det));
        const double radius = std::ceil(3.0 * std::sqrt(lmax));
        Splat2D s;
        s.center = {px, py};
        s.conic = glm::dvec3(c / det, -b / det, a / det);
        s.x0 = std::max(0, int(std::floor(px - radius))),
        s.x1 = std::min(o.width - 1, int(std::ceil(px + radius)));
        s.y0 = std::max(0, int(std::floor(py - radius))),
        s.y1 = std::min(o.height - 1, int(std::ceil(py + radius)));
        if (s.x0 > s.x1 || s.y0 > s.y1) continue;
        glm::vec3 dir(glm::normalize(world - cam.eye));
        if (g.sh_frames.size() == g.size())
            dir = glm::transpose(g.sh_frames[i]) * dir;  // view-direction mode
        s.color = sh_color(g.sh_degree, &g.sh[i * std::size_t(K) * 3], dir);
        s.opacity = opac[i];
        s.depth = depth;
        splats.push_back(s);
    }
    std::stable_sort(splats.begin(), splats.end(),
                     [](const Splat2D& x, const Splat2D& y) { return x.depth < y.depth; });

    std::vector<unsigned char> done(img.color.size(), 0);
    for (const Splat2D& s : splats)
        for (int y = s.y0; y <= s.y1; ++y)
            for (int x = s.x0; x <= s.x1; ++x) {
                const std::size_t p = img.index(x, y);
                if (done[p]) continue;
                const double dx = x + 0.5 - s.center.x, dy = y + 0.5 - s.center.y;
                const double power = -0.5 * (s.conic.x * dx * dx + s.conic.z * dy * dy) - s.conic.y * dx * dy;
                if (power > 0.0) continue;
                const float alpha = std::min(0.99f, s.opacity * float(std::exp(power)));
                if (alpha < 1.0f / 255.0f) continue;
                const float t = img.transmittance[p];
                const float next = t * (1.0f - alpha);
                if (next < 1e-4f) {
                    done[p] = 1;
                    continue;
                }
                img.color[p] += s.color * (alpha * t);
                img.transmittance[p] = next;
            }
    for (std::size_t p = 0; p < img.color.size(); ++p) img.color[p] += img.transmittance[p] * o.background;
    return img;
}

double psnr(const ReferenceImage& a, const ReferenceImage& b) {
    double se = 0.0;
    for (std::size_t p = 0; p < a.color.size(); ++p)
        for (int c = 0; c < 3; ++c) {
            const double d =
                std::clamp(double(a.color[p][c]), 0.0, 1.0) - std::clamp(double(b.color[p][c]), 0.0, 1.0);
            se += d * d;
        }
    const double mse = se / (3.0 * double(a.color.size()));
    return mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
}

}  // namespace sffd::gaussian
