#include "runtime/gfx/context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLFW/glfw3.h>

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <string_view>
#include <vector>

#include "runtime/core/log.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"

namespace sffd::gfx {

namespace {

std::atomic<std::uint64_t> g_gl_errors{0};

const char* source_name(GLenum source) {
    switch (source) {
        case GL_DEBUG_SOURCE_API: return "api";
        case GL_DEBUG_SOURCE_WINDOW_SYSTEM: return "window-system";
        case GL_DEBUG_SOURCE_SHADER_COMPILER: return "shader-compiler";
        case GL_DEBUG_SOURCE_THIRD_PARTY: return "third-party";
        case GL_DEBUG_SOURCE_APPLICATION: return "application";
        default: return "other";
    }
}

const char* type_name(GLenum type) {
    switch (type) {
        case GL_DEBUG_TYPE_ERROR: return "error";
        case GL_DEBUG_TYPE_DEPRECATED_BEHAVIOR: return "deprecated";
        case GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR: return "undefined-behaviour";
        case GL_DEBUG_TYPE_PORTABILITY: return "portability";
        case GL_DEBUG_TYPE_PERFORMANCE: return "performance";
        case GL_DEBUG_TYPE_MARKER: return "marker";
        default: return "other";
    }
}

// The one GL error path: every context registers this callback, so no code checks glGetError().
void GLAPIENTRY debug_callback(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                               const GLchar* message, const void* /*user*/) {
    if (type == GL_DEBUG_TYPE_PUSH_GROUP || type == GL_DEBUG_TYPE_POP_GROUP || type == GL_DEBUG_TYPE_MARKER)
        return;
    const std::string_view text(message,
                                length < 0 ? std::char_traits<char>::length(message) : std::size_t(length));
    const std::string line =
        log::str("GL ", type_name(type), " (", source_name(source), ", id ", id, "): ", text);
    // Compile errors come back from load_program() as results mapped to file:line; the raw copy the
    // driver also sends here would only repeat them with source-string numbers.
    if (source == GL_DEBUG_SOURCE_SHADER_COMPILER) {
        log::debug(line);
    } else if (type == GL_DEBUG_TYPE_ERROR) {
        ++g_gl_errors;
        log::error(line);
    } else if (severity == GL_DEBUG_SEVERITY_HIGH || severity == GL_DEBUG_SEVERITY_MEDIUM) {
        log::warn(line);
    } else {
        log::debug(line);
    }
}

void install_debug_callback() {
    GLint flags = 0;
    glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
    glEnable(GL_DEBUG_OUTPUT);
    // Synchronous: the callback runs inside the offending call, so a breakpoint shows the culprit.
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(debug_callback, nullptr);
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
    if (!(flags & GL_CONTEXT_FLAG_DEBUG_BIT))
        log::debug("GL context is not a debug context; errors may be missed");
}

std::string gl_string(GLenum name) {
    const auto* s = reinterpret_cast<const char*>(glGetString(name));
    return s ? s : "";
}

// --- EGL: one display per process, initialised once and never terminated (terminating and
// re-initialising Mesa's surfaceless display between tests is slow and has leaked in the past; the
// display is a process-wide singleton anyway). Contexts are created and destroyed freely.
struct EglDisplay {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLConfig config = nullptr;
    std::string error;
    bool on_device = false;  // EGL_EXT_platform_device (the fallback), not surfaceless
};

const char* egl_error_name(EGLint e) {
    switch (e) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
        default: return "EGL error";
    }
}

// Opens and initialises one EGL display of `platform` (surfaceless Mesa, or one EGL device).
EglDisplay open_display(EGLenum platform, void* native, const char* what) {
    EglDisplay out;
    out.display = eglGetPlatformDisplay(platform, native, nullptr);
    if (out.display == EGL_NO_DISPLAY) {
        out.error = log::str("eglGetPlatformDisplay(", what, "): ", egl_error_name(eglGetError()));
        return out;
    }
    EGLint major = 0, minor = 0;
    if (!eglInitialize(out.display, &major, &minor)) {
        out.error = log::str("eglInitialize(", what, "): ", egl_error_name(eglGetError()));
        out.display = EGL_NO_DISPLAY;
        return out;
    }
    const EGLint attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                              EGL_NONE};
    EGLint count = 0;
    if (!eglChooseConfig(out.display, attribs, &out.config, 1, &count) || count == 0) {
        // Surfaceless needs no surface type; accept any GL-capable config.
        const EGLint any_gl[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        if (!eglChooseConfig(out.display, any_gl, &out.config, 1, &count) || count == 0) out.config = nullptr;
    }
    return out;
}

// The first EGL device that is not a software rasterizer (EGL_EXT_device_enumeration; Mesa marks its
// software device with EGL_MESA_device_software), or null when there is none or no enumeration.
EGLDeviceEXT first_hardware_device() {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client || std::string_view(client).find("EGL_EXT_platform_device") == std::string_view::npos)
        return nullptr;
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_string =
        reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
    if (!query_devices || !query_string) return nullptr;
    EGLint count = 0;
    if (!query_devices(0, nullptr, &count) || count <= 0) return nullptr;
    std::vector<EGLDeviceEXT> devices(std::size_t(count), nullptr);
    if (!query_devices(count, devices.data(), &count)) return nullptr;
    for (EGLint i = 0; i < count; ++i) {
        const char* ext = query_string(devices[std::size_t(i)], EGL_EXTENSIONS);
        if (!ext || std::string_view(ext).find("EGL_MESA_device_software") == std::string_view::npos)
            return devices[std::size_t(i)];
    }
    return nullptr;
}

