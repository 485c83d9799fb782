// The Gaussian drawing tests' fixture and harness. A headless GL context and, per test, a GaussianHarness
// made in it (failed, or skipped under SFFD_NO_GL=1, where no context can be made), plain (`Base` =
// test::HeadlessGlTest) or parameterised (test::HeadlessGlTestWithParam<P>).
//
// GaussianHarness is the engine's drawing of one Gaussian cloud outside a frame: the render system's renderer
// (render::GlRenderer, systems/splat_render/gaussian_draw.h) and one cloud made resident by the
// residency's own upload (gaussian::upload_rest, as residency_system does), drawn by draw_gaussians into
// an RGBA32F target of the harness and read back with the background blended in like the CPU reference
// (gaussian::render_reference), so images compare with it pixel by pixel. The frame's other work (the
// surface splats, the composite) is tested through render_system (render_system_test.cpp).
#pragma once

#include <chrono>
#include <optional>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/residency.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/gaussian/gpu_upload.h"
#include "systems/gaussian/reference_render.h"
#include "systems/splat_render/gaussian_draw.h"
#include "tests/test_util/headless_gl.h"

namespace sffd::test {

struct GaussianHarness : render::GlRenderer {
    gaussian::GpuGaussians cloud;  // as a GpuGaussianStore entry holds it (state rest)
    bool has_frames = false;       // the cloud's SH frames uploaded into cloud.frames (read as such)
    glm::dvec3 origin{0.0};
    gfx::Texture color;
    gfx::Framebuffer framebuffer;
    int width = 0, height = 0;
    float min_footprint_px = 0.0f;  // GaussianView::min_footprint_px of draw_gl
    double readback_ms = 0.0;       // with stage_timing
};

// The resident cloud's buffers, its SH frames included when it has them.
inline render::GaussianBuffers resident_buffers(const GaussianHarness& r) {
    render::GaussianBuffers b = render::gaussian_buffers(r.cloud);
    if (r.has_frames) b.frames = r.cloud.frames.id(), b.has_frames = true;
    return b;
}

// The cloud (with `opacities` instead of its own when given) made resident through the residency's upload.
inline Status upload_gl(GaussianHarness& r, const GaussianCloud& g,
                        const std::vector<float>* opacities = nullptr) {
    Status s;
    if (opacities) {
        GaussianCloud copy = g;
        copy.opacities = *opacities;
        s = gaussian::upload_rest(r.cloud, copy, 1);
    } else {
        s = gaussian::upload_rest(r.cloud, g, 1);
    }
    if (!s) return s;
    const std::size_t n = g.size();
    r.has_frames = g.sh_frames.size() == n && n > 0;
    if (r.has_frames) {
        std::vector<glm::vec4> cols(n * 3);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t c = 0; c < 3; ++c) cols[i * 3 + c] = glm::vec4(g.sh_frames[i][int(c)], 0.0f);
        gfx::fill_buffer(r.cloud.frames, "test.sh_frames", cols.data(), cols.size() * sizeof(glm::vec4));
    }
    r.origin = g.origin;
    return {};
}

// One draw of the resident cloud (quads, or with blend_path tiles the tile renderer) into the harness's
// target, read back (GL rows bottom-up) with the background blended in by the remaining transmittance.
inline Result<gaussian::ReferenceImage> draw_gl(GaussianHarness& r, const Camera& cam,
                                                const gaussian::ReferenceOptions& o) {
    if (o.width < 1 || o.height < 1) return make_error("draw_gl(): empty image");
    if (r.width != o.width || r.height != o.height) {
        r.color = gfx::Texture::create("test.gaussian_color", GL_TEXTURE_2D);
        glTextureStorage2D(r.color.id(), 1, GL_RGBA32F, o.width, o.height);
        r.framebuffer = gfx::Framebuffer::create("test.gaussian_target");
        glNamedFramebufferTexture(r.framebuffer.id(), GL_COLOR_ATTACHMENT0, r.color.id(), 0);
        r.width = o.width, r.height = o.height;
    }
    render::GaussianView v;
    v.view = glm::lookAt(cam.eye, cam.target, cam.up) * glm::translate(glm::dmat4(1.0), r.origin);
    v.eye = cam.eye - r.origin;
    v.fov_y_degrees = double(cam.fov_y_degrees);
    v.near_plane = double(o.near_plane);
    v.width = o.width, v.height = o.height;
    v.min_footprint_px = r.min_footprint_px;
    glBindFramebuffer(GL_FRAMEBUFFER, r.framebuffer.id());
    glViewport(0, 0, o.width, o.height);
    const float clear[4] = {0, 0, 0, 0};
    glClearNamedFramebufferfv(r.framebuffer.id(), GL_COLOR, 0, clear);
    glDisable(GL_DEPTH_TEST);
    render::TileTargets target;
    target.color = r.color.id();
    const Status drawn = render::draw_gaussians(r, resident_buffers(r), v, nullptr,
                                                r.blend_path == render::BlendPath::tiles ? &target : nullptr);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!drawn) return drawn.error();
    const auto t = std::chrono::steady_clock::now();
    std::vector<glm::vec4> pixels(std::size_t(o.width) * std::size_t(o.height));
    glGetTextureImage(r.color.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(pixels.size() * sizeof(glm::vec4)),
                      pixels.data());
    gaussian::ReferenceImage img;
    img.width = o.width, img.height = o.height;
    img.color.resize(pixels.size());
    img.transmittance.resize(pixels.size());
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
            const glm::vec4 p = pixels[std::size_t(o.height - 1 - y) * std::size_t(o.width) + std::size_t(x)];
            const std::size_t k = img.index(x, y);
            img.transmittance[k] = 1.0f - p.w;
            img.color[k] = glm::vec3(p) + (1.0f - p.w) * o.background;
        }
    r.readback_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    return img;
}

// upload_gl + draw_gl: renders like render_reference() (same camera model, background blended in).
inline Result<gaussian::ReferenceImage> render_gl(GaussianHarness& r, const GaussianCloud& g,
                                                  const Camera& cam, const gaussian::ReferenceOptions& o,
                                                  const std::vector<float>* opacities = nullptr) {
    if (Status s = upload_gl(r, g, opacities); !s) return s.error();
    return draw_gl(r, cam, o);
}

inline Result<GaussianHarness> create_gaussian_harness() {
    auto made = render::create_gl_renderer();
    if (!made) return made.error();
    GaussianHarness r;
    static_cast<render::GlRenderer&>(r) = std::move(*made);
    return r;
}

template <class Base>
class GaussianGlRendererTest : public Base {
protected:
    void SetUp() override {
        Base::SetUp();
        if (this->IsSkipped() || this->HasFatalFailure()) return;
        emplace_made(renderer, create_gaussian_harness());
    }
    void TearDown() override { renderer.reset(); }
    std::optional<GaussianHarness> renderer;
};

}  // namespace sffd::test
