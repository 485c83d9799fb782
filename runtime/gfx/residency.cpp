#include "runtime/gfx/residency.h"

#include "runtime/gfx/context.h"

#include <EGL/egl.h>
#include <GLFW/glfw3.h>

#include <algorithm>
#include <numeric>

#include "runtime/gfx/point_marks.h"

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

bool ResidentCloud::MarksState::any_selected() const {
    return std::any_of(page_selected.begin(), page_selected.end(), [](std::uint32_t k) { return k != 0; });
}
bool ResidentCloud::MarksState::any_gone() const {
    return std::any_of(page_gone.begin(), page_gone.end(), [](std::uint32_t k) { return k != 0; });
}

namespace {

// Packs the marks of page `page` into `words` (two a word) and counts its selected and gone points.
void pack_page(ResidentCloud::MarksState& m, const PointMarkSources& s, std::size_t n, std::size_t page,
               std::uint32_t* words) {
    const PageRange r = page_range(page, n);
    std::uint32_t selected = 0, gone = 0;
    for (std::size_t k = 0; k < r.count; k += 2) {
        const std::uint16_t lo = point_mark_of(s.flags, s.weights, n, r.first + k);
        const std::uint16_t hi =
            k + 1 < r.count ? point_mark_of(s.flags, s.weights, n, r.first + k + 1) : kDefaultPointMark;
        for (const std::uint16_t mark : {lo, hi}) {
            gone += mark_gone(mark) ? 1u : 0u;
            selected += !mark_gone(mark) && (mark & SFFD_MARK_SELECTED) ? 1u : 0u;
        }
        words[k / 2] = std::uint32_t(lo) | (std::uint32_t(hi) << 16);
    }
    m.page_selected[page] = selected, m.page_gone[page] = gone;
}

}  // namespace

std::size_t sync_point_marks(ResidentCloud& c, std::size_t n, const PointMarkSources& s) {
    ResidentCloud::MarksState& m = c.marks_state;
    const bool flags = n > 0 && s.flags && s.flags->bits.size() == n;
    const bool weights = n > 0 && s.weights && s.weights->values.size() == n;
    if (!flags && !weights) {
        if (c.marks) c.marks.reset(), c.preview_index.reset();
        m = {};
        return 0;
    }
    const std::uint64_t fv = flags ? s.flags_version : 0, wv = weights ? s.weights_version : 0;
    bool full = !c.marks || m.count != n || m.rest_version != c.rest_version || m.flags != flags ||
                m.weights != weights;
    if (!full && fv == m.flags_version && wv == m.weights_version) return 0;
    const std::size_t pages = page_count(n);
    std::vector<std::uint32_t> dirty;
    if (!full) {
        // Only the pages an edit marked (point_pages.h), when every change of the columns was marked.
        const PointPages* p = s.pages;
        constexpr PointColumn groups[] = {PointColumn::selection, PointColumn::visibility,
                                          PointColumn::weight};
        if (p && p->points == n && p->clock >= m.clock && p->stamps[0].size() == pages &&
            (!flags || p->flags_version == fv) && (!weights || p->weights_version == wv))
            dirty = pages_changed_since(*p, m.clock, groups);
        else full = true;
    }
    m.page_selected.resize(pages), m.page_gone.resize(pages);
    std::size_t packed = 0;
    if (full) {
        fill_buffer_in_place(c.marks, "cloud.marks", point_mark_words(n) * sizeof(std::uint32_t),
                             [&](void* dst) {
                                 auto* words = static_cast<std::uint32_t*>(dst);
                                 for (std::size_t page = 0; page < pages; ++page)
                                     pack_page(m, s, n, page, words + (page << kPageShift) / 2);
                             });
        packed = n;
    } else {
        std::vector<std::uint32_t> words(kPagePoints / 2);
        for (const std::uint32_t page : dirty) {
            const PageRange r = page_range(page, n);
            pack_page(m, s, n, page, words.data());
            glNamedBufferSubData(c.marks.id(), GLintptr(r.first / 2 * sizeof(std::uint32_t)),
                                 GLsizeiptr(point_mark_words(r.count) * sizeof(std::uint32_t)), words.data());
            packed += r.count;
        }
    }
    m.flags_version = fv, m.weights_version = wv;
    m.clock = s.pages ? s.pages->clock : 0;
    m.rest_version = c.rest_version;
    m.count = std::uint32_t(n);
    m.flags = flags, m.weights = weights;
    sync_preview_index(c);
    return packed;
}

void sync_preview_index(ResidentCloud& c) {
    if (!c.marks || c.state != Residency::preview_cpu || c.preview_indices.size() != c.preview_count ||
        c.preview_index_key == c.deformed_version + 1)
        return;
    fill_buffer(c.preview_index, "cloud.preview_index", c.preview_indices.data(),
                c.preview_indices.size() * sizeof(std::uint32_t));
    c.preview_index_key = c.deformed_version + 1;
}

std::uint32_t resident_marks_mode(const ResidentCloud& c) {
    if (!c.marks || c.marks_state.count != c.count) return 0;
    if (c.state != Residency::preview_cpu) return SFFD_MARKS_PRESENT;
    return c.preview_index_key == c.deformed_version + 1 ? SFFD_MARKS_PRESENT | SFFD_MARKS_INDEXED : 0u;
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
