// Encoding a folder of PNG frames as a video with ffmpeg: `splatffd render --video` and
// `splatffd assemble --video` share it (and its checks), so a clip assembled from shards encodes exactly
// as a single run's would.
#pragma once

#include <filesystem>
#include <string>

#include <glm/vec3.hpp>

#include "runtime/core/result.h"

namespace sffd::cli {

// The full path of `name` on PATH (an executable regular file), or "".
std::string find_on_path(const std::string& name);

// Checks a --video FILE before any work: .mp4 or .gif, ffmpeg on PATH, the folder writable. On success
// returns ffmpeg's path. `usage` is set when the mistake is the option's (exit 2) rather than the machine's.
Result<std::string> check_video_output(const std::string& video, bool& usage);

// What a user must be told about the video's size, or "": H.264 in yuv420p needs an even width and height,
// so an MP4 of an odd WIDTHxHEIGHT is padded by one column and/or row of the background colour (the frames
// and a GIF keep the size). Printed by `render --video` and `assemble --video`.
std::string video_size_note(const std::filesystem::path& video, long width, long height);

// Encodes DIR/frame_FIRST..LAST.png into `video` (.mp4: H.264 yuv420p, padded to an even size with the
// background colour; .gif: per-clip palette)
// through a temporary file renamed at the end, so a failed encode leaves no half video. ffmpeg runs with
// an argument vector (no shell): paths with spaces or quotes are safe. Both formats are laid over the same
// opaque `background` (sRGB 0..1; black by default), blended in display space.
Status encode_video(const std::string& ffmpeg, const std::filesystem::path& dir, long first, long last,
                    double fps, const std::filesystem::path& video, glm::vec3 background = glm::vec3(0.0f));

}  // namespace sffd::cli
