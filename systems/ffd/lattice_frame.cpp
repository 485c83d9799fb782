#include "systems/ffd/lattice_frame.h"

#include "runtime/scene/camera.h"

namespace sffd::ffd {

namespace {

bool same_transform(const Transform* a, const Transform* b) {
    const Transform identity;
    const Transform& x = a ? *a : identity;
    const Transform& y = b ? *b : identity;
    return x.translation == y.translation && x.rotation == y.rotation && x.scale == y.scale;
}

}  // namespace

glm::dmat4 lattice_to_cloud(const ecs::Registry& registry, ecs::Entity cloud, ecs::Entity lattice) {
    const Transform* tc = registry.valid(cloud) ? registry.try_get<Transform>(cloud) : nullptr;
    const Transform* tl = registry.valid(lattice) ? registry.try_get<Transform>(lattice) : nullptr;
    if (same_transform(tc, tl)) return glm::dmat4(1.0);
    return glm::inverse(model_matrix(tc)) * model_matrix(tl);
}

Lattice map_lattice(const Lattice& l, const glm::dmat4& m) {
    Lattice out = l;
    const glm::dmat3 linear(m);
    auto point = [&](const glm::dvec3& p) { return glm::dvec3(m * glm::dvec4(p, 1.0)); };
    out.origin = point(l.origin);
    for (int a = 0; a < 3; ++a) out.axes[std::size_t(a)] = linear * l.axes[std::size_t(a)];
    for (glm::dvec3& p : out.rest) p = point(p);
    // The same arithmetic on equal inputs gives equal outputs: a still point stays equal to its rest.
    for (glm::dvec3& p : out.current) p = point(p);
    return out;
}

CloudLattices cloud_lattices(const ecs::Registry& registry, ecs::Entity cloud,
                             std::span<const ecs::Entity> lattices) {
    CloudLattices out;
    for (const ecs::Entity le : lattices) {
        const Lattice* l = registry.valid(le) ? registry.try_get<Lattice>(le) : nullptr;
        if (!l) continue;
        const glm::dmat4 m = lattice_to_cloud(registry, cloud, le);
        out.entities.push_back(le);
        if (m == glm::dmat4(1.0)) {
            out.lattices.push_back(l);
            continue;
        }
        out.mapped.push_back(map_lattice(*l, m));
        out.lattices.push_back(&out.mapped.back());
    }
    return out;
}

Box world_box(const Box& box, const glm::dmat4& model) {
    if (box.empty) return box;
    Box out;
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 p((c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                           (c & 4) ? box.hi.z : box.lo.z);
        out.add(glm::dvec3(model * glm::dvec4(p, 1.0)));
    }
    return out;
}

}  // namespace sffd::ffd
