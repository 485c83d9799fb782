// The Gaussian GL renderer against the storage-block limits of GL 4.5 (runtime/gfx/limits.h), simulated
// with gfx::ScopedLimits: the blend reads the projection whole and at random, so it is stored as three
// 16-byte arrays (gaussian_layout.h) and a cloud whose arrays exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE is
// refused before anything runs; every program keeps to the storage blocks and binding points the engine
// requires of an implementation; the quads fetch the sorted order as a vertex attribute after the barrier
// that makes the GPU sort's writes visible to vertex fetches.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/gaussian/gl_render.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/systems/gaussian/gl_renderer_fixture.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

class GaussianGlLimits : public sffd::test::GaussianGlRendererTest<sffd::test::HeadlessGlTest> {};

Camera camera_at(glm::dvec3 eye) {
    Camera c;
    c.eye = eye, c.target = glm::dvec3(0.0), c.up = {0, 1, 0}, c.fov_y_degrees = 40.0f;
    return c;
}

GaussianCloud random_cloud(std::size_t n, int degree) { return test::seeded_random_cloud(23, n, degree); }

constexpr std::size_t kCount = 3000;
// 48 bytes a Gaussian (the projection as one array of records) would be 144,000 bytes in one block;
// 16 bytes (each of the three arrays) are 48,000.
constexpr std::int64_t kBetween = 100'000;
constexpr std::int64_t kBelow = 40'000;

std::int64_t bound_size(GLuint binding) {
    GLint64 size = -1;
    glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, binding, &size);
    return size;
}

}  // namespace

// A limit the old 48-byte records would exceed and the 16-byte arrays fit: the image is exactly the
// unlimited one on each sort and blend path, and each projection array is bound as this cloud's 48,000
// bytes, not as the whole grow-only buffer (sized by a larger cloud drawn first).
TEST_F(GaussianGlLimits, ProjectionPastTheOldRecordSizeDrawsTheUnlimitedImage) {
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    const GaussianCloud g = random_cloud(kCount, 1);
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = kBetween;
    ASSERT_GT(std::int64_t(kCount * 48), kBetween);
    ASSERT_LE(std::int64_t(kCount * SFFD_GPU_PROJECTED_STRIDE), kBetween);
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            const std::string what = std::string(blend == BlendPath::tiles ? "tiles" : "quads") +
                                     (sort == SortPath::gpu ? ", GPU sort" : ", CPU sort");
            renderer->sort_path = sort, renderer->blend_path = blend;
            ASSERT_TRUE(render_gl(*renderer, random_cloud(2 * kCount, 1), cam, o));  // grows the buffers
            auto whole = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(whole) << whole.message();
            auto limited = [&] {
                gfx::ScopedLimits scope(small);
                return render_gl(*renderer, g, cam, o);
            }();
            ASSERT_TRUE(limited) << what << ": " << limited.message();
            EXPECT_EQ(limited->color, whole->color) << what;
            EXPECT_GT(psnr(*limited, render_reference(g, cam, o)), 40.0) << what;
            if (blend == BlendPath::tiles) {
                EXPECT_LE(std::int64_t(renderer->tile_entries * 4), kBetween);
            }
            // The blend's bindings (the tile blend rebinds points 7 and 8 to the projection last).
            for (GLuint binding :
                 {SFFD_GAUSS_SSBO_PROJ_CENTER, SFFD_GAUSS_SSBO_PROJ_CONIC, SFFD_GAUSS_SSBO_PROJ_COLOR})
                EXPECT_EQ(bound_size(binding), std::int64_t(kCount * SFFD_GPU_PROJECTED_STRIDE))
                    << what << ", binding " << binding;
        }
}

