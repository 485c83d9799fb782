#include "systems/editor/tool_widgets.h"

#include <imgui.h>

namespace sffd::editor {

void proportional_widgets(EditorState& state) {
    ProportionalSettings& p = state.proportional;
    ImGui::Checkbox("proportional (O)", &p.enabled);
    int falloff = int(p.falloff);
    if (ImGui::Combo("falloff (shift+O)", &falloff, "smooth\0sphere\0linear\0sharp\0constant\0"))
        p.falloff = Falloff(falloff);
    double radius = p.radius;
    if (ImGui::InputDouble("radius (wheel)", &radius, 0.05, 0.5, "%.4f"))
        p.radius = clamp_proportional_radius(radius);
}

}  // namespace sffd::editor
