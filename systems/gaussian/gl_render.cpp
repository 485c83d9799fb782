#include "systems/gaussian/gl_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>

#include <tbb/parallel_sort.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "shaders/gaussian/gaussian_layout.h"

namespace sffd::gaussian {

Result<GlRenderer> create_gl_renderer() {
    GlRenderer r;
    auto project = gfx::load_compute_program("gaussian/project.comp", "gaussian.project");
    if (!project) return project.error();
    auto splat = gfx::load_program({{GL_VERTEX_SHADER, "gaussian/splat.vert"}, {GL_FRAGMENT_SHADER, "gaussian/splat.frag"}},
                                   "gaussian.splat");
    if (!splat) return splat.error();
    r.project = std::move(*project);
    r.splat = std::move(*splat);
    r.vao = gfx::VertexArray::create("gaussian.quads");
    r.gaussians = gfx::Buffer::create("gaussian.in");
    r.sh = gfx::Buffer::create("gaussian.sh");
    r.projected = gfx::Buffer::create("gaussian.projected");
    r.order = gfx::Buffer::create("gaussian.order");
    r.frames = gfx::Buffer::create("gaussian.sh_frames");
    r.depth = gfx::Buffer::create("gaussian.depth_keys");
    return r;
}

namespace {

// Buffer storage that grows (never zero-sized: GL needs a store to bind).
void upload(const gfx::Buffer& b, const void* data, std::size_t bytes) {
    glNamedBufferData(b.id(), GLsizeiptr(std::max<std::size_t>(bytes, 16)), nullptr, GL_DYNAMIC_DRAW);
    if (bytes > 0 && data) glNamedBufferSubData(b.id(), 0, GLsizeiptr(bytes), data);
}

void set(GLuint program, const char* name, float v) { glProgramUniform1f(program, glGetUniformLocation(program, name), v); }
void set(GLuint program, const char* name, glm::vec2 v) { glProgramUniform2f(program, glGetUniformLocation(program, name), v.x, v.y); }
void set(GLuint program, const char* name, glm::vec3 v) {
    glProgramUniform3f(program, glGetUniformLocation(program, name), v.x, v.y, v.z);
}

}  // namespace

Result<ReferenceImage> render_gl(GlRenderer& r, const GaussianCloud& g, const Camera& cam, const ReferenceOptions& o,
                                 const std::vector<float>* opacity_override) {
    if (Status s = upload_gl(r, g, opacity_override); !s) return s.error();
    return draw_gl(r, cam, o);
}

Status upload_gl(GlRenderer& r, const GaussianCloud& g, const std::vector<float>* opacity_override) {
    const std::vector<float>& opac = opacity_override ? *opacity_override : g.opacities;
    const std::size_t n = g.size();
    if (opac.size() != n || g.sh.size() != n * std::size_t(sh_coeffs(g.sh_degree)) * 3)
        return make_error("upload_gl(): cloud arrays differ in size");
    if (n >= (std::size_t(1) << 31)) return make_error("upload_gl(): more than 2^31 Gaussians in one draw");
    // Upload (positions relative to the origin; the view matrix carries the origin, composed in double).
    std::vector<gpu::GpuGaussian> in(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p = g.positions[i];
        const glm::quat q = g.rotations[i];
        in[i] = {{p.x, p.y, p.z, opac[i]}, {q.w, q.x, q.y, q.z}, {g.scales[i].x, g.scales[i].y, g.scales[i].z, 0.0f}};
    }
    upload(r.gaussians, in.data(), in.size() * sizeof(gpu::GpuGaussian));
    upload(r.sh, g.sh.data(), g.sh.size() * sizeof(float));
    if (g.sh_frames.size() == n && n > 0) {
        std::vector<glm::vec4> cols(n * 3);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t c = 0; c < 3; ++c) cols[i * 3 + c] = glm::vec4(g.sh_frames[i][int(c)], 0.0f);
        upload(r.frames, cols.data(), cols.size() * sizeof(glm::vec4));
    } else {
        upload(r.frames, nullptr, 0);
    }

    r.count = n, r.sh_degree = g.sh_degree, r.origin = g.origin;
    r.has_frames = g.sh_frames.size() == n && n > 0;
    return {};
}

GaussianBuffers resident_buffers(const GlRenderer& r) {
    return {r.gaussians.id(), r.sh.id(), r.frames.id(), r.count, r.sh_degree, r.has_frames};
}

namespace {

// Front-to-back order of the Gaussians the projection kept, into r.order; returns how many.
// CPU depth sort: read back the depth keys only (4 bytes per Gaussian) and sort (depth bits, index)
// pairs: positive floats order like their bit patterns, and the index breaks ties, so the order equals
// the reference's stable sort (and is deterministic).
std::size_t sort_front_to_back(GlRenderer& r, std::size_t n) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<float> depth(n);
    if (n > 0) glGetNamedBufferSubData(r.depth.id(), 0, GLsizeiptr(n * sizeof(float)), depth.data());
    std::vector<std::uint64_t> keys;
    keys.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (depth[i] > 0.0f) {
            std::uint32_t bits;
            std::memcpy(&bits, &depth[i], 4);
            keys.push_back(std::uint64_t(bits) << 32 | std::uint64_t(i));
        }
    tbb::parallel_sort(keys.begin(), keys.end());
    std::vector<std::uint32_t> order(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) order[k] = std::uint32_t(keys[k] & 0xffffffffu);
    upload(r.order, order.data(), order.size() * sizeof(std::uint32_t));
    r.sort_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return order.size();
}

}  // namespace

