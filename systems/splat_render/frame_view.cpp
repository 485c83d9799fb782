// Splat render system: the camera, the per-frame uniforms and the screen rectangle the clouds cover.
#include "systems/splat_render/splat_render_detail.h"

#include <cmath>
#include <utility>

namespace sffd::render::detail {

ViewSetup choose_camera(ecs::Registry& reg, const SplatRenderState& /*s*/, double aspect) {
    ViewSetup v;
    // The one default-camera rule (camera_math.h), fed with the bounds cached per uploaded cloud.
    v.camera = scene_camera(
        reg, aspect,
        [&](ecs::Entity e, const SplatCloud&) {
            const CloudGpu* gpu = std::as_const(reg).try_get<CloudGpu>(e);
            return gpu ? gpu->bounds : BoundingSphere{glm::dvec3(0.0), -1.0};
        },
        [&](ecs::Entity e, const GaussianCloud&) { return cached_gaussian_bounds(reg, e); });
    v.view = view_matrix(v.camera);
    v.projection = projection_matrix(v.camera, aspect);
    return v;
}

gpu::FrameBlock frame_block(ecs::Registry& reg, const RenderSettings& settings, const ViewSetup& view,
                            float max_point_size) {
    gpu::FrameBlock b = camera_frame_block(view.view, view.projection, settings.width, settings.height,
                                           settings.visibility_epsilon, max_point_size, settings.culling);
    std::uint32_t lights = 0;
    reg.view<const DirectionalLight>().each([&](const DirectionalLight& l) {
        if (lights >= SFFD_MAX_LIGHTS) return;
        b.light_dir[lights] = glm::vec4(-glm::normalize(l.direction), 0.0f);
        b.light_color[lights] = glm::vec4(l.color * l.intensity, 0.0f);
        ++lights;
    });
    bool has_ambient = false;
    reg.view<const AmbientLight>().each([&](const AmbientLight& a) {
        b.ambient += glm::vec4(a.color * a.intensity, 0.0f);
        has_ambient = true;
    });
    if (lights == 0 && !has_ambient) {  // an unlit scene gets the default key light and ambient
        const DirectionalLight l;
        const AmbientLight a;
        b.light_dir[0] = glm::vec4(-glm::normalize(l.direction), 0.0f);
        b.light_color[0] = glm::vec4(l.color * l.intensity, 0.0f);
        b.ambient = glm::vec4(a.color * a.intensity, 0.0f);
        lights = 1;
    }
    b.background = glm::vec4(settings.background.value_or(glm::vec3(0.0f)), 0.0f);
    b.counts = glm::uvec4(0u, lights, 0u, 0u);
    return b;
}

// Pixel rectangle (x, y, width, height; GL's bottom-left origin) that holds every cloud's projection:
// the deformer's world box when the cloud is deformed, else the rest bounding sphere; the whole frame
// when a bound reaches behind the near plane or a deformed cloud has no box.
glm::ivec4 screen_rect(ecs::Registry& reg, const ViewSetup& view, int w, int h) {
    const glm::ivec4 full(0, 0, w, h);
    const double p00 = view.projection[0][0], p11 = view.projection[1][1];
    const double near_plane = double(view.camera.near_plane);
    glm::dvec2 lo(1e30), hi(-1e30);
    bool everything = false;
    auto add_ball = [&](const glm::dvec3& world_center, double radius) {
        const glm::dvec3 c = glm::dvec3(view.view * glm::dvec4(world_center, 1.0));
        const double depth = -c.z, near_depth = depth - radius;
        if (near_depth <= near_plane) {
            everything = true;
            return;
        }
        const glm::dvec2 ndc(p00 * c.x / depth, p11 * c.y / depth);
        const glm::dvec2 half(radius * std::sqrt(p00 * p00 + ndc.x * ndc.x) / near_depth,
                              radius * std::sqrt(p11 * p11 + ndc.y * ndc.y) / near_depth);
        lo = glm::min(lo, ndc - half);
        hi = glm::max(hi, ndc + half);
    };
    const auto* store = reg.try_resource<gfx::GpuSplatStore>();
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        if (everything || cloud.size() == 0) return;
        const auto sit = store ? store->clouds.find(e) : decltype(store->clouds.end()){};
        const bool deformed = store && sit != store->clouds.end() && sit->second.is_deformed();
        if (deformed) {
            const auto* d = reg.try_get<DeformedSplats>(e);
            if (!d || d->bounds_max.x < d->bounds_min.x) {
                everything = true;
                return;
            }
            // Box -> ball around it, grown by 4x the largest rest splat radius (the box holds the centres;
            // deformed axes are longer by the local stretch).
            const CloudGpu* drawn = std::as_const(reg).try_get<CloudGpu>(e);
            const double splat_r = drawn ? drawn->bounds.max_splat_radius : 0.0;
            add_ball(0.5 * (d->bounds_min + d->bounds_max),
                     0.5 * glm::length(d->bounds_max - d->bounds_min) + 4.0 * splat_r);
            return;
        }
        const CloudGpu* drawn = std::as_const(reg).try_get<CloudGpu>(e);
        if (!drawn) return;
        const glm::dmat4 m = model_matrix(reg.try_get<Transform>(e), cloud.origin);
        const double scale = std::max(
            {glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
        add_ball(glm::dvec3(m * glm::dvec4(drawn->bounds.center, 1.0)), drawn->bounds.radius * scale);
    });
    if (everything) return full;
    if (hi.x < lo.x) return glm::ivec4(0, 0, 0, 0);
    const int x0 = std::clamp(int(std::floor((lo.x * 0.5 + 0.5) * w)) - 1, 0, w);
    const int x1 = std::clamp(int(std::ceil((hi.x * 0.5 + 0.5) * w)) + 1, 0, w);
    const int y0 = std::clamp(int(std::floor((lo.y * 0.5 + 0.5) * h)) - 1, 0, h);
    const int y1 = std::clamp(int(std::ceil((hi.y * 0.5 + 0.5) * h)) + 1, 0, h);
    return glm::ivec4(x0, y0, x1 - x0, y1 - y0);
}

glm::ivec4 intersect_rects(const glm::ivec4& a, const glm::ivec4& b) {
    const int x0 = std::max(a.x, b.x), y0 = std::max(a.y, b.y);
    const int x1 = std::min(a.x + a.z, b.x + b.z), y1 = std::min(a.y + a.w, b.y + b.w);
    return x1 > x0 && y1 > y0 ? glm::ivec4(x0, y0, x1 - x0, y1 - y0) : glm::ivec4(x0, y0, 0, 0);
}

glm::ivec4 plan_drawn_rect(const FramePlan& plan) {
    const glm::ivec4 frame(0, 0, plan.width, plan.height);
    const auto finite = [](const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); };
    if (!plan.drawn_known || !finite(plan.drawn_lo) || !finite(plan.drawn_hi)) return frame;
    if (plan.drawn_lo.x > plan.drawn_hi.x || plan.drawn_lo.y > plan.drawn_hi.y) return glm::ivec4(0);  // none
    // Whole pixels around the squares; clamped in float first (a far sprite's square may be huge).
    const glm::vec2 lo = glm::clamp(glm::floor(plan.drawn_lo), glm::vec2(0.0f), glm::vec2(frame.z, frame.w));
    const glm::vec2 hi = glm::clamp(glm::ceil(plan.drawn_hi), glm::vec2(0.0f), glm::vec2(frame.z, frame.w));
    return intersect_rects(frame, glm::ivec4(int(lo.x), int(lo.y), int(hi.x - lo.x), int(hi.y - lo.y)));
}

}  // namespace sffd::render::detail
