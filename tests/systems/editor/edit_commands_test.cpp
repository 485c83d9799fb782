// Edits as commands: the panels post, the input phase applies (pending_edits.h); the animation is the one
// writer of an animated lattice's pose; undo brings deleted entities back (entity_undo.h) and a step holds
// what it changed.
#include <cstring>
#include <numbers>

#include <gtest/gtest.h>
#include <imgui.h>

#include "runtime/scene/components.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/entity_undo.h"
#include "systems/editor/lattice_manage.h"
#include "systems/editor/panels.h"
#include "systems/editor/pending_edits.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/picking/components.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

template <class T>
bool bit_equal(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

InputEvent key(const char* k, std::uint8_t m = 0) {
    InputEvent e;
    e.kind = InputKind::key, e.key = k, e.modifiers = m;
    return e;
}

// A cloud (a sphere of points inside [-1,1]^3), a camera, optionally a 3x3x3 lattice bound to the cloud.
struct World {
    ecs::Registry reg;
    ecs::Entity cloud, lattice;
    EditorState* state = nullptr;
    std::uint64_t frame = 0;

    explicit World(bool with_lattice = true, int points = 800) {
        cloud = reg.create();
        reg.emplace<Name>(cloud, Name{"ball"});
        reg.emplace<Transform>(cloud, Transform{});
        SplatCloud& c = reg.emplace<SplatCloud>(cloud);
        const int rows = 20, cols = points / rows;
        for (int a = 0; a < cols; ++a)
            for (int b = 0; b < rows; ++b) {
                const double th = a * 2 * std::numbers::pi / cols, ph = (b + 0.5) * std::numbers::pi / rows;
                const glm::vec3 n(std::sin(ph) * std::cos(th), std::cos(ph), std::sin(ph) * std::sin(th));
                c.positions.push_back(0.6f * n);
                c.normals.push_back(n);
                c.axis_u.push_back(0.02f * glm::normalize(glm::cross(n, glm::vec3(0.3f, 1, 0.1f))));
                c.axis_v.push_back(0.02f *
                                   glm::cross(n, glm::normalize(glm::cross(n, glm::vec3(0.3f, 1, 0.1f)))));
            }
        if (with_lattice) {
            lattice = reg.create();
            reg.emplace<Name>(lattice, Name{"ball.lattice"});
            reg.emplace<Transform>(lattice, Transform{});
            reg.emplace<Lattice>(
                lattice,
                make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                             {3, 3, 3}));
            reg.emplace<Deformers>(cloud, Deformers{{lattice}});
        }
        Camera& cam = reg.emplace<Camera>(reg.create());
        cam.eye = {0.6, 0.8, 6.0};
        cam.target = {0, 0, 0};
        reg.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
        state = &setup_editor(reg, Viewport{800, 600});
    }
    // The engine's order for what these tests need: input, animation, deformation.
    void run(std::vector<InputEvent> events = {}) {
        for (auto& e : events) e.frame = frame;
        state->events = std::move(events);
        const FrameContext f{frame, frame / 60.0, 1 / 60.0};
        editor_input_system(reg, f);
        animation_system(reg, f);
        ffd_system(reg, f);
        ++frame;
    }
    std::vector<glm::vec3> deformed() const { return reg.get<DeformedSplats>(cloud).positions; }
    ecs::Entity only_lattice() const {
        ecs::Entity found = ecs::null_entity;
        std::size_t n = 0;
        reg.each_entity([&](ecs::Entity e) {
            if (reg.has<Lattice>(e)) found = e, ++n;
        });
        return n == 1 ? found : ecs::null_entity;
    }
};

std::vector<InputEvent> typed(std::initializer_list<const char*> names) {
    std::vector<InputEvent> out;
    for (const char* k : names) out.push_back(key(k));
    return out;
}

// A clip stretching the lattice's centre point up over one second, paused at 0.5 s.
void attach_paused_clip(ecs::Registry& reg, ecs::Entity lattice) {
    AnimationClip clip;
    clip.name = "lift";
    const Lattice& l = reg.get<Lattice>(lattice);
    const std::size_t t =
        add_stretch_track(clip, "lift", {std::uint32_t(l.index(1, 1, 1)), std::uint32_t(l.index(2, 2, 2))});
    set_key(clip.tracks[t], {0.0, {0, 0, 0}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[t], {1.0, {0, 0.4, 0}, Interpolation::linear, Easing::none});
    attach_clip(reg, lattice, std::move(clip), false);
    scrub(reg.patch<AnimationState>(lattice), 0.5);
}

}  // namespace

