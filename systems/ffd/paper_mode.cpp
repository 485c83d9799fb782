#include "systems/ffd/paper_mode.h"

#include <glm/gtc/type_ptr.hpp>

#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/deform_kernels.h"
#include "systems/ffd/lattice.h"

namespace sffd::ffd {

namespace {
struct FfdBlock {  // std140 mirror of FfdBlock in shaders/ffd/ffd_common.glsl (same as ffd_gpu.cpp)
    float minv[3][4];
    float stu0[4];
    std::int32_t div[4];
    float cull_lo[4];
    float cull_hi[4];
    std::uint32_t count[4];
};
}  // namespace

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
    glNamedBufferData(impl->ubo.id(), sizeof(FfdBlock), nullptr, GL_DYNAMIC_DRAW);
    impl->controls = gfx::Buffer::create("ffd.paper_mode.control_points");
    return PaperModeRenderer(std::move(impl));
}

Status PaperModeRenderer::draw(const Lattice& lattice, std::uint64_t stamp, const glm::dvec3& cloud_origin, GLuint rest,
                               std::uint32_t count, const glm::mat4& view_proj, float point_size) {
    if (Status s = validate(lattice); !s) return s;
    Impl& m = *m_impl;
    const detail::Prepared P = detail::prepare(lattice, cloud_origin);
    FfdBlock block{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) block.minv[r][c] = P.minv[r * 3 + c];
    for (int a = 0; a < 3; ++a) {
        block.stu0[a] = P.stu0[a];
        block.div[a] = lattice.divisions[a];
        block.cull_lo[a] = P.cull_lo[a];
        block.cull_hi[a] = P.cull_hi[a];
    }
    block.div[3] = lattice.basis == LatticeBasis::bspline ? 1 : 0;
    block.count[0] = count;
    block.count[1] = P.moved.empty() ? 1u : 0u;
    glNamedBufferSubData(m.ubo.id(), 0, sizeof block, &block);
    if (stamp == 0 || stamp != m.stamp) {
        const std::vector<float>& data = lattice.basis == LatticeBasis::bspline ? P.grid : P.dp4;
        const std::size_t bytes = std::max<std::size_t>(data.size(), 4) * sizeof(float);
        if (bytes > m.controls_capacity) {
            glNamedBufferData(m.controls.id(), GLsizeiptr(bytes), nullptr, GL_DYNAMIC_DRAW);
            m.controls_capacity = bytes;
        }
        if (!data.empty()) glNamedBufferSubData(m.controls.id(), 0, GLsizeiptr(data.size() * sizeof(float)), data.data());
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

void PaperModeRenderer::draw_deformed(GLuint deformed, std::uint32_t count, const glm::mat4& view_proj, float point_size) {
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
