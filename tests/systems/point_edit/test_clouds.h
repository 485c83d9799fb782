// Clouds with every column filled with distinct values (index-derived), so a copied point can be told from
// every other point, for the point operation tests.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"

namespace sffd::point_edit::test {

inline float value(std::size_t i, int k) { return float(i) * 0.001f + float(k) * 0.25f; }

inline SplatCloud surface_cloud(std::size_t n) {
    SplatCloud c;
    c.origin = {10.0, -5.0, 2.5};
    for (std::size_t i = 0; i < n; ++i) {
        c.positions.emplace_back(value(i, 0), value(i, 1), value(i, 2));
        c.normals.emplace_back(0.0f, 0.0f, 1.0f + value(i, 3));
        c.axis_u.emplace_back(value(i, 4), 0.0f, 0.0f);
        c.axis_v.emplace_back(0.0f, value(i, 5), 0.0f);
        c.colors.push_back(std::uint32_t(i * 2654435761u));
        c.uvs.emplace_back(value(i, 6), value(i, 7));
        c.uv_axes.emplace_back(value(i, 8), value(i, 9), value(i, 10), value(i, 11));
    }
    c.texture.path = "tex.png";
    c.texture.width = 2, c.texture.height = 1;
    c.texture.rgba8 = {1, 2, 3, 4, 5, 6, 7, 8};
    return c;
}

inline GaussianCloud gaussian_cloud(std::size_t n, int degree) {
    GaussianCloud c;
    c.origin = {-3.0, 1.0, 0.5};
    c.sh_degree = degree;
    const std::size_t k = std::size_t(sh_coeffs(degree)) * 3;
    for (std::size_t i = 0; i < n; ++i) {
        c.positions.emplace_back(value(i, 0), value(i, 1), value(i, 2));
        c.scales.emplace_back(value(i, 3), value(i, 4), value(i, 5));
        c.rotations.emplace_back(1.0f, value(i, 6), 0.0f, 0.0f);
        c.opacities.push_back(value(i, 7));
        for (std::size_t j = 0; j < k; ++j) c.sh.push_back(value(i, 8 + int(j)));
    }
    return c;
}

// Flags with random selected/hidden/deleted bits (fixed seed), p_select of the points selected.
inline std::vector<std::uint8_t> random_flags(std::size_t n, double p_select, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<std::uint8_t> bits(n, 0);
    for (auto& b : bits) {
        if (u(rng) < p_select) b |= kPointSelected;
        if (u(rng) < 0.1) b |= kPointHidden;
        if (u(rng) < 0.05) b |= kPointDeleted;
    }
    return bits;
}

// An entity with the cloud, flags, weights, Transform, SplatMaterial, Name and Deformers (a dummy lattice
// id: the part must not inherit it).
template <class Cloud>
ecs::Entity add_cloud(ecs::Registry& reg, Cloud cloud, std::vector<std::uint8_t> bits) {
    const ecs::Entity e = reg.create();
    const std::size_t n = cloud.size();
    reg.emplace<Cloud>(e, std::move(cloud));
    reg.emplace<PointFlags>(e, PointFlags{std::move(bits)});
    PointWeights w;
    for (std::size_t i = 0; i < n; ++i) w.values.push_back(float(i % 97) / 96.0f);
    reg.emplace<PointWeights>(e, std::move(w));
    Transform t;
    t.translation = {1.0, 2.0, 3.0};
    t.scale = glm::dvec3(2.0);
    reg.emplace<Transform>(e, t);
    SplatMaterial m;
    m.base_color = {0.1f, 0.2f, 0.3f, 1.0f};
    m.specular = 0.7f;
    reg.emplace<SplatMaterial>(e, m);
    reg.emplace<Name>(e, Name{"scan"});
    reg.emplace<Deformers>(e, Deformers{{reg.create()}});
    return e;
}

}  // namespace sffd::point_edit::test
