// The material is its own component: an edit (a replayed slider gesture, the same path as the
// inspector's) re-renders only. The cloud's change stamp, its deformed output, its GPU residency and the
// picking scene stay as they were; the image changes; undo restores the material and the image; and the
// undo step holds two materials, whatever the size of the cloud.
#include <gtest/gtest.h>

#include <cstdlib>
#include <new>
#include <optional>
#include <vector>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/scene.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/splat_store.h"
#include "systems/animation/components.h"
#include "systems/editor/editor_state.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/material_edit.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/components.h"
#include "systems/picking/picking_state.h"
#include "systems/picking/splat_source.h"
#include "systems/splat_render/splat_render.h"
#include "tests/test_util/gl_required.h"

// Bytes allocated through operator new by this thread: what recording an undo step costs in memory.
namespace {
thread_local std::size_t t_allocated = 0;
}
void* operator new(std::size_t n) {
    t_allocated += n;
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
// The replaced operator new allocates with malloc, so free is the matching release; GCC inlines the pair
// into callers and then reports them as mismatched.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace sffd::editor {
namespace {

// Bytes allocated by one material edit of a cloud of `splats` splats (its undo step included).
std::size_t material_edit_bytes(std::size_t splats) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<SplatCloud>(e, assets::make_sphere_cloud(splats));
    reg.emplace<SplatMaterial>(e);
    EditorState state;
    {  // the counter sees a copy of the cloud, which is what an undo step of the whole cloud would cost
        const std::size_t at = t_allocated;
        const SplatCloud copy = reg.get<SplatCloud>(e);
        EXPECT_GT(t_allocated - at, splats * sizeof(glm::vec3)) << copy.size();
    }
    const std::size_t at = t_allocated;
    EXPECT_TRUE(set_material_value(reg, state, e, MaterialField::specular, 0.9f));
    const std::size_t bytes = t_allocated - at;
    EXPECT_EQ(reg.get<SplatMaterial>(e).specular, 0.9f);
    EXPECT_EQ(state.undo.size(), 1u);
    const auto* step = dynamic_cast<const ComponentChange<SplatMaterial>*>(&state.undo.at(0));
    EXPECT_NE(step, nullptr) << "the undo step stores the material, not the cloud";
    return bytes;
}

TEST(MaterialEdit, UndoStepIsTheSameSmallSizeForASmallAndALargeCloud) {
    const std::size_t small = material_edit_bytes(1000), large = material_edit_bytes(200000);
    EXPECT_EQ(small, large);
    EXPECT_LT(large, 1024u);
}

TEST(MaterialEdit, SliderRangeClampsAndAnEntityWithoutAMaterialIsRefused) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<SplatCloud>(e, assets::make_sphere_cloud(100));
    EditorState state;
    EXPECT_FALSE(set_material_value(reg, state, e, MaterialField::shininess, 8.0f));
    EXPECT_EQ(state.undo.size(), 0u);
    reg.emplace<SplatMaterial>(e);
    EXPECT_EQ(material_target(reg, state), e);
    EXPECT_TRUE(set_material_value(reg, state, e, MaterialField::shininess, 1000.0f));
    EXPECT_EQ(reg.get<SplatMaterial>(e).shininess, 256.0f);
    EXPECT_TRUE(set_material_value(reg, state, e, MaterialField::base_g, -1.0f));
    EXPECT_EQ(reg.get<SplatMaterial>(e).base_color.y, 0.0f);
    ASSERT_TRUE(material_field("material.base_color.g"));
    EXPECT_FALSE(material_field("material.roughness"));
}

class MaterialEditFrame : public testing::Test {
protected:
    static constexpr int kWidth = 128, kHeight = 96;
    void SetUp() override {
        auto c = gfx::create_context({.headless = true, .width = kWidth, .height = kHeight});
        if (!c) SFFD_GL_UNAVAILABLE(c.message());
        ctx.emplace(std::move(*c));
    }
    std::optional<gfx::GlContext> ctx;
};

std::size_t differing(const render::FrameImage& a, const render::FrameImage& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.color.size() && i < b.color.size(); ++i) n += a.color[i] != b.color[i];
    return n;
}

