#include "systems/picking/gaussian_source.h"

#include <algorithm>
#include <cmath>

#include "runtime/gfx/residency.h"
#include "runtime/gfx/gl.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd::picking {

namespace {

// Centres and accumulated Jacobians of `cloud` (entity e) through `lattices` in order (J = J_n ... J_1),
// each in the cloud's frame (systems/ffd/lattice_frame.h). False when a lattice is refused (the cache then
// keeps nothing and the authored cloud is picked).
bool deform_centres(const ecs::Registry& registry, ecs::Entity e, const std::vector<ecs::Entity>& lattices,
                    const GaussianCloud& cloud, PickCache::Entry& entry) {
    const std::size_t n = cloud.size();
    entry.positions = cloud.positions;
    entry.jacobians.assign(n, glm::mat3(1.0f));
    std::vector<glm::vec3> moved(n);
    std::vector<glm::mat3> step(n);
    const ffd::CloudLattices framed = ffd::cloud_lattices(registry, e, lattices);
    for (const Lattice* l : framed.lattices) {
        const ffd::PointsIn in{entry.positions.data(), nullptr, nullptr, nullptr, n, cloud.origin};
        ffd::PointsOut out{moved.data(), nullptr, nullptr, nullptr};
        out.jacobians = step.data();
        if (!ffd::deform(*l, in, out)) return false;
        entry.positions.swap(moved);
        for (std::size_t i = 0; i < n; ++i) entry.jacobians[i] = step[i] * entry.jacobians[i];
    }
    return true;
}

// The resident GPU-only deformed output of cloud `e` (state deformed_gpu, n Gaussians), if one is readable.
const gaussian::GpuGaussians* gpu_only_output(const ecs::Registry& registry, ecs::Entity e, std::size_t n) {
    if (!gfx::context_current()) return nullptr;
    const auto* store = registry.try_resource<gaussian::GpuGaussianStore>();
    if (!store) return nullptr;
    const auto it = store->clouds.find(e);
    if (it == store->clouds.end()) return nullptr;
    const gaussian::GpuGaussians& gpu = it->second;
    const bool current = gpu.state == gfx::Residency::deformed_gpu && gpu.count == n &&
                         gpu.rest_version == registry.version<GaussianCloud>(e);
    return current ? &gpu : nullptr;
}

// Centres, scales and rotations of a GPU-only output (waits for the GPU).
void read_back(const gaussian::GpuGaussians& gpu, PickCache::Entry& entry) {
    const std::size_t n = gpu.count;
    std::vector<gpu::GpuGaussian> rows(n);
    // The compute pass wrote the buffer through shader storage: make those writes visible to the copy.
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    if (n)
        glGetNamedBufferSubData(gpu.deformed.id(), 0, GLsizeiptr(n * sizeof(gpu::GpuGaussian)), rows.data());
    entry.positions.resize(n), entry.scales.resize(n), entry.rotations.resize(n);
    entry.jacobians.clear();
    for (std::size_t i = 0; i < n; ++i) {
        const gpu::GpuGaussian& r = rows[i];
        entry.positions[i] = {r.pos_opacity[0], r.pos_opacity[1], r.pos_opacity[2]};
        entry.rotations[i] = glm::quat(r.rotation[0], r.rotation[1], r.rotation[2], r.rotation[3]);
        entry.scales[i] = {r.scale[0], r.scale[1], r.scale[2]};
    }
}

}  // namespace

GaussianSource gaussian_source(ecs::Registry& registry, ecs::Entity e, PickCache& cache) {
    GaussianSource src;
    const GaussianCloud* cloud = registry.try_get<GaussianCloud>(e);
    if (!cloud) return src;
    const std::size_t n = cloud->size();
    const bool consistent =
        cloud->scales.size() == n && cloud->rotations.size() == n && cloud->opacities.size() == n;
    if (!consistent) return src;  // malformed component: nothing to pick rather than out-of-range reads
    src.opacities = cloud->opacities;
    src.kind = GaussianSource::Kind::authored;
    src.version = registry.version<GaussianCloud>(e);
    src.origin = cloud->origin;
    src.positions = cloud->positions;
    src.scales = cloud->scales;
    src.rotations = cloud->rotations;
    if (!registry.has<Deformers>(e)) {
        cache.erase(PickCloudKind::gaussian, e);
        return src;
    }
    const ffd::DeformInputs inputs = ffd::deform_inputs<GaussianCloud>(registry, e);
    const DeformedGaussians* deformed = registry.try_get<DeformedGaussians>(e);
    if (deformed && deformed->seen == inputs.stamps && deformed->cloud.size() == n &&
        deformed->cloud.scales.size() == n && deformed->cloud.rotations.size() == n) {
        cache.erase(PickCloudKind::gaussian, e);
        src.kind = GaussianSource::Kind::deformed;
        src.version = registry.version<DeformedGaussians>(e);
        src.origin = deformed->cloud.origin;
        src.positions = deformed->cloud.positions;
        src.scales = deformed->cloud.scales;
        src.rotations = deformed->cloud.rotations;
        return src;
    }
    // Current output, GPU-only: read it back once per version.
    if (deformed && deformed->seen == inputs.stamps && gaussian::output_on_gpu(registry, e))
        if (const gaussian::GpuGaussians* gpu = gpu_only_output(registry, e, n)) {
            PickCache::Entry& entry = cache.entry(PickCloudKind::gaussian, e);
            if (!entry.holds_read_back(gpu->deformed_version, inputs.stamps)) {
                read_back(*gpu, entry);
                cache.filled(entry, true, gpu->deformed_version, inputs.stamps);
                ++cache.gaussian_read_backs;
            }
            src.kind = GaussianSource::Kind::gpu_read_back;
            src.version = entry.serial;
            src.origin = cloud->origin;
            src.positions = entry.positions;
            src.scales = entry.scales;
            src.rotations = entry.rotations;
            return src;
        }
    // Output missing, stale or not readable: picking's own centres + Jacobians.
    PickCache::Entry& entry = cache.entry(PickCloudKind::gaussian, e);
    if (!entry.holds_deformation(inputs.stamps)) {
        if (!deform_centres(registry, e, inputs.lattices, *cloud, entry)) {
            cache.erase(PickCloudKind::gaussian, e);
            return src;  // a refused lattice: the authored cloud, as the deformation phase would skip it
        }
        entry.scales.clear(), entry.rotations.clear();
        cache.filled(entry, false, 0, inputs.stamps);
        ++cache.gaussian_deformations;
    }
    src.kind = GaussianSource::Kind::cpu_deformed;
    src.version = entry.serial;
    src.positions = entry.positions;
    src.jacobians = entry.jacobians;
    return src;
}

