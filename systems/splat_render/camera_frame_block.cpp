// camera_frame_block() of camera_math.h, apart from the scene cameras: it is glm alone, so the CPU
// kernels' build (SFFD_CPU_KERNELS_ONLY) links it into the rasteriser's tests without the GL passes that
// scene_camera() reaches.
#include "systems/splat_render/camera_math.h"

namespace sffd::render {

gpu::FrameBlock camera_frame_block(const glm::dmat4& view, const glm::dmat4& projection, int width,
                                   int height, float visibility_epsilon, float max_point_size, bool culling) {
    gpu::FrameBlock b{};
    b.model_view = glm::mat4(view);
    b.normal_view = glm::mat4(glm::mat3(glm::transpose(glm::inverse(glm::dmat3(view)))));
    b.projection = glm::mat4(projection);
    b.view_to_world = glm::mat4(glm::inverse(view));
    b.viewport = glm::vec4(float(width), float(height), 1.0f / float(width), 1.0f / float(height));
    b.ray_map = glm::vec4(float(2.0 / (double(width) * projection[0][0])),
                          float(2.0 / (double(height) * projection[1][1])), float(-1.0 / projection[0][0]),
                          float(-1.0 / projection[1][1]));
    b.params = glm::vec4(visibility_epsilon, max_point_size, culling ? 1.0f : 0.0f, 0.0f);
    b.base_color = glm::vec4(1.0f);
    return b;
}

}  // namespace sffd::render