Status draw_gaussians(GlRenderer& r, const GaussianBuffers& b, const GaussianView& v, const gfx::Program* splat_program) {
    const std::size_t n = b.count;
    if (n >= (std::size_t(1) << 31)) return make_error("draw_gaussians(): more than 2^31 Gaussians in one draw");
    if (r.scratch < n || !r.projected) {
        if (!r.projected) r.projected = gfx::Buffer::create("gaussian.projected");
        if (!r.depth) r.depth = gfx::Buffer::create("gaussian.depth_keys");
        if (!r.order) r.order = gfx::Buffer::create("gaussian.order");
        upload(r.projected, nullptr, n * sizeof(gpu::GpuProjected));
        upload(r.depth, nullptr, n * sizeof(float));
        r.scratch = n;
    }
    // The scratch buffers were read by the previous draw (another cloud this frame): its reads come first.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    const double tan_half = std::tan(glm::radians(v.fov_y_degrees) * 0.5);
    const GLuint pp = r.project.id();
    glProgramUniformMatrix4fv(pp, glGetUniformLocation(pp, "u_view"), 1, GL_FALSE, glm::value_ptr(glm::mat4(v.view)));
    set(pp, "u_eye", glm::vec3(v.eye));
    set(pp, "u_size", glm::vec2(float(v.width), float(v.height)));
    set(pp, "u_focal", float(v.height / (2.0 * tan_half)));
    set(pp, "u_limit", glm::vec2(float(1.3 * tan_half * v.width / v.height), float(1.3 * tan_half)));
    set(pp, "u_near", float(v.near_plane));
    glProgramUniform1ui(pp, glGetUniformLocation(pp, "u_count"), GLuint(n));
    glProgramUniform1i(pp, glGetUniformLocation(pp, "u_degree"), b.sh_degree);
    glProgramUniform1i(pp, glGetUniformLocation(pp, "u_frames"), b.has_frames ? 1 : 0);
    // A buffer with no store cannot be bound: the frames slot falls back to the Gaussians (never read).
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_IN, b.gaussians);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_SH, b.sh);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_PROJECTED, r.projected.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_FRAMES, b.has_frames && b.frames ? b.frames : b.gaussians);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DEPTH, r.depth.id());
    glUseProgram(pp);
    if (Status st = gfx::dispatch_1d(n, 64, std::max(1u, r.max_groups_x)); !st) return st.error();
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);

    const std::size_t visible = sort_front_to_back(r, n);

    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFuncSeparate(GL_ONE_MINUS_DST_ALPHA, GL_ONE, GL_ONE_MINUS_DST_ALPHA, GL_ONE);
    const GLuint sp = splat_program ? splat_program->id() : r.splat.id();
    set(sp, "u_size", glm::vec2(float(v.width), float(v.height)));
    set(sp, "u_ndc_depth", glm::vec2(v.ndc_depth));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_PROJECTED, r.projected.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_ORDER, r.order.id());
    glUseProgram(sp);
    glBindVertexArray(r.vao.id());
    if (visible > 0) glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(visible));
    glDisable(GL_BLEND);
    glBindVertexArray(0);
    glUseProgram(0);
    return {};
}

Result<ReferenceImage> draw_gl(GlRenderer& r, const Camera& cam, const ReferenceOptions& o) {
    if (o.width < 1 || o.height < 1) return make_error("draw_gl(): empty image");
    if (r.width != o.width || r.height != o.height) {
        r.color = gfx::Texture::create("gaussian.color", GL_TEXTURE_2D);
        glTextureStorage2D(r.color.id(), 1, GL_RGBA32F, o.width, o.height);
        r.framebuffer = gfx::Framebuffer::create("gaussian.target");
        glNamedFramebufferTexture(r.framebuffer.id(), GL_COLOR_ATTACHMENT0, r.color.id(), 0);
        if (glCheckNamedFramebufferStatus(r.framebuffer.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return make_error("draw_gl(): RGBA32F framebuffer incomplete");
        r.width = o.width, r.height = o.height;
    }
    GaussianView v;
    v.view = glm::lookAt(cam.eye, cam.target, cam.up) * glm::translate(glm::dmat4(1.0), r.origin);
    v.eye = cam.eye - r.origin;
    v.fov_y_degrees = double(cam.fov_y_degrees);
    v.near_plane = double(o.near_plane);
    v.width = o.width, v.height = o.height;
    glBindFramebuffer(GL_FRAMEBUFFER, r.framebuffer.id());
    glViewport(0, 0, o.width, o.height);
    const float clear[4] = {0, 0, 0, 0};
    glClearNamedFramebufferfv(r.framebuffer.id(), GL_COLOR, 0, clear);
    glDisable(GL_DEPTH_TEST);
    const Status drawn = draw_gaussians(r, resident_buffers(r), v);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!drawn) return drawn.error();

    std::vector<glm::vec4> pixels(std::size_t(o.width) * std::size_t(o.height));
    glGetTextureImage(r.color.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(pixels.size() * sizeof(glm::vec4)), pixels.data());
    ReferenceImage img;
    img.width = o.width, img.height = o.height;
    img.color.resize(pixels.size());
    img.transmittance.resize(pixels.size());
    for (int y = 0; y < o.height; ++y)  // GL rows go bottom-up
        for (int x = 0; x < o.width; ++x) {
            const glm::vec4 p = pixels[std::size_t(o.height - 1 - y) * std::size_t(o.width) + std::size_t(x)];
            const std::size_t k = img.index(x, y);
            img.transmittance[k] = 1.0f - p.w;
            img.color[k] = glm::vec3(p) + (1.0f - p.w) * o.background;
        }
    return img;
}

}  // namespace sffd::gaussian
