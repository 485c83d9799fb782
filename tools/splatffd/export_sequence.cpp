#include "tools/splatffd/export_sequence.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "runtime/app/clock.h"
#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "systems/animation/evaluate.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/engine/engine_frame.h"

namespace sffd::cli {

namespace {

std::string name_of(const ecs::Registry& r, ecs::Entity e, const char* fallback) {
    const Name* n = r.try_get<Name>(e);
    return n && !n->value.empty() ? n->value : fallback;
}

const char* mode_name(PlayMode m) {
    switch (m) {
        case PlayMode::loop: return "loop";
        case PlayMode::once: return "once";
        case PlayMode::ping_pong: return "ping_pong";
    }
    return "loop";
}

std::string quoted(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
    return s;
}

}  // namespace

std::optional<ExportFormat> parse_export_format(std::string_view name) {
    if (name == "ply") return ExportFormat::ply;
    if (name == "compressed-ply") return ExportFormat::compressed_ply;
    if (name == "sog") return ExportFormat::sog;
    if (name == "spz") return ExportFormat::spz;
    if (name == "glb") return ExportFormat::glb;
    return std::nullopt;
}

std::string_view export_format_name(ExportFormat format) {
    switch (format) {
        case ExportFormat::ply: return "ply";
        case ExportFormat::compressed_ply: return "compressed-ply";
        case ExportFormat::sog: return "sog";
        case ExportFormat::spz: return "spz";
        case ExportFormat::glb: return "glb";
    }
    return "ply";
}

bool gaussian_only(ExportFormat format) {
    return format == ExportFormat::compressed_ply || format == ExportFormat::sog ||
           format == ExportFormat::spz;
}

std::string_view export_extension(ExportFormat format) {
    switch (format) {
        case ExportFormat::ply: return ".ply";
        case ExportFormat::compressed_ply: return ".compressed.ply";
        case ExportFormat::sog: return ".sog";
        case ExportFormat::spz: return ".spz";
        case ExportFormat::glb: return ".glb";
    }
    return ".ply";
}

int export_frame_digits(long last) {
    int digits = 1;
    for (long v = last; v >= 10; v /= 10) ++digits;
    return digits < 4 ? 4 : digits;
}

std::string export_frame_name(long frame, long last, ExportFormat format) {
    char number[32];
    std::snprintf(number, sizeof number, "%0*ld", export_frame_digits(last), frame);
    return "frame" + std::string(number) + std::string(export_extension(format));
}

Status open_export_scene(const std::string& scene, const std::string& cloud_name, ExportScene& out) {
    ecs::Registry& r = out.registry;
    sffd::use_engine_scene_hooks(r);
    if (Status st = load_scene(r, scene); !st) return st;
    // The clouds the engine deforms: those with Deformers naming lattices (render shows the others at rest).
    std::vector<ecs::Entity> deformed, clouds;
    std::vector<std::string> deformed_names;
    r.each_entity([&](ecs::Entity e) {
        if (!r.has<SplatCloud>(e) && !r.has<GaussianCloud>(e)) return;
        clouds.push_back(e);
        const Deformers* d = r.try_get<Deformers>(e);
        bool bound = false;
        if (d)
            for (ecs::Entity l : d->lattices) bound = bound || (r.valid(l) && r.has<Lattice>(l));
        if (!bound) return;
        deformed.push_back(e);
        deformed_names.push_back(name_of(r, e, "cloud"));
    });
    if (clouds.empty()) return make_error(scene + ": no point cloud or Gaussians; nothing to export");
    if (deformed.empty()) return make_error(scene + ": no lattice bound to the cloud; nothing to export");
    if (!cloud_name.empty()) {
        out.cloud = ecs::null_entity;
        for (std::size_t i = 0; i < deformed.size(); ++i)
            if (deformed_names[i] == cloud_name) out.cloud = deformed[i];
        if (!out.cloud)
            return make_error(scene + ": no deformed cloud named '" + cloud_name +
                              "' (deformed clouds: " + quoted(deformed_names) + ")");
    } else if (deformed.size() > 1) {
        return make_error(scene + ": " + std::to_string(deformed.size()) + " deformed clouds (" +
                          quoted(deformed_names) + "); a frame file holds one: choose it with --cloud NAME");
    } else {
        out.cloud = deformed[0];
    }
    // Frames are exports: no hidden or deleted point is written (runtime/scene/point_subset.h).
    if (auto gone = drop_gone_points(r, out.cloud, PointDrop::hidden_and_deleted); !gone)
        return make_error(scene + ": " + gone.message());
    out.gaussians = r.has<GaussianCloud>(out.cloud);
    out.cloud_name = name_of(r, out.cloud, "cloud");
    out.count = out.gaussians ? r.get<GaussianCloud>(out.cloud).size() : r.get<SplatCloud>(out.cloud).size();
    for (ecs::Entity l : r.get<Deformers>(out.cloud).lattices) {
        if (!r.valid(l) || !r.has<Lattice>(l)) continue;
        out.lattices.push_back(l);
        ExportClip c;
        c.lattice = name_of(r, l, "lattice");
        if (const AnimationClip* clip = r.try_get<AnimationClip>(l)) {
            // A clip the animation system would skip (render then shows the saved pose) is refused here, so
            // no export silently differs from the clip it names.
            if (Status st = validate_clip(*clip, r.get<Lattice>(l).rest.size()); !st)
                return make_error(scene + ": lattice '" + c.lattice + "': " + st.message());
            c.has_clip = true;
            c.name = clip->name;
            c.duration = clip->duration;
            c.mode = mode_name(clip->mode);
            const AnimationState* state = r.try_get<AnimationState>(l);
            c.speed = clip->speed * (state ? state->speed : 1.0);
            for (const AnimationTrack& t : clip->tracks) c.keys += t.keys.size();
        }
        out.clips.push_back(std::move(c));
    }
    return {};
}

void pose_export_frame(ExportScene& scene, double fps, long frame) {
    // The same frame context render's frame k gets (cmd_render.cpp render_frame), so the pose is render's.
    Clock clock(ClockSettings{.fixed_dt = 1.0 / fps});
    clock.seek(double(frame) / fps);
    FrameContext context = clock.tick();
    context.frame = std::uint64_t(frame);
    animation_system(scene.registry, context);
}

namespace {

// The cloud's weights (PointWeights) when they are one a point; else null (weight 1).
const float* weights_of(const ecs::Registry& r, ecs::Entity e, std::size_t n) {
    const PointWeights* w = r.try_get<PointWeights>(e);
    return w && w->values.size() == n && n > 0 ? w->values.data() : nullptr;
}

Result<ExportedFrame> write_surface(const ExportScene& scene, ExportFormat format,
                                    const std::filesystem::path& path) {
    const ecs::Registry& r = scene.registry;
    SplatCloud cloud = r.get<SplatCloud>(scene.cloud);
    const std::size_t n = cloud.size();
    // As deform: attributes of the wrong length are dropped, not deformed past their end.
    if (cloud.axis_u.size() != n || cloud.axis_v.size() != n) cloud.axis_u.clear(), cloud.axis_v.clear();
    if (cloud.normals.size() != n) cloud.normals.clear();
    auto ptr = [](std::vector<glm::vec3>& v) { return v.empty() ? nullptr : v.data(); };
    ExportedFrame done;
    // In the cloud's frame through both Transforms, as the engine and `deform` place them.
    const ffd::CloudLattices frame = ffd::cloud_lattices(r, scene.cloud, scene.lattices);
    for (std::size_t li = 0; li < frame.lattices.size(); ++li) {
        const ecs::Entity e = frame.entities[li];
        const Lattice& l = *frame.lattices[li];
        ffd::PointsIn in{cloud.positions.data(),
                         ptr(cloud.normals),
                         ptr(cloud.axis_u),
                         ptr(cloud.axis_v),
                         n,
                         cloud.origin};
        in.weights = weights_of(r, scene.cloud, n);  // P + w (FFD(P) - P), as the engine deforms it
        const ffd::PointsOut o{cloud.positions.data(), ptr(cloud.normals), ptr(cloud.axis_u),
                               ptr(cloud.axis_v)};
        auto stats = ffd::deform(l, in, o);
        if (!stats) return make_error(name_of(r, e, "lattice") + ": " + stats.message());
        done.inverted += stats->inverted;
    }
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(cloud.positions[i].x) || !std::isfinite(cloud.positions[i].y) ||
            !std::isfinite(cloud.positions[i].z))
            return make_error("deformed point " + std::to_string(i) +
                              " is not finite; nothing was written to " + path.string());
    const SplatMaterial* m = r.try_get<SplatMaterial>(scene.cloud);
    Status saved = format == ExportFormat::glb
                       ? assets::save_splat_glb(cloud, path, scene.cloud_name, m ? *m : SplatMaterial{})
                       : assets::save_splat_ply(cloud, path);
    if (!saved) return saved.error();
    done.files.push_back(path);
    // A PLY cannot hold texels without a file: save_splat_ply wrote them beside it
    // (runtime/assets/formats/surface/export.h).
    if (format == ExportFormat::ply && cloud.texture.path.empty() && !cloud.texture.rgba8.empty())
        done.files.push_back(path.parent_path() / (path.stem().string() + "_texture.png"));
    return done;
}

Result<ExportedFrame> write_gaussians(const ExportScene& scene, ExportFormat format,
                                      const std::filesystem::path& path) {
    const ecs::Registry& r = scene.registry;
    GaussianCloud cloud = r.get<GaussianCloud>(scene.cloud);
    ExportedFrame done;
    gaussian::DeformOptions options;
    options.weights = weights_of(r, scene.cloud, cloud.size());  // as the engine deforms them
    const ffd::CloudLattices frame = ffd::cloud_lattices(r, scene.cloud, scene.lattices);
    for (std::size_t li = 0; li < frame.lattices.size(); ++li) {
        const ecs::Entity e = frame.entities[li];
        auto stats = gaussian::deform(*frame.lattices[li], cloud, cloud, options);
        if (!stats) return make_error(name_of(r, e, "lattice") + ": " + stats.message());
        done.inverted += stats->inverted;
        done.not_finite += stats->not_finite;
    }
    gaussian::bake_sh_frames(cloud);
    Status saved;
    switch (format) {
        case ExportFormat::ply: saved = gaussian::write_ply(path, cloud); break;
        case ExportFormat::compressed_ply: saved = gaussian::write_compressed_ply(path, cloud); break;
        case ExportFormat::spz: saved = gaussian::write_spz(path, cloud); break;
        case ExportFormat::glb: saved = gaussian::write_glb(path, cloud); break;
        case ExportFormat::sog: saved = gaussian::write_sog(path, cloud); break;
    }
    if (!saved) return saved.error();
    done.files.push_back(path);
    return done;
}

}  // namespace

Result<ExportedFrame> write_export_frame(const ExportScene& scene, ExportFormat format,
                                         const std::filesystem::path& path) {
    if (scene.gaussians) return write_gaussians(scene, format, path);
    if (gaussian_only(format))
        return make_error("--format " + std::string(export_format_name(format)) +
                          " is for 3D Gaussians; surface splats export as ply or glb");
    return write_surface(scene, format, path);
}

}  // namespace sffd::cli