// GL_RENDERER of a throw-away 4.5 core context on `d` (empty when none can be made).
std::string probe_renderer(const EglDisplay& d) {
    if (!eglBindAPI(EGL_OPENGL_API)) return {};
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              4,
                              EGL_CONTEXT_MINOR_VERSION,
                              5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    const EGLContext ctx = eglCreateContext(d.display, d.config, EGL_NO_CONTEXT, attribs);
    if (ctx == EGL_NO_CONTEXT) return {};
    const EGLDisplay old_display = eglGetCurrentDisplay();
    const EGLContext old_context = eglGetCurrentContext();
    std::string renderer;
    if (eglMakeCurrent(d.display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) renderer = gl_string(GL_RENDERER);
    if (old_context != EGL_NO_CONTEXT)
        eglMakeCurrent(old_display, EGL_NO_SURFACE, EGL_NO_SURFACE, old_context);
    else eglMakeCurrent(d.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(d.display, ctx);
    return renderer;
}

// Surfaceless Mesa first (no device node needed; Mesa picks a render node when it can). When that fails,
// or gives a software renderer while a hardware EGL device exists (a GPU whose driver Mesa's surfaceless
// platform does not drive, e.g. NVIDIA's), the first hardware device through EGL_EXT_platform_device.
const EglDisplay& egl_display() {
    static const EglDisplay d = [] {
        EglDisplay surfaceless =
            open_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, "EGL_PLATFORM_SURFACELESS_MESA");
        EGLDeviceEXT device = first_hardware_device();
        if (!device) {
            if (surfaceless.display == EGL_NO_DISPLAY) surfaceless.error += " (is libegl-mesa0 installed?)";
            return surfaceless;
        }
        if (surfaceless.display != EGL_NO_DISPLAY && surfaceless.config) {
            const std::string renderer = probe_renderer(surfaceless);
            if (!renderer.empty() && !software_renderer_name(renderer)) return surfaceless;
            log::info("EGL surfaceless gives ", renderer.empty() ? "no GL 4.5 context" : renderer,
                      "; trying the first hardware EGL device");
        }
        EglDisplay on_device = open_display(EGL_PLATFORM_DEVICE_EXT, device, "EGL_PLATFORM_DEVICE_EXT");
        if (on_device.display != EGL_NO_DISPLAY && on_device.config) {
            on_device.on_device = true;
            return on_device;
        }
        log::warn("EGL device fallback failed: ",
                  on_device.error.empty() ? "no OpenGL config" : on_device.error);
        if (surfaceless.display == EGL_NO_DISPLAY) surfaceless.error += "; " + on_device.error;
        return surfaceless;
    }();
    return d;
}

// GLFW is initialised when the first window opens and stays initialised until the process exits:
// glfwTerminate() closes the X display, which makes GLVND unload the Mesa driver; its remaining
// allocations then show up in LeakSanitizer as leaks from an "<unknown module>" that no suppression can
// name, and every later window would reload the driver. Windows themselves are destroyed normally.
std::mutex g_glfw_mutex;
bool g_glfw_initialised = false;

void glfw_error(int code, const char* description) { log::error("GLFW error ", code, ": ", description); }

}  // namespace

