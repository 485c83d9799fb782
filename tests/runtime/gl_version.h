// What the current GL context is, read back from GL itself (not from what was requested): the headless
// and the window test check the same properties of the contexts create_context() makes.
#pragma once

#include "runtime/gfx/gl.h"

namespace sffd::test {

struct CurrentContext {
    int version = 0;     // major * 10 + minor
    bool core = false;   // GL_CONTEXT_CORE_PROFILE_BIT
    bool debug = false;  // GL_CONTEXT_FLAG_DEBUG_BIT
};

inline CurrentContext current_context() {
    GLint major = 0, minor = 0, profile = 0, flags = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
    return {major * 10 + minor, (profile & GL_CONTEXT_CORE_PROFILE_BIT) != 0,
            (flags & GL_CONTEXT_FLAG_DEBUG_BIT) != 0};
}

}  // namespace sffd::test
