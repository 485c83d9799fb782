// Move-only owners of GL object names (Magnum's rule: copy deleted, move zeroes the source, destructor
// deletes). Created with direct state access (glCreate*) and labelled with glObjectLabel so debug
// output and captures name them. Needs a current GL 4.5 context for construction and destruction.
//
//   gfx::Buffer positions = gfx::Buffer::create("ffd.deformed");
//   glNamedBufferData(positions.id(), bytes, nullptr, GL_DYNAMIC_DRAW);
#pragma once

#include <string_view>
#include <utility>

#include "runtime/gfx/gl.h"

namespace sffd::gfx {

enum class GlKind {
    buffer,
    texture,
    framebuffer,
    renderbuffer,
    vertex_array,
    program,
    shader,
    query,
    sampler
};

template <GlKind K>
class GlObject {
public:
    GlObject() = default;
    explicit GlObject(GLuint id) : m_id(id) {}
    ~GlObject() { reset(); }
    GlObject(const GlObject&) = delete;
    GlObject& operator=(const GlObject&) = delete;
    GlObject(GlObject&& o) noexcept : m_id(std::exchange(o.m_id, 0)) {}
    GlObject& operator=(GlObject&& o) noexcept {
        if (this != &o) {
            reset();
            m_id = std::exchange(o.m_id, 0);
        }
        return *this;
    }

    GLuint id() const { return m_id; }
    explicit operator bool() const { return m_id != 0; }
    GLuint release() { return std::exchange(m_id, 0); }

    void reset() {
        if (!m_id) return;
        if constexpr (K == GlKind::buffer) glDeleteBuffers(1, &m_id);
        else if constexpr (K == GlKind::texture) glDeleteTextures(1, &m_id);
        else if constexpr (K == GlKind::framebuffer) glDeleteFramebuffers(1, &m_id);
        else if constexpr (K == GlKind::renderbuffer) glDeleteRenderbuffers(1, &m_id);
        else if constexpr (K == GlKind::vertex_array) glDeleteVertexArrays(1, &m_id);
        else if constexpr (K == GlKind::program) glDeleteProgram(m_id);
        else if constexpr (K == GlKind::shader) glDeleteShader(m_id);
        else if constexpr (K == GlKind::query) glDeleteQueries(1, &m_id);
        else if constexpr (K == GlKind::sampler) glDeleteSamplers(1, &m_id);
        m_id = 0;
    }

    // Creates one object with DSA and labels it. `target` is needed for textures and queries.
    static GlObject create(std::string_view label, GLenum target = 0) {
        GLuint id = 0;
        GLenum identifier = 0;
        if constexpr (K == GlKind::buffer) glCreateBuffers(1, &id), identifier = GL_BUFFER;
        else if constexpr (K == GlKind::texture) glCreateTextures(target, 1, &id), identifier = GL_TEXTURE;
        else if constexpr (K == GlKind::framebuffer)
            glCreateFramebuffers(1, &id), identifier = GL_FRAMEBUFFER;
        else if constexpr (K == GlKind::renderbuffer)
            glCreateRenderbuffers(1, &id), identifier = GL_RENDERBUFFER;
        else if constexpr (K == GlKind::vertex_array)
            glCreateVertexArrays(1, &id), identifier = GL_VERTEX_ARRAY;
        else if constexpr (K == GlKind::program) id = glCreateProgram(), identifier = GL_PROGRAM;
        else if constexpr (K == GlKind::shader) id = glCreateShader(target), identifier = GL_SHADER;
        else if constexpr (K == GlKind::query) glCreateQueries(target, 1, &id), identifier = GL_QUERY;
        else if constexpr (K == GlKind::sampler) glCreateSamplers(1, &id), identifier = GL_SAMPLER;
        if (id && !label.empty())
            glObjectLabel(identifier, id, static_cast<GLsizei>(label.size()), label.data());
        return GlObject(id);
    }

private:
    GLuint m_id = 0;
};

using Buffer = GlObject<GlKind::buffer>;
using Texture = GlObject<GlKind::texture>;
using Framebuffer = GlObject<GlKind::framebuffer>;
using Renderbuffer = GlObject<GlKind::renderbuffer>;
using VertexArray = GlObject<GlKind::vertex_array>;
using Program = GlObject<GlKind::program>;
using Shader = GlObject<GlKind::shader>;
using Query = GlObject<GlKind::query>;
using Sampler = GlObject<GlKind::sampler>;

}  // namespace sffd::gfx
