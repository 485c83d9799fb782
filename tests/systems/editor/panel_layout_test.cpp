// The editor's panel layout (panel_layout.h) at many window sizes, and the panels ImGui really draws
// (draw_panels in a headless ImGui context: no window, no GL): no two overlap, all lie inside the
// window, collapsing a panel gives its height to its column, the collapsed state survives ImGui's ini
// (what `splatffd view` keeps in $XDG_CONFIG_HOME/splatffd/imgui.ini); the frame-time graph's scale.
#include "systems/editor/panel_layout.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <imgui.h>

#include "runtime/scene/components.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/panels.h"
#include "systems/ffd/components.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

void expect_fits(const std::vector<std::pair<std::string, PanelRect>>& rects, float w, float h) {
    for (std::size_t i = 0; i < rects.size(); ++i) {
        const PanelRect& r = rects[i].second;
        EXPECT_GE(r.x, 0.0f) << rects[i].first << " at " << w << "x" << h;
        EXPECT_GE(r.y, 0.0f) << rects[i].first << " at " << w << "x" << h;
        EXPECT_LE(r.x + r.w, w) << rects[i].first << " at " << w << "x" << h;
        EXPECT_LE(r.y + r.h, h) << rects[i].first << " at " << w << "x" << h;
        EXPECT_GT(r.w, 0.0f) << rects[i].first;
        EXPECT_GT(r.h, 0.0f) << rects[i].first;
        for (std::size_t j = i + 1; j < rects.size(); ++j)
            EXPECT_FALSE(overlaps(r, rects[j].second))
                << rects[i].first << " overlaps " << rects[j].first << " at " << w << "x" << h;
    }
}

std::vector<std::pair<std::string, PanelRect>> named(const std::array<PanelRect, panel_count>& a,
                                                     const LayoutInput& in) {
    std::vector<std::pair<std::string, PanelRect>> out;
    for (std::size_t i = 0; i < panel_count; ++i) out.emplace_back(panel_title(Panel(i)), a[i]);
    out.emplace_back("menu", PanelRect{0, 0, in.width, in.top});
    out.emplace_back("status", PanelRect{0, in.height - in.bottom, in.width, in.bottom});
    return out;
}

}  // namespace

TEST(PanelLayout, NoOverlapInsideTheWindowAtAnySize) {
    const float sizes[][2] = {{1280, 720}, {1600, 900}, {1920, 1080}, {2560, 1440},
                              {1024, 768}, {800, 600},  {3840, 2160}};
    for (const auto& s : sizes)
        for (unsigned mask = 0; mask < (1u << panel_count); mask += 7) {  // a spread of collapsed states
            LayoutInput in;
            in.width = s[0], in.height = s[1];
            for (std::size_t i = 0; i < panel_count; ++i) in.collapsed[i] = (mask >> i) & 1u;
            expect_fits(named(layout_panels(in), in), in.width, in.height);
        }
}

TEST(PanelLayout, CollapsingGivesTheHeightToTheColumn) {
    LayoutInput in;
    const auto open = layout_panels(in);
    in.collapsed[std::size_t(Panel::outliner)] = true;
    const auto folded = layout_panels(in);
    EXPECT_FLOAT_EQ(folded[std::size_t(Panel::outliner)].h, in.title);
    EXPECT_GT(folded[std::size_t(Panel::inspector)].h, open[std::size_t(Panel::inspector)].h + 60.0f);
    EXPECT_GT(folded[std::size_t(Panel::frame_time)].h, open[std::size_t(Panel::frame_time)].h + 30.0f);
    // The column stays filled: what the Outliner gave up, the others took (up to rounding).
    const auto column = [](const std::array<PanelRect, panel_count>& r) {
        const PanelRect& last = r[std::size_t(Panel::frame_time)];
        return last.y + last.h - r[std::size_t(Panel::outliner)].y;
    };
    EXPECT_NEAR(column(folded), column(open), 3.0f);
    // The other column does not move.
    EXPECT_FLOAT_EQ(folded[std::size_t(Panel::lattice)].y, open[std::size_t(Panel::lattice)].y);
    // At 1280x720 the inspector has room for its material rows (the frame-time panel used to cover them).
    EXPECT_GE(open[std::size_t(Panel::inspector)].h, 300.0f);
    EXPECT_GE(open[std::size_t(Panel::frame_time)].h, 150.0f);
}

// The lattice overlay is clipped to the view rectangle: inside the window, below the menu, under no
// expanded panel; a column whose panels are all collapsed gives its width back.
TEST(PanelLayout, TheViewRectangleIsWhereNoPanelCovers) {
    for (const auto& s : {std::pair{1280.0f, 720.0f}, {800.0f, 600.0f}, {1920.0f, 1080.0f}})
        for (unsigned mask = 0; mask < (1u << panel_count); mask += 5) {
            LayoutInput in;
            in.width = s.first, in.height = s.second;
            for (std::size_t i = 0; i < panel_count; ++i) in.collapsed[i] = (mask >> i) & 1u;
            const auto panels = layout_panels(in);
            const PanelRect v = view_rect(panels, in);
            EXPECT_GE(v.x, 0.0f);
            EXPECT_GE(v.y, in.top);
            EXPECT_LE(v.x + v.w, in.width);
            EXPECT_LE(v.y + v.h, in.height - in.bottom);
            EXPECT_GT(v.w, 0.0f);
            EXPECT_GT(v.h, 0.0f);
            for (std::size_t i = 0; i < panel_count; ++i) {
                if (!in.collapsed[i] || Panel(i) == Panel::timeline) {
                    EXPECT_FALSE(overlaps(v, panels[i])) << panel_title(Panel(i)) << " mask " << mask;
                }
            }
        }
    LayoutInput in;
    const PanelRect open = view_rect(layout_panels(in), in);
    for (Panel p : {Panel::tools, Panel::lattice}) in.collapsed[std::size_t(p)] = true;
    const PanelRect right_folded = view_rect(layout_panels(in), in);
    EXPECT_FLOAT_EQ(right_folded.x, open.x);
    EXPECT_FLOAT_EQ(right_folded.x + right_folded.w, in.width);
    // Small windows start with their panels collapsed; the usual sizes do not.
    EXPECT_TRUE(panels_start_collapsed(800, 600));
    EXPECT_FALSE(panels_start_collapsed(1280, 720));
    EXPECT_FALSE(panels_start_collapsed(1920, 1080));
}

