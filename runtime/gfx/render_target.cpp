#include "runtime/gfx/render_target.h"

#include <algorithm>
#include <cassert>
#include <cstring>

#include "runtime/core/log.h"

namespace sffd::gfx {

GLenum gl_internal_format(ColorFormat format) {
    switch (format) {
        case ColorFormat::rgba8: return GL_RGBA8;
        case ColorFormat::rgba16f: return GL_RGBA16F;
        case ColorFormat::rgba32f: return GL_RGBA32F;
        case ColorFormat::r32f: return GL_R32F;
    }
    return GL_RGBA8;
}

int channel_count(ColorFormat format) { return format == ColorFormat::r32f ? 1 : 4; }

Result<RenderTarget> RenderTarget::create(const RenderTargetDesc& desc) {
    if (desc.color.empty() && !desc.depth)
        return make_error(log::str("RenderTarget::create(", desc.label, "): no attachments"));
    for (std::size_t i = 0; i < desc.color.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (desc.color[i].name == desc.color[j].name)
                return make_error(log::str("RenderTarget::create(", desc.label,
                                           "): duplicate attachment name '", desc.color[i].name, "'"));
    RenderTarget target;
    target.m_desc = desc;
    if (Status s = target.allocate(); !s) return s.error();
    return target;
}

Status RenderTarget::allocate() {
    GLint max_size = 0, max_attachments = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &max_attachments);
    if (m_desc.width <= 0 || m_desc.height <= 0 || m_desc.width > max_size || m_desc.height > max_size)
        return make_error(log::str("RenderTarget(", m_desc.label, "): invalid size ", m_desc.width, "x",
                                   m_desc.height, " (1..", max_size, ")"));
    if (int(m_desc.color.size()) > max_attachments)
        return make_error(log::str("RenderTarget(", m_desc.label, "): ", m_desc.color.size(),
                                   " colour attachments, the driver allows ", max_attachments));
    m_color.clear();
    m_depth.reset();
    m_fbo = Framebuffer::create(m_desc.label);
    std::vector<GLenum> draw_buffers;
    for (std::size_t i = 0; i < m_desc.color.size(); ++i) {
        const ColorAttachmentDesc& a = m_desc.color[i];
        Texture tex = Texture::create(log::str(m_desc.label, ".", a.name), GL_TEXTURE_2D);
        glTextureStorage2D(tex.id(), 1, gl_internal_format(a.format), m_desc.width, m_desc.height);
        glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        const auto attachment = GLenum(GL_COLOR_ATTACHMENT0 + i);
        glNamedFramebufferTexture(m_fbo.id(), attachment, tex.id(), 0);
        draw_buffers.push_back(attachment);
        m_color.push_back(std::move(tex));
    }
    if (m_desc.depth) {
        m_depth = Texture::create(m_desc.label + ".depth", GL_TEXTURE_2D);
        glTextureStorage2D(m_depth.id(), 1, GL_DEPTH_COMPONENT32F, m_desc.width, m_desc.height);
        glTextureParameteri(m_depth.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(m_depth.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glNamedFramebufferTexture(m_fbo.id(), GL_DEPTH_ATTACHMENT, m_depth.id(), 0);
    }
    if (draw_buffers.empty()) glNamedFramebufferDrawBuffer(m_fbo.id(), GL_NONE);
    else glNamedFramebufferDrawBuffers(m_fbo.id(), GLsizei(draw_buffers.size()), draw_buffers.data());
    const GLenum status = glCheckNamedFramebufferStatus(m_fbo.id(), GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        return make_error(log::str("RenderTarget(", m_desc.label, "): framebuffer incomplete (status 0x",
                                   std::hex, status, ")"));
    return {};
}

Status RenderTarget::resize(int width, int height) {
    if (width == m_desc.width && height == m_desc.height && m_fbo) return {};
    const RenderTargetDesc previous = m_desc;
    m_desc.width = width;
    m_desc.height = height;
    if (Status s = allocate(); !s) {
        m_desc = previous;
        (void)allocate();
        return s;
    }
    return {};
}

void RenderTarget::bind() const {
    glBindFramebuffer(GL_FRAMEBUFFER, m_fbo.id());
    glViewport(0, 0, m_desc.width, m_desc.height);
}

int RenderTarget::attachment_index(std::string_view name) const {
    for (std::size_t i = 0; i < m_desc.color.size(); ++i)
        if (m_desc.color[i].name == name) return int(i);
    return -1;
}

GLuint RenderTarget::color_texture(std::string_view name) const {
    return color_texture(attachment_index(name));
}

GLuint RenderTarget::color_texture(int index) const {
    return index >= 0 && std::size_t(index) < m_color.size() ? m_color[std::size_t(index)].id() : 0;
}

void RenderTarget::clear_color(std::string_view name, const float rgba[4]) const {
    const int index = attachment_index(name);
    assert(index >= 0 && "clear_color(): unknown attachment");
    if (index >= 0) glClearNamedFramebufferfv(m_fbo.id(), GL_COLOR, index, rgba);
}

void RenderTarget::clear_depth(float depth) const {
    if (m_depth) glClearNamedFramebufferfv(m_fbo.id(), GL_DEPTH, 0, &depth);
}

std::vector<std::uint8_t> RenderTarget::read_rgba8(std::string_view name) const {
    const GLuint tex = color_texture(name);
    assert(tex && "read_rgba8(): unknown attachment");
    std::vector<std::uint8_t> pixels(std::size_t(m_desc.width) * std::size_t(m_desc.height) * 4);
    if (!tex) return pixels;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(tex, 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(pixels.size()), pixels.data());
    return pixels;
}

std::vector<float> RenderTarget::read_float(std::string_view name) const {
    const int index = attachment_index(name);
    assert(index >= 0 && "read_float(): unknown attachment");
    if (index < 0) return {};
    const int channels = channel_count(m_desc.color[std::size_t(index)].format);
    std::vector<float> pixels(std::size_t(m_desc.width) * std::size_t(m_desc.height) * std::size_t(channels));
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(color_texture(index), 0, channels == 1 ? GL_RED : GL_RGBA, GL_FLOAT,
                      GLsizei(pixels.size() * sizeof(float)), pixels.data());
    return pixels;
}

std::vector<float> RenderTarget::read_depth() const {
    assert(m_depth && "read_depth(): target has no depth");
    if (!m_depth) return {};
    std::vector<float> depth(std::size_t(m_desc.width) * std::size_t(m_desc.height));
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(m_depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(depth.size() * sizeof(float)),
                      depth.data());
    return depth;
}

void RenderTarget::blit_to_default_framebuffer(std::string_view name, int dst_width, int dst_height) const {
    const int index = attachment_index(name);
    assert(index >= 0 && "blit_to_default_framebuffer(): unknown attachment");
    if (index < 0) return;
    glNamedFramebufferReadBuffer(m_fbo.id(), GLenum(GL_COLOR_ATTACHMENT0 + index));
    const bool same = dst_width == m_desc.width && dst_height == m_desc.height;
    glBlitNamedFramebuffer(m_fbo.id(), 0, 0, 0, m_desc.width, m_desc.height, 0, 0, dst_width, dst_height,
                           GL_COLOR_BUFFER_BIT, same ? GL_NEAREST : GL_LINEAR);
}

void flip_rows(std::span<std::byte> pixels, std::size_t row_bytes) {
    if (row_bytes == 0) return;
    const std::size_t rows = pixels.size() / row_bytes;
    std::vector<std::byte> tmp(row_bytes);
    for (std::size_t top = 0, bottom = rows - (rows ? 1 : 0); top < bottom; ++top, --bottom) {
        std::byte* a = pixels.data() + top * row_bytes;
        std::byte* b = pixels.data() + bottom * row_bytes;
        std::memcpy(tmp.data(), a, row_bytes);
        std::memcpy(a, b, row_bytes);
        std::memcpy(b, tmp.data(), row_bytes);
    }
}

}  // namespace sffd::gfx
