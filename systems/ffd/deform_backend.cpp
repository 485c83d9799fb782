#include "systems/ffd/deform_backend.h"

#include <EGL/egl.h>
#include <GLFW/glfw3.h>

#include "runtime/gfx/context.h"
#include "systems/ffd/ffd_system.h"

namespace sffd::ffd {

DeformBackend choose_deform_backend(const FfdSettings* settings) {
    DeformBackend b;
    const bool force_gpu = settings && settings->force_gpu;
    b.have_gl = eglGetCurrentContext() != EGL_NO_CONTEXT || glfwGetCurrentContext() != nullptr;
    b.force_cpu =
        (settings && settings->force_cpu) || (b.have_gl && !force_gpu && gfx::software_rasterizer());
    return b;
}

}  // namespace sffd::ffd
