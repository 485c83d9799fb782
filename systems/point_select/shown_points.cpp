#include "systems/point_select/shown_points.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/splat_source.h"

namespace sffd::point_select {

PointSelectState::PointSelectState() : m_impl(std::make_unique<Impl>()) {}
PointSelectState::~PointSelectState() = default;
PointSelectState::PointSelectState(PointSelectState&&) noexcept = default;
PointSelectState& PointSelectState::operator=(PointSelectState&&) noexcept = default;
const PointSelectState::Stats& PointSelectState::stats() const { return m_impl->stats; }
PointSelectState::Impl& PointSelectState::impl() { return *m_impl; }

namespace detail {
namespace {

bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// What the radii are computed from (one of the three is used, in this order).
struct RadiusInputs {
    std::span<const glm::vec3> axis_u, axis_v;  // surface splats: the disc is the longer axis
    std::span<const glm::vec3> normals;         // surface splats
    std::span<const glm::vec3> scales;          // Gaussians: the largest standard deviation
    std::span<const glm::quat> rotations;       // Gaussians: the shortest axis of a flat one is its normal
    std::span<const glm::mat3> jacobians;       // Gaussians deformed by picking: J maps the axes
};

glm::vec3 unit_or_zero(const glm::vec3& v) {
    const float l = glm::length(v);
    return l > 0.0f && std::isfinite(l) ? v / l : glm::vec3(0.0f);
}

glm::vec3 normal_of(const RadiusInputs& in, std::size_t i) {
    if (!in.normals.empty()) return unit_or_zero(in.normals[i]);
    if (!in.axis_u.empty()) return unit_or_zero(glm::cross(in.axis_u[i], in.axis_v[i]));
    if (in.scales.empty() || in.rotations.empty()) return glm::vec3(0.0f);
    const glm::vec3 s = glm::abs(in.scales[i]);
    const int k = s.x <= s.y && s.x <= s.z ? 0 : (s.y <= s.z ? 1 : 2);
    if (!(s[k] < 0.5f * std::max({s.x, s.y, s.z}))) return glm::vec3(0.0f);  // round: faces the eye
    const glm::vec3 axis = glm::mat3_cast(in.rotations[i])[k];
    if (in.jacobians.empty()) return unit_or_zero(axis);
    const glm::mat3& j = in.jacobians[i];  // normals map by the inverse transpose
    return std::abs(glm::determinant(j)) > 1e-12f ? unit_or_zero(glm::transpose(glm::inverse(j)) * axis)
                                                  : glm::vec3(0.0f);
}

float radius_of(const RadiusInputs& in, std::size_t i) {
    if (!in.axis_u.empty()) return std::max(glm::length(in.axis_u[i]), glm::length(in.axis_v[i]));
    if (in.scales.empty()) return 0.0f;
    const glm::vec3 s = in.scales[i];
    float r = float(kFootprintSigmas) * std::max({std::abs(s.x), std::abs(s.y), std::abs(s.z)});
    if (!in.jacobians.empty()) {
        const glm::mat3& j = in.jacobians[i];
        r *= std::max({glm::length(j[0]), glm::length(j[1]), glm::length(j[2])});
    }
    return std::isfinite(r) ? r : 0.0f;
}

void rebuild(CloudCache& c, std::span<const glm::vec3> positions, const RadiusInputs& in) {
    const std::size_t n = positions.size();
    c.radius.resize(n);
    c.normal.resize(n);
    c.blocks.assign((n + kBlockPoints - 1) / kBlockPoints, Block{});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, c.blocks.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t b = range.begin(); b != range.end(); ++b) {
                              Block blk;
                              blk.lo = glm::vec3(INFINITY), blk.hi = glm::vec3(-INFINITY);
                              const std::size_t end = std::min(n, (b + 1) * kBlockPoints);
                              for (std::size_t i = b * kBlockPoints; i < end; ++i) {
                                  const float r = radius_of(in, i);
                                  c.radius[i] = r;
                                  c.normal[i] = normal_of(in, i);
                                  if (!finite(positions[i])) continue;
                                  blk.lo = glm::min(blk.lo, positions[i]);
                                  blk.hi = glm::max(blk.hi, positions[i]);
                                  blk.max_radius = std::max(blk.max_radius, r);
                              }
                              c.blocks[b] = blk;
                          }
                      });
}

}  // namespace

Shown shown_points(ecs::Registry& registry, PointSelectState& state, ecs::Entity e) {
    PointSelectState::Impl& impl = state.impl();
    // Caches of destroyed entities or removed clouds go (a slot reused by a new entity has new bits).
    for (auto it = impl.clouds.begin(); it != impl.clouds.end();) {
        const ecs::Entity owner = ecs::Entity::from_bits(it->first);
        const bool alive = registry.valid(owner) &&
                           (registry.try_get<SplatCloud>(owner) || registry.try_get<GaussianCloud>(owner));
        it = alive ? std::next(it) : impl.clouds.erase(it);
    }

    Shown s;
    if (!registry.valid(e)) return s;
    int kind = -1;
    std::uint64_t version = 0;
    glm::dvec3 origin(0.0);
    RadiusInputs radii;
    std::size_t n = 0;
    if (const SplatCloud* cloud = registry.try_get<SplatCloud>(e)) {
        const picking::SplatSource src = picking::splat_source(registry, e, impl.sources);
        if (src.kind == picking::SplatSource::Kind::none) return s;
        kind = int(src.kind), version = src.version, origin = src.origin, s.positions = src.positions;
        radii.axis_u = src.axis_u, radii.axis_v = src.axis_v, radii.normals = src.normals;
        n = cloud->size();
    } else if (const GaussianCloud* gaussians = registry.try_get<GaussianCloud>(e)) {
        n = gaussians->size();
        const picking::GaussianSource src = picking::gaussian_source(registry, e, impl.sources);
        if (src.kind == picking::GaussianSource::Kind::none) return s;
        kind = int(src.kind), version = src.version, origin = src.origin, s.positions = src.positions;
        radii.scales = src.scales.size() == n ? src.scales : std::span<const glm::vec3>();
        radii.rotations = src.rotations.size() == n ? src.rotations : std::span<const glm::quat>();
        radii.jacobians = src.jacobians.size() == n ? src.jacobians : std::span<const glm::mat3>();
    } else {
        return s;
    }
    if (s.positions.size() != n) return Shown{};

    CloudCache& c = impl.clouds[e.bits()];
    if (c.kind != kind || c.version != version || c.data != s.positions.data() || c.n != n) {
        rebuild(c, s.positions, radii);
        c.kind = kind, c.version = version, c.data = s.positions.data(), c.n = n;
        ++impl.stats.block_rebuilds;
    }
    s.n = n;
    s.cache = &c;
    s.model = model_matrix(registry.try_get<Transform>(e), origin);
    s.scale = std::max({glm::length(glm::dvec3(s.model[0])), glm::length(glm::dvec3(s.model[1])),
                        glm::length(glm::dvec3(s.model[2]))});
    if (const PointFlags* flags = registry.try_get<PointFlags>(e); flags && flags->bits.size() == n)
        s.flags = flags->bits;
    return s;
}

}  // namespace detail
}  // namespace sffd::point_select
