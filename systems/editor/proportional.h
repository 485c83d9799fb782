// Proportional editing of lattice control points (Blender's "proportional edit", key `o`): the control
// points that are not selected but lie within a radius of the selection follow its move, twist or scale
// by a falloff weight of their distance.
//
// Distance: in world space, from a control point (at the pose shown when the edit began) to the nearest
// edited (selected, not pinned) control point; that is Blender's distance with "connected only" off.
// Weight (Blender's calculatePropRatio), with u = (r - d) / r for d <= r:
//   smooth    3u^2 - 2u^3      sphere    sqrt(2u - u^2)      linear    u
//   sharp     u^2              constant  1
// and 0 for d > r. The edited points have weight 1. A neighbour of weight w moves by w times the edit:
// a stretch by w·d, a twist by w·angle about the same axis and pivot, a scale by w times the way the
// scale moves it (p + w·(pivot + S(p - pivot) - p)), as Blender interpolates each transform.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace sffd::editor {

enum class Falloff : std::uint8_t { smooth, sphere, linear, sharp, constant };
inline constexpr int falloff_count = 5;
const char* falloff_name(Falloff falloff);
std::optional<Falloff> falloff_from_name(std::string_view name);

struct ProportionalSettings {
    bool enabled = false;
    Falloff falloff = Falloff::smooth;
    double radius = 1.0;  // world units
};
// Radius limits (Blender's: 0.00001 and a view's far clip) and the factor of one wheel notch or
// PageUp/PageDown (Blender's 1.1).
inline constexpr double proportional_min_radius = 1e-5, proportional_max_radius = 1e6;
inline constexpr double proportional_radius_step = 1.1;
double clamp_proportional_radius(double radius);

// Replay `set` fields (input_record.h): proportional.enabled (0 or 1), proportional.radius (world units,
// clamped to the limits), proportional.falloff (a falloff name in the file; its index in the event).
bool is_proportional_field(std::string_view field);
void set_proportional_field(ProportionalSettings& settings, std::string_view field, double value);

// The weight of a point at distance `d` from the nearest edited point; radius <= 0 gives 0.
double falloff_weight(Falloff falloff, double d, double radius);

// For each point of `world`, the distance to the nearest of the points `edited` (0 for those); infinity
// when `edited` is empty. Brute force over the edited points: a lattice has at most a few thousand.
std::vector<double> nearest_edited_distance(std::span<const glm::dvec3> world,
                                            std::span<const std::uint32_t> edited);

// Points moved by an edit and their weights: the edited points (weight 1) and every point not in
// `excluded` (pinned; may be empty) whose falloff weight at `distance` is above 0, sorted by index; off
// (or without distances) the edited points alone, in their order.
struct WeightedPoints {
    std::vector<std::uint32_t> indices;
    std::vector<double> weights;
};
WeightedPoints proportional_points(std::span<const std::uint32_t> edited, std::span<const double> distance,
                                   std::span<const std::uint8_t> excluded,
                                   const ProportionalSettings& settings);

}  // namespace sffd::editor
