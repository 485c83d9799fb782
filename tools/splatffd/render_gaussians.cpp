#include "tools/splatffd/render_gaussians.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "runtime/gfx/context.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gl_render.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/image_io.h"

namespace sffd::cli {

Camera gaussian_file_camera(const GaussianCloud& cloud, double aspect) {
    glm::dvec3 lo(cloud.positions[0]), hi = lo;
    for (const glm::vec3& p : cloud.positions) lo = glm::min(lo, glm::dvec3(p)), hi = glm::max(hi, glm::dvec3(p));
    const glm::dvec3 center = cloud.origin + 0.5 * (lo + hi);
    const double radius = std::max(0.5 * glm::length(hi - lo), 1e-6);
    return render::framing_camera(center, radius, aspect);
}

int render_gaussians(const std::string& in, const std::string& out_dir, int width, int height,
                     std::optional<glm::vec3> background) {
    auto fail = [](const std::string& m) {
        std::fprintf(stderr, "splatffd render: %s\n", m.c_str());
        return 1;
    };
    auto cloud = gaussian::read_gaussians(in);
    if (!cloud) return fail(cloud.message());
    if (cloud->size() == 0) return fail(in + ": no Gaussians");
    const Camera camera = gaussian_file_camera(*cloud, double(width) / double(height));

    auto ctx = gfx::create_context({.headless = true, .width = width, .height = height, .debug = false});
    if (!ctx) return fail(ctx.message());
    int status = 0;
    {
        auto renderer = gaussian::create_gl_renderer();
        if (!renderer) return fail(renderer.message());
        gaussian::ReferenceOptions o;
        o.width = width, o.height = height;
        o.near_plane = double(camera.near_plane);
        const auto t0 = std::chrono::steady_clock::now();
        auto img = gaussian::render_gl(*renderer, *cloud, camera, o);
        if (!img) return fail(img.message());
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        render::Rgba8Image png;
        png.width = width, png.height = height;
        png.pixels.resize(std::size_t(width) * std::size_t(height) * 4);
        auto byte = [](double v) { return std::uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
        for (std::size_t k = 0; k < img->color.size(); ++k) {
            const double alpha = 1.0 - double(img->transmittance[k]);
            const glm::dvec3 premultiplied(img->color[k]);  // background was black: colour is premultiplied
            glm::dvec3 c = background ? premultiplied + (1.0 - alpha) * glm::dvec3(*background)
                                      : (alpha > 0.0 ? premultiplied / alpha : glm::dvec3(0.0));
            for (int ch = 0; ch < 3; ++ch) png.pixels[k * 4 + std::size_t(ch)] = byte(c[ch]);
            png.pixels[k * 4 + 3] = background ? 255 : byte(alpha);
        }
        const std::filesystem::path file = std::filesystem::path(out_dir) / "frame_0000.png";
        if (Status s = render::write_png(file, png); !s) return fail(s.message());
        std::fprintf(stderr, "splatffd render: %s: %zu Gaussians (SH degree %d) -> %s, %dx%d, %.1f ms (%s)\n", in.c_str(),
                     cloud->size(), cloud->sh_degree, file.string().c_str(), width, height, ms, ctx->renderer().c_str());
    }
    return status;
}

}  // namespace sffd::cli