struct GlContext::Impl {
    bool headless = true;
    EGLContext egl_context = EGL_NO_CONTEXT;
    GLFWwindow* window = nullptr;
    FramebufferSize size;
    bool close_requested = false;
    std::string renderer;
    std::string version;

    ~Impl() {
        if (window) {
            if (glfwGetCurrentContext() == window) glfwMakeContextCurrent(nullptr);
            glfwDestroyWindow(window);
        }
        if (egl_context != EGL_NO_CONTEXT) {
            const EGLDisplay display = egl_display().display;
            if (eglGetCurrentContext() == egl_context)
                eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(display, egl_context);
        }
    }
};

GlContext::GlContext() = default;
GlContext::~GlContext() = default;
GlContext::GlContext(GlContext&&) noexcept = default;
GlContext& GlContext::operator=(GlContext&&) noexcept = default;

void GlContext::make_current() {
    assert(m_impl);
    if (m_impl->window) {
        glfwMakeContextCurrent(m_impl->window);
    } else if (!eglMakeCurrent(egl_display().display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_impl->egl_context)) {
        log::error("eglMakeCurrent(): ", egl_error_name(eglGetError()));
    }
}

void GlContext::release_current() {
    assert(m_impl);
    if (m_impl->window) glfwMakeContextCurrent(nullptr);
    else eglMakeCurrent(egl_display().display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

void GlContext::swap_buffers() {
    if (m_impl && m_impl->window) glfwSwapBuffers(m_impl->window);
}

void GlContext::poll_events() {
    if (m_impl && m_impl->window) glfwPollEvents();
}

bool GlContext::should_close() const {
    if (!m_impl) return true;
    return m_impl->close_requested || (m_impl->window && glfwWindowShouldClose(m_impl->window));
}

void GlContext::request_close() {
    if (!m_impl) return;
    m_impl->close_requested = true;
    if (m_impl->window) glfwSetWindowShouldClose(m_impl->window, GLFW_TRUE);
}

bool GlContext::is_headless() const { return !m_impl || m_impl->headless; }

FramebufferSize GlContext::framebuffer_size() const {
    if (!m_impl) return {};
    if (m_impl->window) {
        FramebufferSize s;
        glfwGetFramebufferSize(m_impl->window, &s.width, &s.height);
        return s;
    }
    return m_impl->size;
}

GLFWwindow* GlContext::window() const { return m_impl ? m_impl->window : nullptr; }

const std::string& GlContext::renderer() const {
    static const std::string none;
    return m_impl ? m_impl->renderer : none;
}

const std::string& GlContext::version() const {
    static const std::string none;
    return m_impl ? m_impl->version : none;
}

bool display_available() {
    const char* x = std::getenv("DISPLAY");
    const char* wl = std::getenv("WAYLAND_DISPLAY");
    return (x && *x) || (wl && *wl);
}

std::uint64_t debug_error_count() { return g_gl_errors.load(); }

namespace {

Result<GlContext> finish(GlContext context, GlContext::Impl& impl, bool debug) {
    impl.renderer = gl_string(GL_RENDERER);
    impl.version = gl_string(GL_VERSION);
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45)
        return make_error(
            log::str("create_context(): need OpenGL 4.5 core, got ", impl.version, " (", impl.renderer, ")"));
    if (hardware_gl_required() && software_renderer_name(impl.renderer))
        return make_error(log::str("create_context(): SFFD_REQUIRE_HARDWARE_GL is set but the renderer is ",
                                   impl.renderer, " (a software rasterizer)"));
    const GlLimits limits = query_limits();
    if (Status s = check_limits(limits); !s)
        return make_error(log::str("create_context(): ", s.message(), " (", impl.renderer, ")"));
    set_context_limits(limits);
    if (debug) install_debug_callback();
    // At info level once per process where the renderer is in question (a GPU run, or the EGL device
    // fallback was taken); otherwise at debug: commands print machine-readable output on the same streams.
    static std::atomic<bool> logged{false};
    const auto line = log::str("GL context: ", impl.headless ? "headless EGL" : "window", ", ", impl.renderer,
                               ", ", impl.version);
    if ((hardware_gl_required() || (impl.headless && egl_display().on_device)) && !logged.exchange(true))
        log::info(line);
    else log::debug(line);
    return context;
}

}  // namespace

Result<GlContext> create_context(const ContextOptions& options) {
    GlContext context;
    context.m_impl = std::make_unique<GlContext::Impl>();
    GlContext::Impl& impl = *context.m_impl;
    impl.size = {options.width, options.height};

    if (!options.headless && display_available()) {
        impl.headless = false;
        {
            std::lock_guard lock(g_glfw_mutex);
            if (!g_glfw_initialised) {
                glfwSetErrorCallback(glfw_error);
                if (!glfwInit()) return make_error("create_context(): glfwInit() failed (is DISPLAY valid?)");
                g_glfw_initialised = true;
            }
        }
        glfwDefaultWindowHints();
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, options.debug ? GLFW_TRUE : GLFW_FALSE);
        glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
        glfwWindowHint(GLFW_DEPTH_BITS, 24);
        impl.window =
            glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
        if (!impl.window) {
            impl.headless = true;
            return make_error("create_context(): glfwCreateWindow() failed for an OpenGL 4.5 core context");
        }
        glfwMakeContextCurrent(impl.window);
        glfwSwapInterval(1);
        return finish(std::move(context), impl, options.debug);
    }

    const EglDisplay& egl = egl_display();
    if (egl.display == EGL_NO_DISPLAY) return make_error("create_context(): " + egl.error);
    if (!eglBindAPI(EGL_OPENGL_API))
        return make_error(
            log::str("create_context(): eglBindAPI(EGL_OPENGL_API): ", egl_error_name(eglGetError())));
    // 4.5 core exactly: llvmpipe on Debian 12 refuses 4.6.
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              4,
                              EGL_CONTEXT_MINOR_VERSION,
                              5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_CONTEXT_OPENGL_DEBUG,
                              options.debug ? EGL_TRUE : EGL_FALSE,
                              EGL_NONE};
    impl.egl_context = eglCreateContext(egl.display, egl.config, EGL_NO_CONTEXT, attribs);
    if (impl.egl_context == EGL_NO_CONTEXT)
        return make_error(
            log::str("create_context(): eglCreateContext(OpenGL 4.5 core): ", egl_error_name(eglGetError())));
    if (!eglMakeCurrent(egl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl.egl_context))
        return make_error(
            log::str("create_context(): eglMakeCurrent(surfaceless): ", egl_error_name(eglGetError())));
    return finish(std::move(context), impl, options.debug);
}

bool software_rasterizer() {
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return renderer && software_renderer_name(renderer);
}

}  // namespace sffd::gfx
