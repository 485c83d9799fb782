#include "runtime/scene/point_columns.h"

#include <algorithm>

namespace sffd {

namespace {

// Entry I of `table` over `v`, checked at compile time against the member's type; `values` per point.
// Empty when v does not hold exactly `points` * values entries.
template <const auto& table, std::size_t I, class T>
ColumnRef ref_of(const std::vector<T>& v, std::size_t points, std::size_t values = 1) {
    static_assert(column_type_of<T>::value == table[I].type, "the table's type is not the member's");
    ColumnRef r;
    r.spec = &table[I];
    r.values = values;
    if (points == 0 || values == 0 || v.size() != points * values) return r;
    r.data = reinterpret_cast<const std::byte*>(v.data());
    r.count = points;
    r.stride = std::ptrdiff_t(values * sizeof(T));
    return r;
}

ColumnRef find(const std::vector<ColumnRef>& all, std::string_view name) {
    for (const ColumnRef& r : all)
        if (r.spec->name == name) return r;
    return {};
}

}  // namespace

std::string_view column_type_name(ColumnType type) {
    switch (type) {
        case ColumnType::u8: return "u8";
        case ColumnType::rgba8: return "rgba8";
        case ColumnType::f32: return "f32";
        case ColumnType::vec2: return "vec2";
        case ColumnType::vec3: return "vec3";
        case ColumnType::vec4: return "vec4";
        case ColumnType::quat: return "quat";
    }
    return "?";
}

std::size_t column_type_bytes(ColumnType type) {
    switch (type) {
        case ColumnType::u8: return 1;
        case ColumnType::rgba8:
        case ColumnType::f32: return 4;
        case ColumnType::vec2: return 8;
        case ColumnType::vec3: return 12;
        case ColumnType::vec4:
        case ColumnType::quat: return 16;
    }
    return 0;
}

std::vector<ColumnRef> point_columns(const SplatCloud& c) {
    const std::size_t n = c.size();
    static_assert(std::size(kSurfaceColumns) == 7, "a new surface column needs its member here");
    return {ref_of<kSurfaceColumns, 0>(c.positions, n), ref_of<kSurfaceColumns, 1>(c.normals, n),
            ref_of<kSurfaceColumns, 2>(c.axis_u, n),    ref_of<kSurfaceColumns, 3>(c.axis_v, n),
            ref_of<kSurfaceColumns, 4>(c.colors, n),    ref_of<kSurfaceColumns, 5>(c.uvs, n),
            ref_of<kSurfaceColumns, 6>(c.uv_axes, n)};
}

std::vector<ColumnRef> point_columns(const GaussianCloud& g) {
    const std::size_t n = g.size();
    static_assert(std::size(kGaussianColumns) == 5, "a new Gaussian column needs its member here");
    const std::size_t sh_values =
        g.sh_degree >= 0 && g.sh_degree <= 3 ? 3 * std::size_t(sh_coeffs(g.sh_degree)) : 0;
    return {ref_of<kGaussianColumns, 0>(g.positions, n), ref_of<kGaussianColumns, 1>(g.scales, n),
            ref_of<kGaussianColumns, 2>(g.rotations, n), ref_of<kGaussianColumns, 3>(g.opacities, n),
            ref_of<kGaussianColumns, 4>(g.sh, n, sh_values)};
}

std::vector<ColumnRef> point_columns(const ecs::Registry& r, ecs::Entity e) {
    std::vector<ColumnRef> all;
    std::size_t n = 0;
    if (!r.valid(e)) return all;
    if (const SplatCloud* c = r.try_get<SplatCloud>(e)) all = point_columns(*c), n = c->size();
    else if (const GaussianCloud* g = r.try_get<GaussianCloud>(e)) all = point_columns(*g), n = g->size();
    else return all;
    static_assert(std::size(kOptionalColumns) == 2, "a new optional column needs its component here");
    static const std::vector<std::uint8_t> no_bits;
    static const std::vector<float> no_values;
    const PointFlags* f = r.try_get<PointFlags>(e);
    const PointWeights* w = r.try_get<PointWeights>(e);
    all.push_back(ref_of<kOptionalColumns, 0>(f ? f->bits : no_bits, n));
    all.push_back(ref_of<kOptionalColumns, 1>(w ? w->values : no_values, n));
    return all;
}

ColumnRef column_ref(const SplatCloud& cloud, std::string_view name) {
    return find(point_columns(cloud), name);
}
ColumnRef column_ref(const GaussianCloud& cloud, std::string_view name) {
    return find(point_columns(cloud), name);
}
ColumnRef column_ref(const ecs::Registry& registry, ecs::Entity e, std::string_view name) {
    return find(point_columns(registry, e), name);
}

}  // namespace sffd