// --- panels post, the input phase applies ----------------------------------------------------------

TEST(PendingEdits, PostedEditsWaitForTheInputPhaseAndAReleaseIsOneUndoStep) {
    World w(false);
    const Transform before = w.reg.get<Transform>(w.cloud);
    Transform moved = before;
    moved.translation.x = 0.5;
    const std::uint64_t stamp = w.reg.version<Transform>(w.cloud);
    post_component<Transform>(w.reg, w.cloud, moved);  // a drag's live value
    EXPECT_EQ(w.reg.get<Transform>(w.cloud).translation.x, 0.0) << "posting writes nothing";
    EXPECT_EQ(w.reg.version<Transform>(w.cloud), stamp);
    w.run();
    EXPECT_EQ(w.reg.get<Transform>(w.cloud).translation.x, 0.5);
    EXPECT_GT(w.reg.version<Transform>(w.cloud), stamp) << "patched: the systems that read it see it";
    EXPECT_EQ(w.state->undo.size(), 0u) << "no step while the widget is held";
    moved.translation.x = 0.75;
    post_component_step<Transform>(w.reg, w.cloud, before, moved, "move entity");  // released
    w.run();
    ASSERT_EQ(w.state->undo.size(), 1u);
    EXPECT_EQ(w.state->undo.at(0).label(), "move entity");
    EXPECT_EQ(w.reg.get<Transform>(w.cloud).translation.x, 0.75);
    // Operations are posted too, and run in order: undo, then a redo.
    post_edit(w.reg, "undo", [](ecs::Registry& r, EditorState& s) { undo(r, s); });
    w.run();
    EXPECT_EQ(w.reg.get<Transform>(w.cloud).translation.x, 0.0) << "undone back to the value at activation";
    post_edit(w.reg, "redo", [](ecs::Registry& r, EditorState& s) { redo(r, s); });
    post_edit(w.reg, "undo", [](ecs::Registry& r, EditorState& s) { undo(r, s); });
    post_edit(w.reg, "redo", [](ecs::Registry& r, EditorState& s) { redo(r, s); });
    w.run();
    EXPECT_EQ(w.reg.get<Transform>(w.cloud).translation.x, 0.75);
    EXPECT_EQ(pending_edits(w.reg).applied, 6u);
    EXPECT_TRUE(pending_edits(w.reg).queue.empty());
}

// The inspector in a headless ImGui context: a mouse drag on the translation's x field. While ImGui draws
// nothing is written (the Transform's change stamp stays); the next input phase sets the value, and the
// release is one undo step.
TEST(PendingEdits, TheInspectorsDragIsPostedAndAppliedInTheNextInputPhase) {
    World w(false);
    const ecs::Entity mover = w.reg.create();  // only a Transform: its header is the inspector's first row
    w.reg.emplace<Transform>(mover, Transform{});
    w.state->selected_entity = mover;
    ImGuiContext* ctx = ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    unsigned char* px = nullptr;
    int aw = 0, ah = 0;
    io.Fonts->GetTexDataAsRGBA32(&px, &aw, &ah);
    std::size_t frames = 0, drawn_without_writes = 0;
    const auto ui_frame = [&](ImVec2 mouse, bool down) {
        const std::uint64_t stamp = w.reg.storage_version<Transform>();
        io.DisplaySize = ImVec2(1280, 720);
        io.DeltaTime = 1.0f / 60.0f;
        io.MousePos = mouse;
        io.MouseDown[0] = down;
        ImGui::NewFrame();
        draw_panels(w.reg, FrameContext{});
        ImGui::Render();
        ++frames;
        drawn_without_writes += w.reg.storage_version<Transform>() == stamp;
        w.run();  // the next frame's input phase applies what the panels posted
    };
    for (int f = 0; f < 3; ++f) ui_frame(ImVec2(-100, -100), false);  // the layout settles
    PanelRect inspector{};
    for (const NamedPanelRect& p : panel_rects(w.reg))
        if (p.name == panel_title(Panel::inspector)) inspector = p.rect;
    ASSERT_GT(inspector.w, 0.0f);
    // Title bar, the Transform header, then the translation row; its x field starts at the left padding.
    const ImGuiStyle& style = ImGui::GetStyle();
    const float frame_h = ImGui::GetFontSize() + 2 * style.FramePadding.y;
    const ImVec2 at(
        inspector.x + style.WindowPadding.x + 10.0f,
        inspector.y + frame_h + style.WindowPadding.y + frame_h + style.ItemSpacing.y + 0.5f * frame_h);
    ui_frame(at, true);
    for (int k = 1; k <= 4; ++k) {
        ui_frame(ImVec2(at.x + 10.0f * k, at.y), true);
        if (k == 2) {
            EXPECT_GT(w.reg.get<Transform>(mover).translation.x, 0.0) << "live while dragging";
        }
    }
    ui_frame(ImVec2(at.x + 40.0f, at.y), false);
    ui_frame(ImVec2(-100, -100), false);
    ImGui::DestroyContext(ctx);
    EXPECT_EQ(drawn_without_writes, frames) << "a panel wrote the Transform while drawing";
    EXPECT_NEAR(w.reg.get<Transform>(mover).translation.x, 0.4, 1e-9) << "40 px at 0.01 per px";
    EXPECT_EQ(w.reg.get<Transform>(mover).translation.y, 0.0);
    ASSERT_EQ(w.state->undo.size(), 1u) << "one step for the whole drag";
    EXPECT_EQ(w.state->undo.at(0).label(), "move entity");
    post_edit(w.reg, "undo", [](ecs::Registry& r, EditorState& s) { undo(r, s); });
    w.run();
    EXPECT_EQ(w.reg.get<Transform>(mover).translation.x, 0.0);
}

