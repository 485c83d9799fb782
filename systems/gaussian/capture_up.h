// Which way is up in a Gaussian capture, and the one turn that shows it upright in the engine's world.
//
// Every reader brings its format into the same frame (gaussian_axes.h: the 3DGS PLY frame; SPZ and
// KHR_gaussian_splatting state their own axes and are turned into it), so one convention covers every
// format: captures come out of COLMAP-style pipelines with y down, as SuperSplat and splat-transform
// assume, and the engine's world is y up (glTF). A Gaussian file loaded into a scene gets the Transform
// that turns its up onto +y; its data stays as stored, so every file-level command (convert, deform, info)
// works in the file's own coordinates. `splatffd --up AXIS` (any command) names another up for files
// stored otherwise; the same capture takes the same --up from every format. Scene files store their
// Gaussians' transform and are not turned again.
#pragma once

#include <string>
#include <string_view>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

enum class CaptureUp {
    minus_y,  // y down (3DGS, COLMAP, OpenCV camera axes): the default
    plus_y,   // y up (stored already in the engine's orientation)
    plus_z,   // z up (photogrammetry and CAD exports)
    minus_z,
};

// "-y", "y" (or "+y"), "z" (or "+z"), "-z"; anything else is an error naming the option.
Result<CaptureUp> parse_capture_up(std::string_view text);
const char* capture_up_name(CaptureUp up);

// The up of every Gaussian file loaded from now on (the process's choice, set once by the command line).
void set_capture_up(CaptureUp up);
CaptureUp capture_up();

// The rotation that turns `up` onto the world's +y: 180 degrees about x for -y (so the capture's forward,
// +z, looks down the world's -z as a default camera does), identity for +y, -90 / +90 degrees about x
// for +z / -z.
Transform capture_transform(CaptureUp up = capture_up());

}  // namespace sffd::gaussian