// A limit even the 16-byte arrays exceed: refused before anything runs (no projection dispatched, so no
// barrier recorded), naming the limit, the count and the buffer, on both entry points.
TEST_F(GaussianGlLimits, ProjectionOverTheBlockSizeIsRefusedNamingTheLimitCountAndBuffer) {
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    const GaussianCloud g = random_cloud(kCount, 0);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = kBelow;
    const auto expect_refusal = [](const std::string& message) {
        EXPECT_NE(message.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (40000)"), std::string::npos) << message;
        EXPECT_NE(message.find("3000 Gaussians"), std::string::npos) << message;
        EXPECT_NE(message.find("gaussian.proj_center: 48000 bytes"), std::string::npos) << message;
    };
    ASSERT_TRUE(upload_gl(*renderer, g));
    gfx::ScopedLimits scope(small);
    for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
        renderer->sort_path = sort;
        gfx::BarrierLog log;
        auto refused = draw_gl(*renderer, camera_at({0.2, 0.3, 3.5}), o);
        ASSERT_FALSE(refused);
        expect_refusal(refused.message());
        GaussianView v;
        v.width = o.width, v.height = o.height;
        v.view = glm::lookAt(glm::dvec3(0.2, 0.3, 3.5), glm::dvec3(0.0), glm::dvec3(0, 1, 0));
        const Status drawn = draw_gaussians(*renderer, resident_buffers(*renderer), v);
        ASSERT_FALSE(drawn);
        expect_refusal(drawn.message());
        EXPECT_TRUE(log.records().empty()) << "GL work was issued before the refusal";
    }
}

// Every program of the renderer within what runtime/gfx/limits.h requires of an implementation (and
// create_context() checks): storage blocks per stage and in all, binding points. GL 4.5 itself
// guarantees no storage block in a vertex shader, 8 per compute shader and 8 binding points.
TEST_F(GaussianGlLimits, ProgramsStayWithinTheRequiredStorageBlocks) {
    const gfx::GlRequirements need;
    const std::pair<const gfx::Program*, const char*> programs[] = {
        {&renderer->project, "project"},          {&renderer->splat, "splat"},
        {&renderer->tile_count, "tile_count"},    {&renderer->tile_emit, "tile_emit"},
        {&renderer->tile_ranges, "tile_ranges"},  {&renderer->tile_blend, "tile_blend"},
        {&renderer->sort_payload, "sort_payload"}};
    for (const auto& [program, name] : programs) {
        GLint blocks = 0;
        glGetProgramInterfaceiv(program->id(), GL_SHADER_STORAGE_BLOCK, GL_ACTIVE_RESOURCES, &blocks);
        int vertex = 0, fragment = 0, compute = 0;
        for (GLint i = 0; i < blocks; ++i) {
            const GLenum props[] = {GL_BUFFER_BINDING, GL_REFERENCED_BY_VERTEX_SHADER,
                                    GL_REFERENCED_BY_FRAGMENT_SHADER, GL_REFERENCED_BY_COMPUTE_SHADER};
            GLint v[4] = {};
            glGetProgramResourceiv(program->id(), GL_SHADER_STORAGE_BLOCK, GLuint(i), 4, props, 4, nullptr,
                                   v);
            EXPECT_LT(v[0], need.ssbo_bindings) << name;
            vertex += v[1] != 0, fragment += v[2] != 0, compute += v[3] != 0;
        }
        EXPECT_GT(blocks, 0) << name;
        EXPECT_LE(vertex, need.vertex_ssbo_blocks) << name;
        EXPECT_LE(fragment, need.fragment_ssbo_blocks) << name;
        EXPECT_LE(compute, need.compute_ssbo_blocks) << name;
        EXPECT_LE(blocks, need.combined_ssbo_blocks) << name;
    }
}

// The GPU sort writes the order through storage blocks; the quads fetch it as an instanced vertex
// attribute, which GL 4.5 §7.12.2 orders only after a VERTEX_ATTRIB_ARRAY barrier (llvmpipe would draw
// the right image without it).
TEST_F(GaussianGlLimits, QuadsFetchTheGpuSortedOrderAfterAVertexAttribBarrier) {
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    renderer->sort_path = SortPath::gpu, renderer->blend_path = BlendPath::quads;
    gfx::BarrierLog log;
    ASSERT_TRUE(render_gl(*renderer, random_cloud(500, 0), camera_at({0.2, 0.3, 3.5}), o));
    std::size_t last_sort = 0, attrib = 0;
    for (std::size_t k = 0; k < log.records().size(); ++k) {
        if (log.records()[k].site == "radix.sort") last_sort = k + 1;
        if (log.records()[k].site == "gaussian.sort" &&
            (log.records()[k].bits & GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT))
            attrib = k + 1;
    }
    ASSERT_GT(last_sort, 0u);
    EXPECT_GT(attrib, last_sort) << "no VERTEX_ATTRIB_ARRAY barrier after the sort";
}