// --- entities come back ----------------------------------------------------------------------------

// shift+a creates a lattice entity; undo destroys it (nothing empty is left); redo creates it again with
// the same components, bound to the cloud under its new id.
TEST(LatticeLife, AddUndoRedoCreatesAndDestroysTheEntity) {
    World w(false);
    const std::size_t alive = w.reg.alive();
    w.run({key("a", mods::shift)});
    const ecs::Entity added = w.only_lattice();
    ASSERT_TRUE(w.reg.valid(added));
    EXPECT_EQ(w.reg.alive(), alive + 1);
    const Lattice lattice = w.reg.get<Lattice>(added);
    const std::string name = w.reg.get<Name>(added).value;
    const std::vector<glm::vec3> deformed = w.deformed();
    w.run({key("z", mods::ctrl)});
    EXPECT_FALSE(w.reg.valid(added));
    EXPECT_EQ(w.reg.alive(), alive) << "undo leaves no empty entity behind";
    EXPECT_TRUE(w.reg.get<Deformers>(w.cloud).lattices.empty());
    EXPECT_FALSE(w.reg.valid(w.state->active_lattice));
    EXPECT_TRUE(bit_equal(w.deformed(), w.reg.get<SplatCloud>(w.cloud).positions)) << "no lattice: authored";
    w.run({key("z", mods::ctrl | mods::shift)});
    const ecs::Entity again = w.only_lattice();
    ASSERT_TRUE(w.reg.valid(again));
    EXPECT_NE(again, added) << "the registry gives the index back with a new generation";
    EXPECT_EQ(w.state->undo.resolve(added), again);
    EXPECT_EQ(w.reg.get<Deformers>(w.cloud).lattices, std::vector<ecs::Entity>{again});
    EXPECT_EQ(w.state->active_lattice, again);
    EXPECT_EQ(w.reg.get<Name>(again).value, name);
    EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(again).current, lattice.current));
    EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(again).rest, lattice.rest));
    EXPECT_TRUE(bit_equal(w.deformed(), deformed));
}

