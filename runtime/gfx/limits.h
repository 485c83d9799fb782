// The GL implementation limits the engine depends on, queried once per context at start-up
// (create_context) into one struct, and the checks against them.
//
// GL 4.5 guarantees little for shader storage: no SSBO in a vertex shader at all, 8 binding points, and a
// small maximum block size (2^24 bytes in the spec's table of minimums). The engine needs more (below);
// create_context() refuses a context that lacks it, naming the limit. Buffers that can outgrow the block
// size (the cull's records at 192 bytes per splat, the compute rasteriser's sums at 36 bytes per pixel)
// are checked where they are bound with ssbo_fits(); their passes fall back to a path that needs no such
// block (systems/splat_render/README.md).
//
//   const gfx::GlLimits& l = gfx::limits();       // the current context's, or a test's override
//   if (!gfx::ssbo_fits(bytes)) ...                // the range bound to one block would be cut short
//
// Tests simulate a small implementation with ScopedLimits (tests/runtime/limits_test.cpp).
#pragma once

#include <cstdint>
#include <string>

#include "runtime/core/result.h"

namespace sffd::gfx {

struct GlLimits {
    std::int64_t max_ssbo_block_size = 0;  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE, bytes
    int max_ssbo_bindings = 0;             // GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS
    int max_vertex_ssbo_blocks = 0;        // GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS
    int max_fragment_ssbo_blocks = 0;      // GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS
    int max_compute_ssbo_blocks = 0;       // GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS
    int max_combined_ssbo_blocks = 0;      // GL_MAX_COMBINED_SHADER_STORAGE_BLOCKS
    int ssbo_offset_alignment = 0;   // GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, bytes (glBindBufferRange)
    int max_uniform_block_size = 0;  // GL_MAX_UNIFORM_BLOCK_SIZE, bytes
    int max_compute_groups_x = 0;    // GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    int max_compute_groups_y = 0;    // GL_MAX_COMPUTE_WORK_GROUP_COUNT[1]
    float max_point_size = 0;        // GL_POINT_SIZE_RANGE[1]
};

// What the engine's shaders need beyond GL 4.5's guarantees (each with the shader that needs it).
struct GlRequirements {
    int vertex_ssbo_blocks = 3;    // splat_render/splat.vert: splats, quad list, uv axes (and
                                   // gaussian/splat.vert: the projection's three arrays)
    int fragment_ssbo_blocks = 2;  // splat_render/compute_resolve.frag: raster depth and sums
    int compute_ssbo_blocks = 8;   // gaussian/deform.comp: 7 of its own plus the lattice's control points
                                   // (and gaussian/project.comp, gaussian/gather.comp: 8)
    int combined_ssbo_blocks = 8;  // the largest program (gaussian/deform.comp)
    int ssbo_bindings = 13;        // binding points 0..12 (shaders/splat_render/compute_raster.h)
};

// Reads the limits of the context current on this thread.
GlLimits query_limits();

// Ok, or one message naming every limit below what `need` asks: "GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS is 0,
// splat_render/splat.vert needs 3".
Status check_limits(const GlLimits& have, const GlRequirements& need = {});

// The limits of the newest context created in this process (create_context stores them), unless a
// ScopedLimits overrides them on this thread.
const GlLimits& limits();
void set_context_limits(const GlLimits& limits);  // create_context() only

// Whether `bytes` bound to one storage block are all visible to the shader.
bool ssbo_fits(std::uint64_t bytes, const GlLimits& l = limits());

// "render.visible_splats: 201326592 bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (134217728)".
std::string ssbo_too_large(const char* what, std::uint64_t bytes, const GlLimits& l = limits());

// Overrides limits() on this thread while alive (tests simulate an implementation with small limits).
class ScopedLimits {
public:
    explicit ScopedLimits(const GlLimits& limits);
    ~ScopedLimits();
    ScopedLimits(const ScopedLimits&) = delete;
    ScopedLimits& operator=(const ScopedLimits&) = delete;

private:
    GlLimits m_limits;
    const GlLimits* m_previous;
};

// The GL renderer of the newest context and whether it is a software rasterizer, and the environment
// variable that makes create_context() refuse one: SFFD_REQUIRE_HARDWARE_GL=1 (GPU test runs set it, so
// a run that silently lands on llvmpipe fails instead of passing).
bool hardware_gl_required();
bool software_renderer_name(const std::string& renderer);

}  // namespace sffd::gfx
