// GL 4.5 core context: a GLFW window (debug context) when a display exists, or an EGL surfaceless Mesa
// context when headless (no display, or forced with `--headless`). Both render into the same offscreen
// targets (runtime/gfx/render_target.h); a window additionally blits the final target to its default
// framebuffer and swaps.
//
//   auto ctx = gfx::create_context({.headless = true, .width = 640, .height = 480});
//   if (!ctx) { log::error(ctx.message()); return 1; }
//   ... GL calls (the context is current on the creating thread) ...
//
// Ownership and threads: GlContext is move-only and owns the EGL context or GLFW window. Every GL object
// (gfx::Buffer, Program, RenderTarget...) must be destroyed while its context is current and before the
// context itself. Headless contexts may be created one after another in a process (tests) and one per
// thread (make_current() on the thread that uses it); GLFW windows only on the main thread.
//
// One GL debug-message callback (KHR_debug) per context logs through runtime/core/log.h: errors at error
// level, warnings at warn, the rest at debug. debug_error_count() counts GL errors seen in this process,
// so tests can assert that a pass produced none.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.h"

struct GLFWwindow;

namespace sffd::gfx {

struct ContextOptions {
    bool headless = false;  // force EGL surfaceless even when DISPLAY is set
    int width = 1280;       // window size, or the nominal framebuffer size when headless
    int height = 720;
    bool visible = true;  // window only
    bool debug = true;    // debug context + debug-message callback
    std::string title = "SplatFFD";
};

struct FramebufferSize {
    int width = 0;
    int height = 0;
};

class GlContext;
Result<GlContext> create_context(const ContextOptions& options);

class GlContext {
public:
    GlContext();
    ~GlContext();
    GlContext(GlContext&&) noexcept;
    GlContext& operator=(GlContext&&) noexcept;
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    explicit operator bool() const { return m_impl != nullptr; }

    void make_current();
    void release_current();  // no context current on this thread afterwards
    void swap_buffers();     // window: present the default framebuffer; headless: no-op
    void poll_events();      // window: process events; headless: no-op
    bool should_close() const;
    void request_close();
    bool is_headless() const;
    // Window: its framebuffer in pixels. Headless: the size asked for in ContextOptions.
    FramebufferSize framebuffer_size() const;
    GLFWwindow* window() const;           // nullptr when headless
    const std::string& renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
    const std::string& version() const;   // GL_VERSION

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
    friend Result<GlContext> create_context(const ContextOptions&);
};

// True when a window can be opened (DISPLAY or WAYLAND_DISPLAY set).
bool display_available();

// Creates the context and makes it current on the calling thread. Window when a display exists and
// options.headless is false, EGL surfaceless otherwise. Errors name the failing call.
Result<GlContext> create_context(const ContextOptions& options);

// True when the current context is one of Mesa's software rasterizers (llvmpipe, softpipe, SWR): its
// "GPU" is the CPU, so systems prefer their native CPU paths there (ffd_system, the render cull).
// False without a current context.
bool software_rasterizer();

// GL errors reported through the debug callback since process start (all contexts).
std::uint64_t debug_error_count();

}  // namespace sffd::gfx