// Deleting a lattice that deforms a cloud and plays a clip (paused mid-way, with a selection and an
// edit made before): undo brings the entity back with its clip, selection and shape, the cloud follows it
// again and deforms bit for bit as before; redo deletes it again; a second undo still finds it, and the
// edit made before the deletion undoes on the re-created entity.
TEST(LatticeLife, DeleteOfAnAnimatedBoundLatticeUndoesToTheSameDeformation) {
    World w;
    attach_paused_clip(w.reg, w.lattice);
    w.run();
    w.run({key("a")});  // select all (one step)
    w.state->pin_outer_layer = false;
    w.run(typed({"g", "x", "0", "period", "1", "enter"}));  // an un-keyed edit at 0.5 s (one step)
    ASSERT_TRUE(w.reg.has<UnkeyedEdit>(w.lattice));
    const std::vector<glm::vec3> before = w.deformed();
    const Lattice shape = w.reg.get<Lattice>(w.lattice);
    const AnimationClip clip = w.reg.get<AnimationClip>(w.lattice);
    const std::size_t selected = w.reg.get<picking::LatticeSelection>(w.lattice).indices.size();
    ASSERT_EQ(selected, shape.size());
    const std::size_t alive = w.reg.alive();

    w.run({key("delete")});
    EXPECT_FALSE(w.reg.valid(w.lattice));
    EXPECT_EQ(w.reg.alive(), alive - 1);
    EXPECT_TRUE(w.reg.get<Deformers>(w.cloud).lattices.empty());
    EXPECT_FALSE(bit_equal(w.deformed(), before));

    for (int pass = 0; pass < 2; ++pass) {
        w.run({key("z", mods::ctrl)});
        const ecs::Entity back = w.only_lattice();
        ASSERT_TRUE(w.reg.valid(back)) << "pass " << pass;
        EXPECT_EQ(w.state->undo.resolve(w.lattice), back);
        EXPECT_EQ(w.reg.get<Deformers>(w.cloud).lattices, std::vector<ecs::Entity>{back});
        EXPECT_EQ(w.state->active_lattice, back);
        EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(back).current, shape.current));
        EXPECT_EQ(w.reg.get<AnimationClip>(back).tracks.size(), clip.tracks.size());
        EXPECT_EQ(w.reg.get<AnimationClip>(back).tracks[0].keys.size(), clip.tracks[0].keys.size());
        EXPECT_FALSE(w.reg.get<AnimationState>(back).playing);
        EXPECT_EQ(w.reg.get<picking::LatticeSelection>(back).indices.size(), selected);
        ASSERT_TRUE(w.reg.has<UnkeyedEdit>(back));
        EXPECT_TRUE(bit_equal(w.deformed(), before))
            << "the same deformation, bit for bit (pass " << pass << ")";
        if (pass == 0) {
            w.run({key("z", mods::ctrl | mods::shift)});  // redo: deleted again
            EXPECT_EQ(w.only_lattice(), ecs::null_entity);
            EXPECT_TRUE(w.reg.get<Deformers>(w.cloud).lattices.empty());
        }
    }
    // The edit made before the deletion names the old id: it undoes on the re-created lattice.
    const ecs::Entity back = w.only_lattice();
    w.run({key("z", mods::ctrl)});
    EXPECT_FALSE(w.reg.has<UnkeyedEdit>(back));
    const std::vector<glm::dvec3> clip_pose =
        evaluate_pose(w.reg.get<AnimationClip>(back), w.reg.get<Lattice>(back), 0.5);
    EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(back).current, clip_pose)) << "the clip's pose at 0.5 s";
}

// --- one writer of the pose ------------------------------------------------------------------------

// A drag on an animated lattice writes its un-keyed edit, never Lattice::current: in the frame of the
// edit the animation phase shows it. Editing while the clip plays pauses it at the frame shown.
TEST(AnimationOwnsThePose, AnEditWhilePlayingPausesAndIsAnUnkeyedEditAtThatTime) {
    World w;
    attach_paused_clip(w.reg, w.lattice);
    play(w.reg.patch<AnimationState>(w.lattice));
    for (int f = 0; f < 6; ++f) w.run();
    const double shown = w.reg.get<AnimationState>(w.lattice).time;
    ASSERT_GT(shown, 0.5);
    w.run({key("a")});
    const double at = w.reg.get<AnimationState>(w.lattice).time;
    const std::vector<glm::dvec3> pose = w.reg.get<Lattice>(w.lattice).current;
    w.state->pin_outer_layer = false;
    // The input phase alone: the typed move writes the un-keyed edit and leaves current to the animation.
    const std::uint64_t stamp = w.reg.version<Lattice>(w.lattice);
    w.state->events = typed({"g", "y", "0", "period", "2", "5", "enter"});
    editor_input_system(w.reg, FrameContext{w.frame, w.frame / 60.0, 1 / 60.0});
    EXPECT_EQ(w.reg.version<Lattice>(w.lattice), stamp) << "the editor wrote Lattice::current";
    EXPECT_FALSE(w.reg.get<AnimationState>(w.lattice).playing) << "editing paused the clip";
    ASSERT_TRUE(w.reg.has<UnkeyedEdit>(w.lattice));
    EXPECT_EQ(w.reg.get<UnkeyedEdit>(w.lattice).time, at);
    animation_system(w.reg, FrameContext{w.frame, w.frame / 60.0, 1 / 60.0});
    ++w.frame;
    const std::vector<glm::dvec3>& edited = w.reg.get<Lattice>(w.lattice).current;
    for (std::size_t i = 0; i < edited.size(); ++i)
        EXPECT_EQ(edited[i], pose[i] + glm::dvec3(0, 0.25, 0)) << i;
    for (int f = 0; f < 3; ++f) w.run();  // paused: the edit stays on screen
    EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(w.lattice).current, w.reg.get<UnkeyedEdit>(w.lattice).points));
    // Undo gives the time back to the clip.
    w.run({key("z", mods::ctrl)});
    EXPECT_FALSE(w.reg.has<UnkeyedEdit>(w.lattice));
    EXPECT_TRUE(bit_equal(w.reg.get<Lattice>(w.lattice).current, pose));
}

