// GL 4.5 renderer of 3D Gaussians (issue 17), first version: a compute pass projects every Gaussian
// (EWA conic, SH colour: shaders/gaussian/project.comp), the visible ones are sorted by view depth on
// the CPU (a GPU radix sort does not exist yet), and one instanced quad per Gaussian is blended front to
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
    gfx::Buffer gaussians, sh, projected, order, frames;
    gfx::Texture color;
    gfx::Framebuffer framebuffer;
    int width = 0, height = 0;
    double sort_ms = 0.0;  // CPU time of the last frame's depth sort (readback + sort + upload)
};

// Compiles the programs (errors name the shader file and line).
Result<GlRenderer> create_gl_renderer();

// Renders like render_reference() (same camera model, background blended in) and reads the image back.
Result<ReferenceImage> render_gl(GlRenderer& renderer, const GaussianCloud& cloud, const Camera& camera,
                                 const ReferenceOptions& options, const std::vector<float>* opacities = nullptr);

}  // namespace sffd::gaussian
