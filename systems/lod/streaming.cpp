#include "systems/lod/streaming.h"

#include <chrono>
#include <cstdio>
#include <limits>
#include <utility>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/capture_up.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/splat_render.h"

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {

double now_s() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

Viewport render_viewport(const ecs::Registry& registry) {
    Viewport v;
    if (const auto* s = registry.try_resource<render::RenderSettings>())
        v.width = std::max(s->width, 1), v.height = std::max(s->height, 1);
    return v;
}

// The lattices' stamp: any lattice or Transform edit, or a change of the list, moves it.
std::uint64_t lattice_stamp(const ecs::Registry& registry, ecs::Entity cloud, const ffd::CloudLattices& l) {
    std::uint64_t h = 1469598103934665603ull;
    const auto mix = [&](std::uint64_t v) { h = (h ^ v) * 1099511628211ull; };
    mix(registry.version<Transform>(cloud));
    for (const ecs::Entity e : l.entities) {
        mix(std::uint64_t(e.index) << 32 | e.generation);
        mix(registry.version<Lattice>(e));
        mix(registry.version<Transform>(e));
    }
    mix(l.entities.size());
    return h;
}

void write_drawn(ecs::Registry& registry, ecs::Entity e, HierarchyStream& stream) {
    if (stream.gaussians()) stream.assemble(registry.patch<GaussianCloud>(e));
    else stream.assemble(registry.patch<SplatCloud>(e));
    // Flags and weights were per point of the old drawn set.
    registry.remove<PointFlags>(e);
    registry.remove<PointWeights>(e);
}

Status load_streamed(ecs::Registry& registry, const fs::path& path) {
    const StreamSettings* set = std::as_const(registry).try_resource<StreamSettings>();  // read only
    const StreamSettings settings = set ? *set : StreamSettings{};
    auto opened = HierarchyStream::open(path, settings.options);
    if (!opened) return opened.error();
    std::shared_ptr<HierarchyStream> stream = std::move(*opened);
    const ecs::Entity e = registry.create();
    const fs::path named = path.parent_path().empty() ? path : path.parent_path();
    registry.emplace<Name>(e, Name{named.filename().string()});
    const Transform t = stream->gaussians() ? gaussian::capture_transform() : Transform{};
    registry.emplace<Transform>(e, t);
    if (stream->gaussians()) {
        std::error_code ec;
        fs::path absolute = fs::absolute(path, ec);
        if (ec) absolute = path;
        registry.emplace<GaussianSource>(e, GaussianSource{absolute.lexically_normal()});
        registry.emplace<GaussianCloud>(e);
    } else {
        registry.emplace<SplatCloud>(e);
        registry.emplace<SplatMaterial>(e);
    }
    // The first cut: the root's box framed, a small budget, waited for.
    const ffd::Box box = stream->bounds();
    const glm::dmat4 model = model_matrix(&t);
    const glm::dvec3 c = glm::dvec3(model * glm::dvec4(0.5 * (box.lo + box.hi), 1.0));
    const double radius = 0.5 * glm::length(glm::dvec3(model * glm::dvec4(box.hi - box.lo, 0.0)));
    const Viewport viewport = render_viewport(registry);
    CutView view;
    view.camera = render::framing_camera(c, std::max(radius, 1e-9), viewport.aspect());
    view.viewport = viewport;
    view.model = model;
    StreamOptions first = settings.options;
    first.splat_budget = std::min(first.splat_budget, settings.first_cut_budget);
    stream->set_options(first);
    stream->update(view);
    if (Status s = stream->wait_complete(); !s) return s;
    stream->set_options(settings.options);
    write_drawn(registry, e, *stream);
    registry.emplace<StreamedCloud>(e, StreamedCloud{stream, now_s(), 0, {}});
    if (registry.count<Camera>() == 0) {
        if (stream->gaussians()) {
            gaussian::add_default_gaussian_view(registry);
        } else {
            glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
            for (int i = 0; i < 8; ++i) {
                const glm::dvec3 p((i & 4) ? box.hi.x : box.lo.x, (i & 2) ? box.hi.y : box.lo.y,
                                   (i & 1) ? box.hi.z : box.lo.z);
                const glm::dvec3 w = glm::dvec3(model * glm::dvec4(p, 1.0));
                lo = glm::min(lo, w), hi = glm::max(hi, w);
            }
            assets::add_default_view(registry, lo, hi, glm::dvec3(0.3, 0.3, 1.0));
        }
    }
    return {};
}

}  // namespace

