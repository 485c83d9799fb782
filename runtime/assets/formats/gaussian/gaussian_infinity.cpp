#include "runtime/assets/formats/gaussian/gaussian_infinity.h"

#include <cmath>

#include "runtime/core/log.h"

namespace sffd::gaussian {

bool opacity_from_logit(double x, float& opacity, InfinityCount& mapped) {
    if (std::isnan(x)) return false;
    if (std::isinf(x)) {
        opacity = x > 0 ? 1.0f : 0.0f;
        ++mapped.opacity;
        return true;
    }
    opacity = float(1.0 / (1.0 + std::exp(-x)));
    return true;
}

bool scale_from_log(double x, float& scale, InfinityCount& mapped) {
    if (std::isnan(x)) return false;
    if (std::isinf(x)) {
        if (x > 0) return false;
        scale = 0.0f;
        ++mapped.scale;
        return true;
    }
    const float s = float(std::exp(x));
    if (!std::isfinite(s)) return false;
    scale = s;
    return true;
}

void report_infinities(const std::string& file, const InfinityCount& mapped) {
    if (mapped.total() == 0) return;
    log::info(file, ": read ", mapped.total(), " infinite values as limits (", mapped.opacity,
              " logit opacities of +-inf as 1 or 0, ", mapped.scale, " log scales of -inf as flat axes)");
}

}  // namespace sffd::gaussian
