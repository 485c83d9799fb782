// The attribute layout of the Potree 2 octrees we write and the encoding of one point (potree2_detail.h).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/assets/formats/surface/potree2_detail.h"

namespace sffd::assets::potree2_detail {

std::uint32_t type_bytes(PotreeType t) {
    switch (t) {
        case PotreeType::int8:
        case PotreeType::uint8: return 1;
        case PotreeType::int16:
        case PotreeType::uint16: return 2;
        case PotreeType::int32:
        case PotreeType::uint32:
        case PotreeType::float32: return 4;
        case PotreeType::int64:
        case PotreeType::uint64:
        case PotreeType::float64: return 8;
    }
    return 0;
}

namespace {
constexpr struct {
    PotreeType type;
    const char* name;
} kTypes[] = {{PotreeType::int8, "int8"},     {PotreeType::uint8, "uint8"},   {PotreeType::int16, "int16"},
              {PotreeType::uint16, "uint16"}, {PotreeType::int32, "int32"},   {PotreeType::uint32, "uint32"},
              {PotreeType::int64, "int64"},   {PotreeType::uint64, "uint64"}, {PotreeType::float32, "float"},
              {PotreeType::float64, "double"}};

// The first slot in Bounds of each of our attributes, in file order.
constexpr int kSlotRgb = 3, kSlotAlpha = 6, kSlotNormal = 7, kSlotU = 10, kSlotV = 13, kSlotLod = 16,
              kSlotUv = 17, kSlotUva = 19, kSlots = 23;
}  // namespace

const char* type_name(PotreeType t) {
    for (const auto& e : kTypes)
        if (e.type == t) return e.name;
    return "?";
}

bool parse_type(const std::string& name, PotreeType& out) {
    for (const auto& e : kTypes)
        if (name == e.name) return out = e.type, true;
    return false;
}

void finish_layout(Layout& l) {
    l.attributes.clear();
    std::uint32_t at = 0;
    const auto add = [&](const AttributeSpec& s) {
        PotreeAttribute a;
        a.name = s.name, a.type = s.type, a.elements = s.elements;
        a.bytes = type_bytes(s.type) * std::uint32_t(s.elements);
        a.offset = at;
        at += a.bytes;
        l.attributes.push_back(a);
    };
    add(kPosition);
    if (l.colors) add(kRgb);
    if (l.colors && l.alpha) add(kAlpha);
    add(kNormal);
    add(kAxisU);
    add(kAxisV);
    add(kLodRadius);
    if (l.uvs) add(kUv);
    if (l.uvs && l.uv_axes) add(kUvAxes);
    l.point_bytes = at;
}

Bounds::Bounds() {
    std::fill(std::begin(lo), std::end(lo), std::numeric_limits<double>::infinity());
    std::fill(std::begin(hi), std::end(hi), -std::numeric_limits<double>::infinity());
}

namespace {
void note(Bounds& b, int slot, double v) {
    b.lo[slot] = std::min(b.lo[slot], v);
    b.hi[slot] = std::max(b.hi[slot], v);
}
template <class T>
void put(std::uint8_t*& out, T v) {
    std::memcpy(out, &v, sizeof v);
    out += sizeof v;
}
}  // namespace

void encode(const Rec& r, const Layout& l, std::uint8_t* out, Bounds& b) {
    for (int a = 0; a < 3; ++a) {
        const double q = std::nearbyint((r.p[a] - l.offset[a]) / l.scale[a]);
        const std::int32_t v = std::int32_t(std::clamp(q, -2147483648.0, 2147483647.0));
        put(out, v);
        note(b, a, double(v) * l.scale[a] + l.offset[a]);
    }
    if (l.colors) {
        for (int c = 0; c < 3; ++c) {
            const std::uint16_t v = std::uint16_t(((r.color >> (8 * c)) & 0xffu) * 257u);
            put(out, v);
            note(b, kSlotRgb + c, v);
        }
        if (l.alpha) {
            put(out, std::uint8_t(r.color >> 24));
            note(b, kSlotAlpha, double(r.color >> 24));
        }
    }
    const auto floats = [&](const float* f, int n, int slot) {
        for (int i = 0; i < n; ++i) put(out, f[i]), note(b, slot + i, double(f[i]));
    };
    floats(r.n, 3, kSlotNormal);
    floats(r.u, 3, kSlotU);
    floats(r.v, 3, kSlotV);
    floats(&r.radius, 1, kSlotLod);
    if (l.uvs) floats(r.uv, 2, kSlotUv);
    if (l.uvs && l.uv_axes) floats(r.uva, 4, kSlotUva);
}

nlohmann::ordered_json attributes_json(const Layout& l, const Bounds& b) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    const auto slot_of = [](const std::string& name) {
        if (name == kRgb.name) return kSlotRgb;
        if (name == kAlpha.name) return kSlotAlpha;
        if (name == kNormal.name) return kSlotNormal;
        if (name == kAxisU.name) return kSlotU;
        if (name == kAxisV.name) return kSlotV;
        if (name == kLodRadius.name) return kSlotLod;
        if (name == kUv.name) return kSlotUv;
        if (name == kUvAxes.name) return kSlotUva;
        return 0;
    };
    static_assert(kSlots <= 32);
    for (const PotreeAttribute& a : l.attributes) {
        nlohmann::ordered_json j;
        j["name"] = a.name;
        j["description"] = "";
        j["size"] = a.bytes;
        j["numElements"] = a.elements;
        j["elementSize"] = type_bytes(a.type);
        j["type"] = type_name(a.type);
        nlohmann::ordered_json mn = nlohmann::ordered_json::array(), mx = nlohmann::ordered_json::array();
        const int s = slot_of(a.name);
        for (int e = 0; e < a.elements; ++e) {
            const bool seen = b.lo[s + e] <= b.hi[s + e];
            mn.push_back(seen ? b.lo[s + e] : 0.0);
            mx.push_back(seen ? b.hi[s + e] : 0.0);
        }
        j["min"] = std::move(mn);
        j["max"] = std::move(mx);
        if (a.name == kPosition.name) {
            j["scale"] = {l.scale.x, l.scale.y, l.scale.z};
            j["offset"] = {l.offset.x, l.offset.y, l.offset.z};
        }
        list.push_back(std::move(j));
    }
    return list;
}

}  // namespace sffd::assets::potree2_detail