void register_streaming_scene_hooks(SceneHooks& hooks) {
    // "0": file loaders are asked in key order, and the whole-file readers also claim these files.
    hooks.add_file_loader(
        "0.streaming", [](const fs::path& p) { return is_streamable(p); }, load_streamed,
        "a level-of-detail hierarchy (a streamed SOG's lod-meta.json, a Potree 2 "
        "metadata.json written by splatffd), streamed");
}

void enable_streaming(ecs::Registry& registry, const StreamSettings& settings) {
    registry.set_resource<StreamSettings>(settings);
    register_streaming_scene_hooks(SceneHooks::in(registry));
}

void streaming_system(ecs::Registry& registry, const FrameContext&) {
    if (registry.count<StreamedCloud>() == 0) return;
    static const StreamSettings defaults;
    const StreamSettings* settings = std::as_const(registry).try_resource<StreamSettings>();  // read only
    if (!settings) settings = &defaults;
    std::vector<ecs::Entity> streamed;
    registry.view<StreamedCloud>().each([&](ecs::Entity e, StreamedCloud&) { streamed.push_back(e); });
    CutView view;
    bool have_camera = false;
    registry.view<const Camera>().each([&](const Camera& c) {
        if (!have_camera) view.camera = c, have_camera = true;
    });
    if (!have_camera) return;
    view.viewport = render_viewport(registry);
    for (const ecs::Entity e : streamed) {
        StreamedCloud& sc = registry.get<StreamedCloud>(e);
        HierarchyStream& stream = *sc.stream;
        if (stream.options().splat_budget != settings->options.splat_budget ||
            stream.options().memory_budget != settings->options.memory_budget ||
            stream.options().tau_pixels != settings->options.tau_pixels)
            stream.set_options(settings->options);
        view.model = model_matrix(std::as_const(registry).try_get<Transform>(e));
        ffd::CloudLattices lattices;
        if (const Deformers* d = std::as_const(registry).try_get<Deformers>(e))
            lattices = ffd::cloud_lattices(registry, e, d->lattices);
        const std::uint64_t stamp = lattice_stamp(registry, e, lattices);
        const bool deforming = stamp != sc.lattice_stamp && sc.frames_seen > 0;
        sc.lattice_stamp = stamp;
        ++sc.frames_seen;
        bool changed = stream.update(view, lattices.span(), stamp);
        if (settings->wait) {
            // The caller refuses the frame (stream_status): it reports the failure itself.
            if (Status s = stream.wait_complete(); !s && sc.error.empty()) sc.error = s.error().message;
            ++sc.frames_waited;
            changed = !stream.complete();
        }
        if (!changed) continue;
        // Kept during a drag: what is drawn covers the model (a coarser level, or the parents grown, stands
        // for what is missing), so only an empty cloud is replaced.
        const std::size_t drawn = stream.gaussians() ? std::as_const(registry).get<GaussianCloud>(e).size()
                                                     : std::as_const(registry).get<SplatCloud>(e).size();
        if (!settings->wait && settings->hold_while_deforming && deforming && drawn > 0) continue;
        const double t = now_s();
        if (!settings->wait && !(stream.stats().missing_pieces == 0) &&
            t - sc.last_assemble < settings->assemble_interval_s)
            continue;
        write_drawn(registry, e, stream);
        sc.last_assemble = t;
        if (Status s = stream.error(); !s && sc.error.empty()) {
            sc.error = s.error().message;
            if (!settings->wait) std::fprintf(stderr, "splatffd: %s\n", sc.error.c_str());
        }
    }
}

Status stream_status(const ecs::Registry& registry) {
    std::string first;
    registry.view<const StreamedCloud>().each([&](const StreamedCloud& sc) {
        if (first.empty()) first = sc.error;
    });
    if (!first.empty()) return make_error(first);
    return {};
}

StreamSummary stream_summary(const ecs::Registry& registry) {
    StreamSummary out;
    registry.view<const StreamedCloud>().each([&](const StreamedCloud& sc) {
        const StreamStats s = sc.stream->stats();
        ++out.clouds;
        StreamStats& o = out.stats;
        o.resident_bytes += s.resident_bytes, o.peak_resident_bytes += s.peak_resident_bytes;
        o.resident_pieces += s.resident_pieces, o.queued += s.queued;
        o.loads += s.loads, o.evictions += s.evictions;
        o.cut_nodes += s.cut_nodes, o.wanted_pieces += s.wanted_pieces, o.missing_pieces += s.missing_pieces;
        o.wanted_splats += s.wanted_splats, o.drawn_splats += s.drawn_splats;
        o.budget_limited = o.budget_limited || s.budget_limited;
        o.memory_limited = o.memory_limited || s.memory_limited;
        o.select_ms += s.select_ms;
    });
    return out;
}

}  // namespace sffd::lod
