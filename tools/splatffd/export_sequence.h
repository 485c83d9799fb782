// What `splatffd export` bakes, one frame at a time: a scene's deformed cloud at frame k of its clips, the
// same pose `render` shows in its frame k (the same fixed-step Clock and the animation system, so the
// frame depends on k alone), deformed on the CPU the way `deform` deforms a scene's cloud (its lattices in
// Deformers order; Gaussians: centres, J Σ Jᵀ and SH, the SH frames baked), and written in one of the
// formats other tools load. The command around it (options, output folder, manifest, shards) is
// cmd_export.cpp.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"

namespace sffd::cli {

enum class ExportFormat { ply, compressed_ply, sog, spz, glb };

// "ply", "compressed-ply", "sog", "spz", "glb"; nothing for any other name.
std::optional<ExportFormat> parse_export_format(std::string_view name);
std::string_view export_format_name(ExportFormat format);
// The formats only 3D Gaussians have (surface splats export as ply or glb).
bool gaussian_only(ExportFormat format);
// ".ply", ".compressed.ply" (the suffix SuperSplat and splat-transform give PlayCanvas's layout), ".sog",
// ".spz", ".glb".
std::string_view export_extension(ExportFormat format);

// frame0007.ply: "frame", the frame number zero-padded to 4 digits (more when `last` needs them, so
// every name of one export has the same width and sorts as text too), the extension. SuperSplat's
// sequence import takes files whose names are a shared prefix, digits and `.ply` or `.compressed.ply`
// (its regex /(.*?)(\d+)(?:\.compressed)?\.ply$/), ordered by the number.
std::string export_frame_name(long frame, long last, ExportFormat format);
// The digits of export_frame_name (4, or as many as `last` has).
int export_frame_digits(long last);

// The one lattice clip of a chain as the manifest names it.
struct ExportClip {
    std::string lattice;  // the lattice's Name
    bool has_clip = false;
    std::string name;
    double duration = 0.0;
    std::string mode;    // loop | once | ping_pong
    double speed = 1.0;  // clip speed times the state's playback speed
    std::size_t keys = 0;
};

// A loaded scene and the one cloud it exports.
struct ExportScene {
    ecs::Registry registry;
    ecs::Entity cloud = ecs::null_entity;
    bool gaussians = false;
    std::string cloud_name;
    std::vector<ecs::Entity> lattices;  // the cloud's Deformers, in order
    std::vector<ExportClip> clips;      // one per lattice, same order
    std::size_t count = 0;              // splats or Gaussians
};

// Loads `scene` (a built-in name or a file, as every command loads it) and picks the cloud to export:
// the one cloud bound to lattices, or the one named `cloud_name` when several are. Errors name the scene:
// "SCENE: no lattice bound to the cloud; nothing to export", several deformed clouds without a name,
// an invalid clip.
Status open_export_scene(const std::string& scene, const std::string& cloud_name, ExportScene& out);

// Poses the scene's lattices at frame `frame` of a clock at `fps`: the Clock render uses (fixed step
// 1/fps, seeked to frame/fps, one tick) and the animation system, so an un-keyed edit shows at its own
// clip time only, exactly as in render's frame.
void pose_export_frame(ExportScene& scene, double fps, long frame);

// What one frame wrote.
struct ExportedFrame {
    std::vector<std::filesystem::path> files;  // the frame file, and its texture when PLY needs one
    std::size_t inverted = 0, not_finite = 0;
};

// Deforms the cloud by its lattices' current control points (CPU, the deform command's arithmetic) and
// writes it to `path` in `format` (atomic). Surface splats: ply or glb (with normals and splat axes);
// Gaussians: every format.
Result<ExportedFrame> write_export_frame(const ExportScene& scene, ExportFormat format,
                                         const std::filesystem::path& path);

}  // namespace sffd::cli