// With auto-key on, the same edit is keyed at the paused time: the clip's pose there is the edit.
TEST(AnimationOwnsThePose, AutoKeyKeysTheEditAndTheClipShowsIt) {
    World w;
    attach_paused_clip(w.reg, w.lattice);
    w.run();
    w.run({key("a"), key("n")});
    w.state->pin_outer_layer = false;
    const std::vector<glm::dvec3> pose = w.reg.get<Lattice>(w.lattice).current;
    w.run(typed({"g", "y", "0", "period", "2", "5", "enter"}));
    EXPECT_FALSE(w.reg.has<UnkeyedEdit>(w.lattice)) << "keyed, not held";
    const AnimationClip& clip = w.reg.get<AnimationClip>(w.lattice);
    ASSERT_EQ(clip.tracks.size(), 2u);
    EXPECT_EQ(clip.tracks[1].keys.size(), 1u);
    const std::vector<glm::dvec3>& now = w.reg.get<Lattice>(w.lattice).current;
    for (std::size_t i = 0; i < now.size(); ++i)
        EXPECT_NEAR(glm::length(now[i] - pose[i] - glm::dvec3(0, 0.25, 0)), 0.0, 1e-12) << i;
}

// --- a step holds what it changed ------------------------------------------------------------------

// Through the editor's own path (selection, typed move, the input system's undo step): 8 control points of
// an 11³ lattice over a 1M-point cloud, with and without a clip on the lattice.
TEST(UndoMemory, MovingEightControlPointsThroughTheEditorIsUnderOneKilobyte) {
    for (const bool animated : {false, true}) {
        ecs::Registry reg;
        const ecs::Entity lattice = reg.create();
        reg.emplace<Lattice>(
            lattice,
            make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                         {10, 10, 10}));
        const ecs::Entity cloud = reg.create();
        reg.emplace<SplatCloud>(cloud).positions.assign(1'000'000, glm::vec3(0.25f));
        reg.emplace<Deformers>(cloud, Deformers{{lattice}});
        Camera& cam = reg.emplace<Camera>(reg.create());
        cam.eye = {0.0, 0.0, 6.0};
        EditorState& state = setup_editor(reg, Viewport{800, 600});
        if (animated) {
            attach_paused_clip(reg, lattice);
            animation_system(reg, FrameContext{0, 0.0, 1 / 60.0});
        }
        const Lattice& l = reg.get<Lattice>(lattice);
        reg.emplace<picking::LatticeSelection>(lattice).indices = {
            std::uint32_t(l.index(2, 2, 2)), std::uint32_t(l.index(2, 3, 2)), std::uint32_t(l.index(3, 2, 2)),
            std::uint32_t(l.index(3, 3, 2)), std::uint32_t(l.index(2, 2, 3)), std::uint32_t(l.index(2, 3, 3)),
            std::uint32_t(l.index(3, 2, 3)), std::uint32_t(l.index(3, 3, 3))};
        state.active_lattice = lattice;
        const std::size_t empty = state.undo.bytes();
        state.events = typed({"g", "x", "0", "period", "1", "enter"});
        editor_input_system(reg, FrameContext{1, 1 / 60.0, 1 / 60.0});
        ASSERT_EQ(state.undo.size(), 1u) << (animated ? "animated" : "plain");
        const std::size_t step = state.undo.bytes() - empty;
        RecordProperty(animated ? "animated_step_bytes" : "step_bytes", int(step));
        EXPECT_LT(step, 1024u) << (animated ? "animated" : "plain");
        EXPECT_GT(step, 8u * 2u * sizeof(glm::dvec3)) << "the 8 points before and after";
        // And it undoes and redoes exactly.
        animation_system(reg, FrameContext{1, 1 / 60.0, 1 / 60.0});
        const std::vector<glm::dvec3> edited = reg.get<Lattice>(lattice).current;
        undo(reg, state);
        animation_system(reg, FrameContext{2, 2 / 60.0, 1 / 60.0});
        EXPECT_FALSE(bit_equal(reg.get<Lattice>(lattice).current, edited));
        redo(reg, state);
        animation_system(reg, FrameContext{3, 3 / 60.0, 1 / 60.0});
        EXPECT_TRUE(bit_equal(reg.get<Lattice>(lattice).current, edited));
    }
}
