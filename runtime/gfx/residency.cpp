#include "runtime/gfx/residency.h"

#include "runtime/gfx/context.h"

#include <EGL/egl.h>
#include <GLFW/glfw3.h>

#include <algorithm>

namespace sffd::gfx {

void fill_buffer(Buffer& b, const char* label, const void* data, std::size_t bytes) {
    if (!b) b = Buffer::create(label);
    GLint64 have = 0;
    glGetNamedBufferParameteri64v(b.id(), GL_BUFFER_SIZE, &have);
    const std::size_t want = std::max<std::size_t>(bytes, 16);
    if (std::size_t(have) != want) glNamedBufferData(b.id(), GLsizeiptr(want), nullptr, GL_DYNAMIC_DRAW);
    if (bytes > 0 && data) glNamedBufferSubData(b.id(), 0, GLsizeiptr(bytes), data);
}

void* map_for_fill(Buffer& b, const char* label, std::size_t bytes) {
    fill_buffer(b, label, nullptr, bytes);
    if (bytes == 0) return nullptr;
    // Invalidating: the old contents are not read, so the implementation need not wait for draws that
    // still read them (it may hand out fresh memory instead).
    return glMapNamedBufferRange(b.id(), 0, GLsizeiptr(bytes),
                                 GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
}

bool unmap_fill(Buffer& b) { return glUnmapNamedBuffer(b.id()) == GL_TRUE; }

bool cpu_reads_in_place() { return software_rasterizer(); }

void reserve_buffer(Buffer& b, const char* label, std::size_t bytes) {
    const std::size_t want = std::max<std::size_t>(bytes, 16);
    if (!b) {
        b = Buffer::create(label);
        glNamedBufferData(b.id(), GLsizeiptr(want), nullptr, GL_DYNAMIC_COPY);
        return;
    }
    GLint64 have = 0;
    glGetNamedBufferParameteri64v(b.id(), GL_BUFFER_SIZE, &have);
    if (std::size_t(have) < want) glNamedBufferData(b.id(), GLsizeiptr(want), nullptr, GL_DYNAMIC_COPY);
}

bool context_current() {
    return eglGetCurrentContext() != EGL_NO_CONTEXT || glfwGetCurrentContext() != nullptr;
}

void set_rest(ResidentCloud& cloud, std::uint64_t version, std::uint32_t count) {
    cloud.rest_version = version;
    cloud.count = count;
    cloud.state = Residency::rest;
}

void set_deformed(ResidentCloud& cloud, Residency how) {
    cloud.state = how;
    ++cloud.deformed_version;
}

void set_preview(ResidentCloud& cloud, std::uint32_t preview_count) {
    cloud.state = Residency::preview_cpu;
    cloud.preview_count = preview_count;
    ++cloud.deformed_version;
}

}  // namespace sffd::gfx
