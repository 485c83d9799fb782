#include "systems/gaussian/capture_up.h"

#include <atomic>
#include <cmath>

namespace sffd::gaussian {

namespace {
std::atomic<CaptureUp> g_up{CaptureUp::minus_y};
}

Result<CaptureUp> parse_capture_up(std::string_view text) {
    if (text == "-y") return CaptureUp::minus_y;
    if (text == "y" || text == "+y") return CaptureUp::plus_y;
    if (text == "z" || text == "+z") return CaptureUp::plus_z;
    if (text == "-z") return CaptureUp::minus_z;
    return make_error("--up: expected -y (y down, the default for Gaussian captures), y, z or -z, got '" +
                      std::string(text) + "'");
}

const char* capture_up_name(CaptureUp up) {
    switch (up) {
        case CaptureUp::minus_y: return "-y";
        case CaptureUp::plus_y: return "y";
        case CaptureUp::plus_z: return "z";
        case CaptureUp::minus_z: return "-z";
    }
    return "?";
}

void set_capture_up(CaptureUp up) { g_up.store(up); }
CaptureUp capture_up() { return g_up.load(); }

Transform capture_transform(CaptureUp up) {
    Transform t;
    const double h = std::sqrt(0.5);
    switch (up) {
        case CaptureUp::minus_y: t.rotation = glm::dquat(0.0, 1.0, 0.0, 0.0); break;  // w, x, y, z
        case CaptureUp::plus_y: break;
        case CaptureUp::plus_z: t.rotation = glm::dquat(h, -h, 0.0, 0.0); break;
        case CaptureUp::minus_z: t.rotation = glm::dquat(h, h, 0.0, 0.0); break;
    }
    return t;
}

}  // namespace sffd::gaussian
