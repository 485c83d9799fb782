// Material edits of a splat cloud: the inspector's sliders (panels.cpp) and a replay's
// `<frame> set material.<field> <value>` lines (input_record.h) both go through this table of fields and
// ranges, and both record one undo step that holds the SplatMaterial before and after (a few bytes: the
// material is its own component, so the cloud is neither copied nor re-deformed, re-uploaded or re-picked).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"

namespace sffd::editor {

struct EditorState;

enum class MaterialField : std::uint8_t { specular, shininess, base_r, base_g, base_b, base_a };

struct MaterialFieldInfo {
    MaterialField field;
    std::string_view name;  // as written in a replay: "material.specular"
    const char* widget;     // the inspector's slider
    const char* label;      // the undo step's label
    float min, max;         // the slider's range (values outside are clamped, as the slider does)
};

// The field called `name` ("material.specular", "material.shininess", "material.base_color.r" ... ".a").
std::optional<MaterialFieldInfo> material_field(std::string_view name);
const MaterialFieldInfo& material_field_info(MaterialField field);
// The names material_field() knows, comma separated (for error messages).
std::string_view material_field_names();

float& material_value(SplatMaterial& material, MaterialField field);

// The cloud a replayed material edit applies to: the inspector's entity when it has a SplatMaterial, else
// the first entity that has one; null when there is none.
ecs::Entity material_target(const ecs::Registry& registry, const EditorState& state);

// One whole slider gesture on `field` of e's SplatMaterial: writes `value` (clamped to the slider's range),
// marks the component changed, and pushes one undo step (the material before and after). False, with
// nothing changed, when e has no SplatMaterial.
bool set_material_value(ecs::Registry& registry, EditorState& state, ecs::Entity e, MaterialField field,
                        float value);

}  // namespace sffd::editor
