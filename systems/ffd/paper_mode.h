// "Paper mode": a small self-contained point-sprite renderer that deforms in the vertex shader, as the
// seed paper did, so its cost can be compared with the skinning-style compute pass (deform once per edit,
// every pass reads the result). Not part of the frame schedule; used by bench_ffd_gpu and the GL tests.
//
//   auto paper = ffd::PaperModeRenderer::create();           // GL context current
//   paper->draw(lattice, cloud_origin, rest_buffer, count, view_proj, 2.0f);       // deforms per vertex
//   paper->draw_deformed(deformed_buffer, count, view_proj, 2.0f);                 // no deformation
// Draws into the currently bound framebuffer and viewport (depth test on, caller clears).
#pragma once

#include <cstdint>
#include <memory>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

class PaperModeRenderer {
public:
    static Result<PaperModeRenderer> create();
    PaperModeRenderer(PaperModeRenderer&&) noexcept;
    PaperModeRenderer& operator=(PaperModeRenderer&&) noexcept;
    ~PaperModeRenderer();

    // GpuSplat[] `rest` deformed by `lattice` in the vertex shader. Control points are uploaded when
    // `lattice_stamp` changes (0: always).
    Status draw(const Lattice& lattice, std::uint64_t lattice_stamp, const glm::dvec3& cloud_origin,
                GLuint rest, std::uint32_t count, const glm::mat4& view_proj, float point_size);
    // GpuSplat[] already deformed (e.g. by the compute pass): same sprites, no deformation.
    void draw_deformed(GLuint deformed, std::uint32_t count, const glm::mat4& view_proj, float point_size);

private:
    struct Impl;
    explicit PaperModeRenderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

}  // namespace sffd::ffd