TEST_F(MaterialEditFrame, AReplayedSliderEditReRendersOnlyAndUndoRestoresIt) {
    ecs::Registry reg;
    use_engine_scene_hooks(reg);
    const Status loaded = load_scene(reg, "sphere");
    ASSERT_TRUE(loaded) << loaded.message();
    // A still scene (the sphere's demo clip would re-deform every frame) with one control point moved, so
    // the cloud has a deformed output whose version must stay put.
    std::vector<ecs::Entity> clips;
    reg.each_entity([&](ecs::Entity e) {
        if (reg.has<AnimationClip>(e)) clips.push_back(e);
    });
    for (ecs::Entity e : clips) reg.remove<AnimationClip>(e);
    ecs::Entity cloud = ecs::null_entity;
    reg.each_entity([&](ecs::Entity e) {
        if (reg.has<SplatCloud>(e)) cloud = e;
    });
    ASSERT_TRUE(reg.valid(cloud) && reg.has<SplatMaterial>(cloud) && reg.has<Deformers>(cloud));
    const ecs::Entity lattice = reg.get<Deformers>(cloud).lattices.at(0);
    Lattice& l = reg.patch<Lattice>(lattice);
    l.current[l.current.size() / 2] += glm::dvec3(0.0, 0.0, 0.3);
    render::RenderSettings settings;
    settings.quality = render::Quality::preview;  // lit per splat with the material's specular
    settings.width = kWidth, settings.height = kHeight;
    reg.set_resource<render::RenderSettings>(settings);
    EditorState& state = setup_editor(reg, Viewport{kWidth, kHeight});

    const Schedule schedule = make_engine_schedule({.present = false});
    auto frame = [&](std::uint64_t k) {
        auto image = render_engine_frame(reg, schedule, *ctx, {.frame = k});
        EXPECT_TRUE(image) << image.message();
        return image ? std::move(*image) : render::FrameImage{};
    };
    frame(0);
    const render::FrameImage before = frame(1);

    struct Stamps {
        std::uint64_t cloud, deformed, rest_version, deformed_version, rest_uploads, deformed_uploads;
        gfx::Residency residency;
        std::uint64_t pick_version;
    };
    picking::PickCache pick_cache;
    auto stamps = [&] {
        const gfx::GpuSplats& gpu = reg.resource<gfx::GpuSplatStore>().clouds.at(cloud);
        const auto& uploads = reg.resource<gfx::ResidencyStats>();
        return Stamps{reg.version<SplatCloud>(cloud),
                      reg.get<DeformedSplats>(cloud).version,
                      gpu.rest_version,
                      gpu.deformed_version,
                      uploads.rest_uploads,
                      uploads.deformed_uploads,
                      gpu.state,
                      picking::splat_source(reg, cloud, pick_cache).version};
    };
    picking::PickingState picking;
    picking.refresh(reg);
    const picking::PickingState::Stats picked = picking.stats();
    const Stamps s0 = stamps();
    ASSERT_NE(s0.residency, gfx::Residency::rest) << "the moved control point deformed the cloud";

    // What a slider drag does, replayed: the input system applies `set` events on the selected cloud.
    state.selected_entity = cloud;
    const SplatMaterial original = reg.get<SplatMaterial>(cloud);
    state.events.push_back({.kind = InputKind::set, .key = "material.specular", .value = 1.0});
    state.events.push_back({.kind = InputKind::set, .key = "material.shininess", .value = 3.0});
    const render::FrameImage edited = frame(2);
    EXPECT_EQ(reg.get<SplatMaterial>(cloud).specular, 1.0f);
    EXPECT_EQ(reg.get<SplatMaterial>(cloud).shininess, 3.0f);
    EXPECT_EQ(state.undo.size(), 2u);

    const Stamps s1 = stamps();
    EXPECT_EQ(s1.cloud, s0.cloud) << "the authored cloud's change stamp";
    EXPECT_EQ(s1.deformed, s0.deformed) << "no re-deformation";
    EXPECT_EQ(s1.rest_version, s0.rest_version);
    EXPECT_EQ(s1.deformed_version, s0.deformed_version) << "the deformed buffer was not rewritten";
    EXPECT_EQ(s1.rest_uploads, s0.rest_uploads) << "no re-upload";
    EXPECT_EQ(s1.deformed_uploads, s0.deformed_uploads) << "no re-upload";
    EXPECT_EQ(s1.residency, s0.residency);
    EXPECT_EQ(s1.pick_version, s0.pick_version) << "the picking data's version";
    EXPECT_FALSE(picking.refresh(reg)) << "no Embree commit";
    EXPECT_EQ(picking.stats().geometries_updated, picked.geometries_updated);
    EXPECT_EQ(picking.stats().geometries_created, picked.geometries_created);
    EXPECT_GT(differing(before, edited), std::size_t(kWidth * kHeight / 50)) << "the image shows the edit";

    undo(reg, state);
    undo(reg, state);
    EXPECT_EQ(reg.get<SplatMaterial>(cloud), original);
    const render::FrameImage undone = frame(3);
    EXPECT_EQ(differing(before, undone), 0u) << "undo restores the image";
    const Stamps s2 = stamps();
    EXPECT_EQ(s2.cloud, s0.cloud);
    EXPECT_EQ(s2.deformed_version, s0.deformed_version);
    EXPECT_EQ(s2.rest_uploads, s0.rest_uploads);
    render::release_render_state(reg);
}

}  // namespace
}  // namespace sffd::editor
