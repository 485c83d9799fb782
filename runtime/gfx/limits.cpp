#include "runtime/gfx/limits.h"

#include <cstdlib>
#include <mutex>
#include <string_view>

#include "runtime/core/log.h"
#include "runtime/gfx/gl.h"

namespace sffd::gfx {

namespace {

std::mutex g_mutex;
GlLimits g_context_limits;
thread_local const GlLimits* t_override = nullptr;

int get_int(GLenum name) {
    GLint v = 0;
    glGetIntegerv(name, &v);
    return v;
}

}  // namespace

GlLimits query_limits() {
    GlLimits l;
    GLint64 block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
    l.max_ssbo_block_size = block;
    l.max_ssbo_bindings = get_int(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
    l.max_vertex_ssbo_blocks = get_int(GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS);
    l.max_fragment_ssbo_blocks = get_int(GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS);
    l.max_compute_ssbo_blocks = get_int(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS);
    l.max_combined_ssbo_blocks = get_int(GL_MAX_COMBINED_SHADER_STORAGE_BLOCKS);
    l.ssbo_offset_alignment = get_int(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT);
    l.max_uniform_block_size = get_int(GL_MAX_UNIFORM_BLOCK_SIZE);
    GLint groups = 0;
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &groups);
    l.max_compute_groups_x = groups;
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 1, &groups);
    l.max_compute_groups_y = groups;
    GLfloat range[2] = {0, 0};
    glGetFloatv(GL_POINT_SIZE_RANGE, range);
    l.max_point_size = range[1];
    return l;
}

Status check_limits(const GlLimits& have, const GlRequirements& need) {
    std::string missing;
    const auto check = [&](const char* name, std::int64_t value, std::int64_t wanted, const char* who) {
        if (value >= wanted) return;
        missing += log::str(missing.empty() ? "" : "; ", name, " is ", value, ", ", who, " needs ", wanted);
    };
    check("GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS", have.max_vertex_ssbo_blocks, need.vertex_ssbo_blocks,
          "splat_render/splat.vert");
    check("GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS", have.max_fragment_ssbo_blocks, need.fragment_ssbo_blocks,
          "splat_render/compute_resolve.frag");
    check("GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS", have.max_compute_ssbo_blocks, need.compute_ssbo_blocks,
          "gaussian/deform.comp");
    check("GL_MAX_COMBINED_SHADER_STORAGE_BLOCKS", have.max_combined_ssbo_blocks, need.combined_ssbo_blocks,
          "gaussian/deform.comp");
    check("GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS", have.max_ssbo_bindings, need.ssbo_bindings,
          "the binding points of shaders/splat_render/compute_raster.h");
    if (missing.empty()) return {};
    return make_error("the GL implementation lacks limits the engine needs: " + missing);
}

const GlLimits& limits() {
    if (t_override) return *t_override;
    std::lock_guard lock(g_mutex);
    return g_context_limits;
}

void set_context_limits(const GlLimits& l) {
    std::lock_guard lock(g_mutex);
    g_context_limits = l;
}

bool ssbo_fits(std::uint64_t bytes, const GlLimits& l) {
    return l.max_ssbo_block_size > 0 && bytes <= std::uint64_t(l.max_ssbo_block_size);
}

std::string ssbo_too_large(const char* what, std::uint64_t bytes, const GlLimits& l) {
    return log::str(what, ": ", bytes, " bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (",
                    l.max_ssbo_block_size, ")");
}

ScopedLimits::ScopedLimits(const GlLimits& l) : m_limits(l), m_previous(t_override) {
    t_override = &m_limits;
}
ScopedLimits::~ScopedLimits() { t_override = m_previous; }

bool hardware_gl_required() {
    const char* v = std::getenv("SFFD_REQUIRE_HARDWARE_GL");
    return v && *v && std::string_view(v) != "0";
}

bool software_renderer_name(const std::string& renderer) {
    const std::string_view r(renderer);
    return r.find("llvmpipe") != r.npos || r.find("softpipe") != r.npos || r.find("SWR") != r.npos ||
           r.find("Software Rasterizer") != r.npos;
}

}  // namespace sffd::gfx
