// Offscreen render target: one framebuffer with named colour attachments and an optional depth texture.
// Window and headless runs render into the same targets; a window blits the final one to its default
// framebuffer (blit_to_default_framebuffer), headless runs read it back (read_rgba8 / read_float).
//
//   auto target = gfx::RenderTarget::create({.label = "render.main", .width = 640, .height = 480,
//                                            .color = {{"color", gfx::ColorFormat::rgba8}}});
//   target->bind();  // framebuffer + viewport; draw buffers = every colour attachment in order
//   ... draw ...
//   std::vector<std::uint8_t> pixels = target->read_rgba8("color");
//
// Readback row order is OpenGL's: row 0 is the BOTTOM row of the image. Image writers flip with
// flip_rows() (PNG/EXR store the top row first).
//
// All textures are immutable storage (glTextureStorage2D) with NEAREST filtering, so passes can sample
// them (e.g. depth for the splat visibility pass). Needs a current GL 4.5 context.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::gfx {

enum class ColorFormat { rgba8, rgba16f, rgba32f, r32f };

GLenum gl_internal_format(ColorFormat format);
int channel_count(ColorFormat format);  // 4, or 1 for r32f

struct ColorAttachmentDesc {
    std::string name;
    ColorFormat format = ColorFormat::rgba8;
};

struct RenderTargetDesc {
    std::string label = "render_target";
    int width = 0;
    int height = 0;
    std::vector<ColorAttachmentDesc> color;  // attachment i is GL_COLOR_ATTACHMENT0 + i
    bool depth = true;                       // GL_DEPTH_COMPONENT32F texture
};

class RenderTarget {
public:
    RenderTarget() = default;
    // Errors: zero/negative or too large size, no attachments, duplicate names, incomplete framebuffer.
    static Result<RenderTarget> create(const RenderTargetDesc& desc);

    // Re-creates the textures at the new size (contents are undefined afterwards). No-op if unchanged.
    Status resize(int width, int height);

    // Binds the framebuffer for drawing and sets the viewport to the whole target.
    void bind() const;

    int width() const { return m_desc.width; }
    int height() const { return m_desc.height; }
    const RenderTargetDesc& desc() const { return m_desc; }
    GLuint framebuffer() const { return m_fbo.id(); }
    // -1 if there is no attachment of that name.
    int attachment_index(std::string_view name) const;
    GLuint color_texture(std::string_view name) const;  // 0 if unknown
    GLuint color_texture(int index) const;
    GLuint depth_texture() const { return m_depth.id(); }

    // Clears one colour attachment to `rgba` (a single float for r32f uses rgba[0]), or the depth.
    void clear_color(std::string_view name, const float rgba[4]) const;
    void clear_depth(float depth = 1.0f) const;

    // Readback (bottom row first). read_rgba8 converts any format to 8-bit RGBA (floats clamped to
    // [0,1]); read_float returns channel_count(format) floats per pixel. Both wait for rendering.
    std::vector<std::uint8_t> read_rgba8(std::string_view name) const;
    std::vector<float> read_float(std::string_view name) const;
    std::vector<float> read_depth() const;

    // Copies attachment `name` to the default framebuffer (a window), scaled to dst_width x dst_height
    // with linear filtering if the sizes differ. The caller then swaps.
    void blit_to_default_framebuffer(std::string_view name, int dst_width, int dst_height) const;

private:
    Status allocate();

    RenderTargetDesc m_desc;
    Framebuffer m_fbo;
    std::vector<Texture> m_color;
    Texture m_depth;
};

// Reverses row order in place (bottom-up <-> top-down) of an image with `row_bytes` bytes per row.
void flip_rows(std::span<std::byte> pixels, std::size_t row_bytes);

template <class T>
void flip_rows(std::vector<T>& pixels, std::size_t values_per_row) {
    flip_rows(std::as_writable_bytes(std::span<T>(pixels)), values_per_row * sizeof(T));
}

}  // namespace sffd::gfx