TEST(PanelLayout, GraphScaleIgnoresTheFirstSlowFrame) {
    std::vector<float> ms(120, 12.0f);
    ms[0] = 2400.0f;  // shader compilation
    ms[50] = 20.0f;
    const float scale = graph_scale(ms);
    EXPECT_GE(scale, 12.0f);
    EXPECT_LE(scale, 30.0f);
    EXPECT_FLOAT_EQ(graph_scale(std::vector<float>{}), 1.0f);
    EXPECT_FLOAT_EQ(graph_scale(std::vector<float>{0.1f, 0.2f}), 1.0f);
}

namespace {

struct HeadlessImGui {
    ImGuiContext* ctx;
    HeadlessImGui() {
        ctx = ImGui::CreateContext();
        ImGuiIO& io = ImGui::GetIO();
        io.IniFilename = nullptr;
        unsigned char* px = nullptr;
        int w = 0, h = 0;
        io.Fonts->GetTexDataAsRGBA32(&px, &w, &h);  // builds the atlas (NewFrame needs it; nothing is drawn)
    }
    ~HeadlessImGui() { ImGui::DestroyContext(ctx); }
    void frame(ecs::Registry& reg, float w, float h) {
        ImGuiIO& io = ImGui::GetIO();
        io.DisplaySize = ImVec2(w, h);
        io.DeltaTime = 1.0f / 60.0f;
        ImGui::NewFrame();
        draw_panels(reg, FrameContext{});
        ImGui::Render();
    }
};

void scene_with_lattice(ecs::Registry& reg) {
    const ecs::Entity l = reg.create();
    reg.emplace<Name>(l, Name{"lattice"});
    Lattice& lat = reg.emplace<Lattice>(l);
    lat.divisions = {1, 1, 1};
    lat.axes = {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};
    for (int i = 0; i < 8; ++i) lat.rest.push_back(glm::dvec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
    lat.current = lat.rest;
    const ecs::Entity c = reg.create();
    SplatCloud& cloud = reg.emplace<SplatCloud>(c);
    cloud.positions = {glm::vec3(0.5f), glm::vec3(0.25f)};
    cloud.normals = {glm::vec3(0, 0, 1), glm::vec3(0, 0, 1)};
    reg.emplace<SplatMaterial>(c);
    reg.emplace<Deformers>(c, Deformers{{l}});
    EditorState& s = setup_editor(reg, Viewport{1280, 720});
    s.selected_entity = c;  // the inspector shows the cloud's material rows
}

std::vector<std::pair<std::string, PanelRect>> drawn(const ecs::Registry& reg) {
    std::vector<std::pair<std::string, PanelRect>> out;
    for (const NamedPanelRect& p : panel_rects(reg)) out.emplace_back(p.name, p.rect);
    return out;
}

}  // namespace

TEST(PanelLayout, ImGuiDrawsThePanelsWhereTheLayoutSays) {
    ecs::Registry reg;
    scene_with_lattice(reg);
    HeadlessImGui imgui;
    for (const auto& s :
         {std::pair{1280.0f, 720.0f}, {1600.0f, 900.0f}, {1920.0f, 1080.0f}, {1024.0f, 640.0f}}) {
        for (int f = 0; f < 3; ++f) imgui.frame(reg, s.first, s.second);  // menu height settles after frame 1
        const auto rects = drawn(reg);
        ASSERT_EQ(rects.size(), panel_count + 2) << "menu, status and six panels";
        expect_fits(rects, s.first, s.second);
    }
}

TEST(PanelLayout, CollapsedPanelsAreRememberedThroughTheIniFile) {
    ecs::Registry reg;
    scene_with_lattice(reg);
    std::string ini;
    float inspector_open = 0, inspector_folded = 0;
    {
        HeadlessImGui imgui;
        for (int f = 0; f < 2; ++f) imgui.frame(reg, 1280, 720);
        for (const NamedPanelRect& p : panel_rects(reg))
            if (p.name == "Inspector") inspector_open = p.rect.h;
        ImGui::SetWindowCollapsed("Outliner", true);  // what a click on its title bar arrow does
        for (int f = 0; f < 2; ++f) imgui.frame(reg, 1280, 720);
        ini = ImGui::SaveIniSettingsToMemory();
    }
    EXPECT_NE(ini.find("[Window][Outliner]"), std::string::npos);
    {
        HeadlessImGui imgui;  // the next run
        ImGui::LoadIniSettingsFromMemory(ini.c_str(), ini.size());
        for (int f = 0; f < 2; ++f) imgui.frame(reg, 1280, 720);
        for (const NamedPanelRect& p : panel_rects(reg)) {
            if (p.name == "Outliner") {
                EXPECT_LE(p.rect.h, ImGui::GetFrameHeight() + 1.0f);
            }
            if (p.name == "Inspector") inspector_folded = p.rect.h;
        }
        expect_fits(drawn(reg), 1280, 720);
    }
    EXPECT_GT(inspector_folded, inspector_open + 60.0f);
}
