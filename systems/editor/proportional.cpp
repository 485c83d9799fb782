#include "systems/editor/proportional.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace sffd::editor {

namespace {
constexpr std::array<const char*, falloff_count> names = {"smooth", "sphere", "linear", "sharp", "constant"};
}

const char* falloff_name(Falloff falloff) {
    const auto i = std::size_t(falloff);
    return i < names.size() ? names[i] : "smooth";
}

std::optional<Falloff> falloff_from_name(std::string_view name) {
    for (std::size_t i = 0; i < names.size(); ++i)
        if (name == names[i]) return Falloff(i);
    return std::nullopt;
}

double clamp_proportional_radius(double radius) {
    if (!std::isfinite(radius)) return proportional_max_radius;
    return std::clamp(radius, proportional_min_radius, proportional_max_radius);
}

bool is_proportional_field(std::string_view field) {
    return field == "proportional.enabled" || field == "proportional.radius" ||
           field == "proportional.falloff";
}

void set_proportional_field(ProportionalSettings& settings, std::string_view field, double value) {
    if (field == "proportional.enabled") settings.enabled = value != 0.0;
    else if (field == "proportional.radius") settings.radius = clamp_proportional_radius(value);
    else if (field == "proportional.falloff" && value >= 0.0 && value < falloff_count)
        settings.falloff = Falloff(int(value));
}

double falloff_weight(Falloff falloff, double d, double radius) {
    if (!(radius > 0.0) || d > radius) return 0.0;
    const double u = std::max(0.0, (radius - d) / radius);
    switch (falloff) {
        case Falloff::smooth: return 3.0 * u * u - 2.0 * u * u * u;
        case Falloff::sphere: return std::sqrt(std::max(0.0, 2.0 * u - u * u));
        case Falloff::linear: return u;
        case Falloff::sharp: return u * u;
        case Falloff::constant: return 1.0;
    }
    return 0.0;
}

std::vector<double> nearest_edited_distance(std::span<const glm::dvec3> world,
                                            std::span<const std::uint32_t> edited) {
    std::vector<double> out(world.size(), std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < world.size(); ++c) {
        double best = std::numeric_limits<double>::infinity();
        for (std::uint32_t e : edited)
            if (e < world.size()) best = std::min(best, glm::length(world[c] - world[e]));
        out[c] = best;
    }
    for (std::uint32_t e : edited)
        if (e < out.size()) out[e] = 0.0;
    return out;
}

WeightedPoints proportional_points(std::span<const std::uint32_t> edited, std::span<const double> distance,
                                   std::span<const std::uint8_t> excluded,
                                   const ProportionalSettings& settings) {
    if (!settings.enabled || distance.empty()) {  // the edited points alone, as without proportional editing
        WeightedPoints out;
        out.indices.assign(edited.begin(), edited.end());
        out.weights.assign(edited.size(), 1.0);
        return out;
    }
    std::vector<double> weight(distance.size(), 0.0);
    for (std::size_t c = 0; c < distance.size(); ++c)
        if (excluded.empty() || !excluded[c])
            weight[c] = falloff_weight(settings.falloff, distance[c], settings.radius);
    for (std::uint32_t e : edited)
        if (e < weight.size()) weight[e] = 1.0;
    WeightedPoints out;
    for (std::size_t c = 0; c < weight.size(); ++c)
        if (weight[c] > 0.0) {
            out.indices.push_back(std::uint32_t(c));
            out.weights.push_back(weight[c]);
        }
    return out;
}

}  // namespace sffd::editor
