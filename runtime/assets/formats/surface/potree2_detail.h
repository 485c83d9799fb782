// What the Potree 2 writer and reader share (internal): the point record the builder sorts, the attribute
// layout we write, and the encoding of one point into octree.bin's bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "runtime/assets/formats/surface/potree2.h"

namespace sffd::assets::potree2_detail {

// One splat while the octree is built (a lod/cell_buckets.h record: the double position first).
struct Rec {
    double p[3];   // world position
    float n[3];    // normal
    float u[3];    // axis_u
    float v[3];    // axis_v
    float radius;  // sffd_lod_radius: its own radius at a leaf, grown when it represents others
    std::uint32_t color;
    float uv[2];
    float uva[4];
};

// Our attributes in file order, and what the file declares for each.
struct AttributeSpec {
    const char* name;
    PotreeType type;
    int elements;
};
inline constexpr AttributeSpec kPosition{"position", PotreeType::int32, 3};
inline constexpr AttributeSpec kRgb{"rgb", PotreeType::uint16, 3};
inline constexpr AttributeSpec kAlpha{"alpha", PotreeType::uint8, 1};
inline constexpr AttributeSpec kNormal{"normal", PotreeType::float32, 3};
inline constexpr AttributeSpec kAxisU{"sffd_axis_u", PotreeType::float32, 3};
inline constexpr AttributeSpec kAxisV{"sffd_axis_v", PotreeType::float32, 3};
inline constexpr AttributeSpec kLodRadius{"sffd_lod_radius", PotreeType::float32, 1};
inline constexpr AttributeSpec kUv{"sffd_uv", PotreeType::float32, 2};
inline constexpr AttributeSpec kUvAxes{"sffd_uv_axes", PotreeType::float32, 4};

std::uint32_t type_bytes(PotreeType t);
const char* type_name(PotreeType t);
bool parse_type(const std::string& name, PotreeType& out);

struct Layout {
    glm::dvec3 offset{0.0}, scale{1.0};
    bool colors = false, alpha = false, uvs = false, uv_axes = false;
    std::vector<PotreeAttribute> attributes;  // filled by finish_layout
    std::uint32_t point_bytes = 0;
};
void finish_layout(Layout& layout);

// Per attribute and element, the range of what was written (metadata.json's min and max).
struct Bounds {
    double lo[32], hi[32];
    Bounds();
};

// One point into layout.point_bytes bytes at `out`, its values added to `bounds`.
void encode(const Rec& r, const Layout& layout, std::uint8_t* out, Bounds& bounds);

nlohmann::ordered_json attributes_json(const Layout& layout, const Bounds& bounds);

}  // namespace sffd::assets::potree2_detail
