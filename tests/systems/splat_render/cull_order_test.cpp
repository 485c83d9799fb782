// The compute cull's lists keep splat order (cull.comp): its draws blend and depth-test in list order, so
// that order is what makes a frame the same image every time it is drawn. Read back from the GPU: the
// sprite records and the quad indices of a grid of splats whose screen positions give their index away.
// llvmpipe runs a dispatch's invocations in order, so an atomic append kept this order there too; on an
// NVIDIA H200 it did not (two renders of one frame differed).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "runtime/gfx/dispatch.h"
#include "systems/splat_render/splat_render_detail.h"
#include "tests/systems/splat_render/gl_fixture.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

constexpr int kSide = 64;  // 4,096 splats: 32 work groups of the cull

// A kSide x kSide grid in the plane z = 0 facing the camera, row by row from the top left: a kept splat's
// sprite centre (NDC) is below, or on the same row right of, every kept splat before it. Every 5th splat
// faces away (culled); every 97th is moved off-screen to the right and enlarged so its disc reaches into
// the frame (a quad: sprites are clipped by their centre).
SplatCloud grid() {
    SplatCloud c;
    const float step = 1.2f / float(kSide), r = 0.4f * step;
    for (int row = 0; row < kSide; ++row)
        for (int col = 0; col < kSide; ++col) {
            const std::size_t i = c.positions.size();
            glm::vec3 p(-0.6f + step * float(col), 0.6f - step * float(row), 0.0f);
            float radius = r;
            if (i % 97 == 0) p.x = 1.5f, radius = 0.6f;
            c.positions.push_back(p);
            c.normals.push_back(glm::vec3(0.0f, 0.0f, i % 5 == 1 ? -1.0f : 1.0f));
            c.axis_u.push_back(glm::vec3(radius, 0.0f, 0.0f));
            c.axis_v.push_back(glm::vec3(0.0f, radius, 0.0f));
            c.colors.push_back(0xffffffffu);
            c.uvs.push_back(glm::vec2(0.0f));
        }
    return c;
}

class CullOrder_ : public GlRenderTest {
protected:
    template <class T>
    std::vector<T> read(GLuint buffer, std::size_t count) {
        std::vector<T> out(count);
        if (count) glGetNamedBufferSubData(buffer, 0, GLsizeiptr(count * sizeof(T)), out.data());
        return out;
    }
};

}  // namespace

TEST_F(CullOrder_, ComputeCullListsKeepSplatOrder) {
    add_camera(2.6);
    add_light({-0.5f, -0.4f, -0.6f}, 0.15f);
    const ecs::Entity e = add_cloud(grid());
    for (std::uint32_t groups_per_row : {0u, 3u}) {  // one row of work groups; a 3 x 11 grid of them
        SCOPED_TRACE(groups_per_row ? "3 groups per row" : "one row");
        gfx::ScopedDispatchLimit limit(groups_per_row ? groups_per_row : gfx::dispatch_group_limit());
        (void)render(Quality::hq, 320, 240, true, CullPath::compute);
        ASSERT_EQ(reg.resource<RenderStats>().compute_culled_clouds, 1u);
        const detail::CloudGpu& gpu = reg.get<detail::CloudGpu>(e);
        const auto commands = read<std::uint32_t>(gpu.commands.id(), detail::draw_command_words);
        const std::uint32_t sprites = commands[0], quads = commands[5];
        // Facing the camera: 4 of every 5 splats; the quads: those of the enlarged ones that face it.
        EXPECT_GT(sprites, 3000u);
        EXPECT_GE(quads, 20u);
        const auto records = read<SplatRecord>(gpu.records.id(), sprites);
        int out_of_order = 0;
        for (std::size_t k = 1; k < records.size(); ++k) {
            const glm::vec4 a = records[k - 1].center, b = records[k].center;
            const bool after = b.y < a.y - 1e-4f || (std::abs(b.y - a.y) <= 1e-4f && b.x > a.x);
            out_of_order += !after;
        }
        EXPECT_EQ(out_of_order, 0) << "of " << records.size() << " sprite records";
        const auto indices = read<std::uint32_t>(gpu.quads.id(), quads);
        EXPECT_TRUE(std::is_sorted(indices.begin(), indices.end()));
        EXPECT_TRUE(std::adjacent_find(indices.begin(), indices.end()) == indices.end());
        for (std::uint32_t i : indices) EXPECT_EQ(i % 97, 0u) << i;
    }
}
