#include "systems/ffd/paper_mode.h"

#include <glm/gtc/type_ptr.hpp>

#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/gpu_block.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

struct PaperModeRenderer::Impl {
    gfx::Program paper, plain;
    gfx::VertexArray vao;
    gfx::Buffer ubo, controls;
    std::size_t controls_capacity = 0;
    std::uint64_t stamp = 0;
};

PaperModeRenderer::PaperModeRenderer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
PaperModeRenderer::PaperModeRenderer(PaperModeRenderer&&) noexcept = default;
PaperModeRenderer& PaperModeRenderer::operator=(PaperModeRenderer&&) noexcept = default;
PaperModeRenderer::~PaperModeRenderer() = default;

Result<PaperModeRenderer> PaperModeRenderer::create() {
    auto impl = std::make_unique<Impl>();
    const std::vector<gfx::ShaderSource> src = {{GL_VERTEX_SHADER, "ffd/paper_mode.vert"},
                                                {GL_FRAGMENT_SHADER, "ffd/paper_mode.frag"}};
    auto paper = gfx::load_program(src, "ffd.paper_mode", {{"PAPER_DEFORM", "1"}});
    if (!paper) return paper.error();
    auto plain = gfx::load_program(src, "ffd.paper_mode_plain", {{"PAPER_DEFORM", "0"}});
    if (!plain) return plain.error();
    impl->paper = std::move(*paper);
    impl->plain = std::move(*plain);
    impl->vao = gfx::VertexArray::create("ffd.paper_mode");
    impl->ubo = gfx::Buffer::create("ffd.paper_mode.lattice_block");
    glNamedBufferData(impl->ubo.id(), sizeof(detail::FfdBlock), nullptr, GL_DYNAMIC_DRAW);
    impl->controls = gfx::Buffer::create("ffd.paper_mode.control_points");
    return PaperModeRenderer(std::move(impl));
}

Status PaperModeRenderer::draw(const Lattice& lattice, std::uint64_t stamp, const glm::dvec3& cloud_origin,
                               GLuint rest, std::uint32_t count, const glm::mat4& view_proj,
                               float point_size) {
    if (Status s = validate(lattice); !s) return s;
    Impl& m = *m_impl;
    const detail::Prepared P = detail::prepare(lattice, cloud_origin, detail::PrepareFor::gpu_controls);
    const detail::FfdBlock block = detail::make_ffd_block(lattice, P, count);
    detail::orphan_upload(m.ubo.id(), sizeof block, &block);
    if (stamp == 0 || stamp != m.stamp) {
        detail::upload_control_points(m.controls.id(), m.controls_capacity, lattice, P);
        m.stamp = stamp;
    }
    glUseProgram(m.paper.id());
    glProgramUniformMatrix4fv(m.paper.id(), 0, 1, GL_FALSE, glm::value_ptr(view_proj));
    glProgramUniform1f(m.paper.id(), 1, point_size);
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FFD, m.ubo.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_CONTROL_POINTS, m.controls.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_IN, rest);
    glBindVertexArray(m.vao.id());
    glEnable(GL_PROGRAM_POINT_SIZE);
    glEnable(GL_DEPTH_TEST);
    glDrawArrays(GL_POINTS, 0, GLsizei(count));
    return {};
}

void PaperModeRenderer::draw_deformed(GLuint deformed, std::uint32_t count, const glm::mat4& view_proj,
                                      float point_size) {
    Impl& m = *m_impl;
    glUseProgram(m.plain.id());
    glProgramUniformMatrix4fv(m.plain.id(), 0, 1, GL_FALSE, glm::value_ptr(view_proj));
    glProgramUniform1f(m.plain.id(), 1, point_size);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_SSBO_SPLATS_IN, deformed);
    glBindVertexArray(m.vao.id());
    glEnable(GL_PROGRAM_POINT_SIZE);
    glEnable(GL_DEPTH_TEST);
    glDrawArrays(GL_POINTS, 0, GLsizei(count));
}

}  // namespace sffd::ffd
