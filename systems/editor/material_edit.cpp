#include "systems/editor/material_edit.h"

#include <algorithm>
#include <array>
#include <memory>

#include "systems/editor/editor_state.h"

namespace sffd::editor {

namespace {

constexpr std::array<MaterialFieldInfo, 6> fields = {{
    {MaterialField::specular, "material.specular", "specular", "material specular", 0.0f, 1.0f},
    {MaterialField::shininess, "material.shininess", "shininess", "material shininess", 1.0f, 256.0f},
    {MaterialField::base_r, "material.base_color.r", "base colour", "material colour", 0.0f, 1.0f},
    {MaterialField::base_g, "material.base_color.g", "base colour", "material colour", 0.0f, 1.0f},
    {MaterialField::base_b, "material.base_color.b", "base colour", "material colour", 0.0f, 1.0f},
    {MaterialField::base_a, "material.base_color.a", "base colour", "material colour", 0.0f, 1.0f},
}};

}  // namespace

std::optional<MaterialFieldInfo> material_field(std::string_view name) {
    for (const MaterialFieldInfo& f : fields)
        if (f.name == name) return f;
    return std::nullopt;
}

const MaterialFieldInfo& material_field_info(MaterialField field) {
    return fields[static_cast<std::size_t>(field)];
}

std::string_view material_field_names() {
    return "material.specular, material.shininess, material.base_color.r, material.base_color.g, "
           "material.base_color.b, material.base_color.a";
}

float& material_value(SplatMaterial& material, MaterialField field) {
    switch (field) {
        case MaterialField::specular: return material.specular;
        case MaterialField::shininess: return material.shininess;
        case MaterialField::base_r: return material.base_color.x;
        case MaterialField::base_g: return material.base_color.y;
        case MaterialField::base_b: return material.base_color.z;
        case MaterialField::base_a: return material.base_color.w;
    }
    return material.specular;
}

ecs::Entity material_target(const ecs::Registry& registry, const EditorState& state) {
    if (registry.valid(state.selected_entity) && registry.has<SplatMaterial>(state.selected_entity))
        return state.selected_entity;
    ecs::Entity found = ecs::null_entity;
    registry.each_entity([&](ecs::Entity e) {
        if (found == ecs::null_entity && registry.has<SplatMaterial>(e)) found = e;
    });
    return found;
}

bool set_material_value(ecs::Registry& registry, EditorState& state, ecs::Entity e, MaterialField field,
                        float value) {
    if (!registry.valid(e) || !registry.has<SplatMaterial>(e)) return false;
    const MaterialFieldInfo& info = material_field_info(field);
    const SplatMaterial before = registry.get<SplatMaterial>(e);
    SplatMaterial& m = registry.patch<SplatMaterial>(e);
    material_value(m, field) = std::clamp(value, info.min, info.max);
    state.undo.push(std::make_unique<ComponentChange<SplatMaterial>>(info.label, e, before, m));
    return true;
}

}  // namespace sffd::editor
