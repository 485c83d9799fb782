// GL 4.5 renderer of 3D Gaussians (issue 17), first version: a compute pass projects every Gaussian
// (EWA conic, SH colour: shaders/gaussian/project.comp), the visible ones are sorted by view depth on
// the CPU (depth keys read back, 4 bytes per Gaussian; a GPU radix sort does not exist yet), and one instanced quad per Gaussian is blended front to
// back into an RGBA32F target (shaders/gaussian/splat.{vert,frag}). The images match the CPU reference
// renderer (reference_render.h: same conventions, same pixel boxes) within the PSNR the GL test states.
// Owns its GL objects (move-only); create and use it with a GL context current, destroy it before the
// context.
#pragma once

#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/reference_render.h"

namespace sffd::gaussian {

struct GlRenderer {
    gfx::Program project;
    gfx::Program splat;
    gfx::VertexArray vao;
    gfx::Buffer gaussians, sh, projected, order, frames, depth;
    gfx::Texture color;
    gfx::Framebuffer framebuffer;
    int width = 0, height = 0;
    std::size_t count = 0;    // Gaussians resident (upload_gl)
    int sh_degree = 0;
    bool has_frames = false;  // the resident cloud carries SH frames
    glm::dvec3 origin{0.0};
    double sort_ms = 0.0;  // CPU time of the last frame's depth sort (readback + sort + upload)
    // Work groups per row of the projection dispatch. GL guarantees only 65,535 groups per dimension
    // (64 × 65,535 = 4.19M Gaussians), so larger clouds are dispatched as a 2D grid; tests lower this to
    // exercise the grid with small clouds.
    unsigned max_groups_x = 65535;
    std::size_t scratch = 0;  // Gaussians the per-draw buffers (projected, depth keys) hold
};

// What one draw reads: a cloud's GPU buffers, either the renderer's own (upload_gl) or a
// GpuGaussianStore entry's (gpu_store.h: draw_buffer(), sh_buffer(), frames), so the render system draws
// clouds it (or the GPU deformation) keeps resident without copying them.
struct GaussianBuffers {
    GLuint gaussians = 0;  // GpuGaussian[count] (shaders/gaussian/gaussian_layout.h)
    GLuint sh = 0;         // float[count * K * 3]
    GLuint frames = 0;     // vec4[3 * count], read when has_frames
    std::size_t count = 0;
    int sh_degree = 0;
    bool has_frames = false;
};

// The camera of one draw, in the cloud's coordinates.
struct GaussianView {
    glm::dmat4 view{1.0};  // cloud coordinates (relative to the cloud origin) -> camera, composed in double
    glm::dvec3 eye{0.0};   // camera position in cloud coordinates (view direction of the SH)
    double fov_y_degrees = 45.0;
    double near_plane = 0.01;
    int width = 1, height = 1;
    // NDC depth of a splat quad, z = ndc_depth.x + ndc_depth.y / view_depth (a perspective projection's
    // -P[2][2] and P[3][2]), clamped below the far plane; (0, 0): every quad at z = 0 (no depth test).
    glm::dvec2 ndc_depth{0.0};
};

// One cloud: projection, front-to-back order of the visible Gaussians, and the instanced splat quads
// blended front to back (GL_ONE_MINUS_DST_ALPHA, GL_ONE) into the framebuffer bound now, through the
// viewport the caller set. Depth test state is the caller's (the render system tests against the surface
// splats' depth); `splat_program` replaces the renderer's splat program (same vertex shader, its own
// fragment shader), null: the renderer's.
Status draw_gaussians(GlRenderer& renderer, const GaussianBuffers& buffers, const GaussianView& view,
                      const gfx::Program* splat_program = nullptr);
// The renderer's own resident cloud (upload_gl) as GaussianBuffers.
GaussianBuffers resident_buffers(const GlRenderer& renderer);

// Compiles the programs (errors name the shader file and line).
Result<GlRenderer> create_gl_renderer();

// Uploads a cloud; it stays resident for draw_gl() until the next upload.
Status upload_gl(GlRenderer& renderer, const GaussianCloud& cloud, const std::vector<float>* opacities = nullptr);
// One frame of the resident cloud: projection, depth sort, splatting, image readback.
Result<ReferenceImage> draw_gl(GlRenderer& renderer, const Camera& camera, const ReferenceOptions& options);
// upload_gl + draw_gl: renders like render_reference() (same camera model, background blended in).
Result<ReferenceImage> render_gl(GlRenderer& renderer, const GaussianCloud& cloud, const Camera& camera,
                                 const ReferenceOptions& options, const std::vector<float>* opacities = nullptr);

}  // namespace sffd::gaussian