std::uint64_t gaussian_source_storage_version(const ecs::Registry& registry) {
    return registry.storage_version<GaussianCloud>() * 0x9E3779B97F4A7C15ull ^
           registry.storage_version<DeformedGaussians>();
}

double gaussian_pick_sigmas(double opacity) {
    const double x = 255.0 * opacity;
    if (!(x > 1.0) || !std::isfinite(x)) return 0.0;
    return std::sqrt(2.0 * std::log(x));
}

PickEllipsoid gaussian_ellipsoid(const glm::dmat4& model, const glm::dvec3& shifted_centre,
                                 const glm::vec3& scale, const glm::quat& rotation, float opacity,
                                 const glm::mat3& jacobian) {
    PickEllipsoid e;
    const double k = gaussian_pick_sigmas(double(std::min(opacity, 1.0f)));
    const glm::dvec3 s(scale);
    const double s_max = std::max({s.x, s.y, s.z});
    const glm::dquat q(rotation);
    const double qn = glm::length(q);
    if (k == 0.0 || !(s_max > 0.0) || !std::isfinite(s_max) || !(qn > 0.0) || !std::isfinite(qn) ||
        !std::isfinite(shifted_centre.x + shifted_centre.y + shifted_centre.z))
        return e;
    const glm::dvec3 sc = glm::max(s, glm::dvec3(1e-6 * s_max));
    const glm::dmat3 R = glm::mat3_cast(q / qn);
    const glm::dmat3 L = glm::dmat3(model) * glm::dmat3(jacobian);
    const double detL = glm::determinant(L);
    if (!(std::abs(detL) > 1e-300) || !std::isfinite(detL)) return e;
    const glm::dmat3 B = L * R * glm::dmat3(sc.x, 0, 0, 0, sc.y, 0, 0, 0, sc.z);  // world axes (columns) × σ
    // to_unit = B⁻¹ = S⁻¹ Rᵀ L⁻¹ (L: the model's linear part times the deformation's J).
    e.to_unit = glm::dmat3(1.0 / sc.x, 0, 0, 0, 1.0 / sc.y, 0, 0, 0, 1.0 / sc.z) * glm::transpose(R) *
                glm::inverse(L);
    if (!std::isfinite(e.to_unit[0][0] + e.to_unit[1][1] + e.to_unit[2][2])) return e;
    e.centre = glm::dvec3(model * glm::dvec4(shifted_centre, 1.0));
    // Half extent along world axis j: k |row j of B| (support function of the ellipsoid B·ball(k)).
    for (int j = 0; j < 3; ++j) e.half_extent[j] = k * glm::length(glm::dvec3(B[0][j], B[1][j], B[2][j]));
    e.k = k;
    e.opacity = double(std::min(opacity, 1.0f));
    return e;
}

double ray_alpha(const PickEllipsoid& e, const glm::dvec3& origin, const glm::dvec3& direction) {
    const glm::dvec3 o = e.to_unit * (origin - e.centre);
    const glm::dvec3 d = e.to_unit * direction;
    const double a = glm::dot(d, d);
    if (!(a > 0.0)) return 0.0;
    const double m2 = std::max(0.0, glm::dot(o, o) - glm::dot(o, d) * glm::dot(o, d) / a);
    return std::min(0.99, e.opacity * std::exp(-0.5 * m2));
}

double intersect_ellipsoid(const PickEllipsoid& e, const glm::dvec3& origin, const glm::dvec3& direction,
                           double tnear, double tfar) {
    if (e.k <= 0.0) return -1.0;
    const glm::dvec3 o = e.to_unit * (origin - e.centre);
    const glm::dvec3 d = e.to_unit * direction;
    const double a = glm::dot(d, d);
    const double b = glm::dot(o, d);
    const double c = glm::dot(o, o) - e.k * e.k;
    const double disc = b * b - a * c;
    if (!(a > 0.0) || !(disc >= 0.0)) return -1.0;
    // Stable roots of a t² + 2 b t + c = 0.
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 >= tnear && t0 <= tfar) return t0;
    if (t1 >= tnear && t1 <= tfar) return t1;
    return -1.0;
}

}  // namespace sffd::picking
