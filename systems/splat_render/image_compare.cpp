#include "systems/splat_render/image_compare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace sffd::render {

namespace {

glm::dvec3 display_rgb(const glm::vec4& c) {
    const double a = std::clamp(double(c.w), 0.0, 1.0);
    return glm::dvec3(linear_to_srgb(std::clamp(c.x, 0.0f, 1.0f)),
                      linear_to_srgb(std::clamp(c.y, 0.0f, 1.0f)),
                      linear_to_srgb(std::clamp(c.z, 0.0f, 1.0f))) *
           a;
}

}  // namespace

Result<ImageComparison> compare_images(const FrameImage& a, const FrameImage& b, bool object_only) {
    if (a.width != b.width || a.height != b.height)
        return make_error("images differ in size: " + std::to_string(a.width) + "x" +
                          std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                          std::to_string(b.height));
    const int w = a.width, h = a.height;
    const std::size_t n = std::size_t(w) * std::size_t(h);
    if (a.color.size() != n || b.color.size() != n)
        return make_error("compare_images(): image without colour");
    std::vector<double> ya(n), yb(n);
    std::vector<unsigned char> mask(n);
    ImageComparison r;
    double sum = 0.0, sum_both = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 ca = display_rgb(a.color[k]), cb = display_rgb(b.color[k]);
        ya[k] = 0.299 * ca.x + 0.587 * ca.y + 0.114 * ca.z;
        yb[k] = 0.299 * cb.x + 0.587 * cb.y + 0.114 * cb.z;
        mask[k] = !object_only || a.color[k].w > 0.0f || b.color[k].w > 0.0f;
        if (!mask[k]) continue;
        const glm::dvec3 d = ca - cb;
        sum += glm::dot(d, d);
        ++r.pixels;
        if (a.color[k].w > 0.0f && b.color[k].w > 0.0f) sum_both += glm::dot(d, d), ++r.pixels_both;
        else if (a.color[k].w > 0.0f || b.color[k].w > 0.0f) ++r.pixels_one;
    }
    if (r.pixels == 0) {
        r.psnr = std::numeric_limits<double>::infinity();
        return r;
    }
    r.mse = sum / (3.0 * double(r.pixels));
    r.psnr = r.mse > 0.0 ? 10.0 * std::log10(1.0 / r.mse) : std::numeric_limits<double>::infinity();
    const double mse_both = r.pixels_both ? sum_both / (3.0 * double(r.pixels_both)) : 0.0;
    r.psnr_both =
        mse_both > 0.0 ? 10.0 * std::log10(1.0 / mse_both) : std::numeric_limits<double>::infinity();
    double sum_interior = 0.0;
    if (b.normal.size() == n) {
        const double cos10 = std::cos(10.0 * 3.14159265358979323846 / 180.0);
        auto same = [&](const glm::vec3& m, const glm::vec3& o) {
            return double(glm::dot(m, o)) > cos10 * double(glm::length(m)) * double(glm::length(o));
        };
        const bool a_normals = a.normal.size() == n;
        for (int y = 2; y + 2 < h; ++y)
            for (int x = 2; x + 2 < w; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(w) + std::size_t(x);
                bool interior = true;
                for (int dy = -2; dy <= 2 && interior; ++dy)
                    for (int dx = -2; dx <= 2 && interior; ++dx) {
                        const std::size_t q = std::size_t(y + dy) * std::size_t(w) + std::size_t(x + dx);
                        interior = a.color[q].w > 0.0f && b.color[q].w > 0.0f &&
                                   same(b.normal[k], b.normal[q]) &&
                                   (!a_normals || same(a.normal[q], b.normal[q]));
                    }
                if (!interior) continue;
                const glm::dvec3 d = display_rgb(a.color[k]) - display_rgb(b.color[k]);
                sum_interior += glm::dot(d, d), ++r.pixels_interior;
            }
    }
    const double mse_interior = r.pixels_interior ? sum_interior / (3.0 * double(r.pixels_interior)) : 0.0;
    r.psnr_interior =
        mse_interior > 0.0 ? 10.0 * std::log10(1.0 / mse_interior) : std::numeric_limits<double>::infinity();

    constexpr int radius = 5;
    std::array<double, 2 * radius + 1> g{};
    for (int i = -radius; i <= radius; ++i)
        g[std::size_t(i + radius)] = std::exp(-double(i * i) / (2.0 * 1.5 * 1.5));
    constexpr double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double ssim_sum = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!mask[std::size_t(y) * std::size_t(w) + std::size_t(x)]) continue;
            double wsum = 0.0, ma = 0.0, mb = 0.0, saa = 0.0, sbb = 0.0, sab = 0.0;
            for (int dy = -radius; dy <= radius; ++dy) {
                const int yy = y + dy;
                if (yy < 0 || yy >= h) continue;
                for (int dx = -radius; dx <= radius; ++dx) {
                    const int xx = x + dx;
                    if (xx < 0 || xx >= w) continue;
                    const double wt = g[std::size_t(dx + radius)] * g[std::size_t(dy + radius)];
                    const std::size_t k = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
                    wsum += wt;
                    ma += wt * ya[k], mb += wt * yb[k];
                    saa += wt * ya[k] * ya[k], sbb += wt * yb[k] * yb[k], sab += wt * ya[k] * yb[k];
                }
            }
            ma /= wsum, mb /= wsum;
            const double va = saa / wsum - ma * ma, vb = sbb / wsum - mb * mb, cov = sab / wsum - ma * mb;
            ssim_sum +=
                ((2.0 * ma * mb + c1) * (2.0 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
        }
    r.ssim = ssim_sum / double(r.pixels);
    return r;
}

}  // namespace sffd::render
