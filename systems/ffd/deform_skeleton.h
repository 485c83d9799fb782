// The deformation phase's one skeleton, shared by both kinds: ffd_system (surface splats, ffd_system.cpp)
// and gaussian_deform_system (3D Gaussians, systems/gaussian/gaussian_system.cpp) are this loop with a
// kind-trait struct. Per cloud with Deformers:
//   1. its inputs (deform_inputs.h) and its page record, brought in step (refresh_point_pages: the phase
//      owns the pages' rest boxes);
//   2. the one staleness rule (deform_staleness.h): nothing (skip), some pages, or everything. Page-wise
//      redo needs an output of the same path to build on (the CPU path its own arrays, the GPU path its
//      own resident output, with the same backend and kind options); budgeted previews always redo
//      everything;
//   3. the output component stamped, its version bumped, the lattices prepared in the cloud's frame
//      (lattice_frame.h), then the kind's preview, GPU or CPU path.
// The kind (Kind) provides:
//   using Cloud, Output, Resident, Stats;
//   static const char* name;                       // for messages
//   static std::span<const PointColumn> reads();
//   static Resident* resident(reg, e, cloud, version, have_gl)
//   static bool options_match(const Output&, const Settings&)   // backend and the kind's own options
//   static std::uint32_t budget(reg, cloud, resident, settings)  // preview budget, 0 = none
//   static void begin(reg, e, Output&, cloud, framed, settings, stats)  // options seen, bounds
//   static void preview(...), static bool gpu(..., plan, ...) (false: fall back to the CPU),
//   static std::size_t cpu(reg, e, Output&, cloud, framed, plan, resident, settings, stats): pages redone
// `Settings` is the kind's per-frame choice (backend, SH modes), made once per frame by the kind.
#pragma once

#include <utility>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/deform_staleness.h"
#include "systems/ffd/lattice_frame.h"

namespace sffd::ffd {

template <class Kind, class Settings>
void run_deformation(ecs::Registry& reg, const Settings& settings, typename Kind::Stats& stats) {
    using Cloud = typename Kind::Cloud;
    using Output = typename Kind::Output;
    // Collect first: emplacing outputs and page records while iterating is a structural change.
    std::vector<ecs::Entity> clouds;
    reg.view<const Cloud, const Deformers>().each(
        [&](ecs::Entity e, const Cloud&, const Deformers&) { clouds.push_back(e); });
    for (ecs::Entity e : clouds) {
        const PointPages& pages = *refresh_point_pages(reg, e);
        const Cloud& cloud = std::as_const(reg).template get<Cloud>(e);  // read only
        const DeformInputs inputs = deform_inputs<Cloud>(reg, e);
        auto* resident = Kind::resident(reg, e, cloud, inputs.stamps.cloud, settings);
        const std::uint32_t budget = Kind::budget(reg, cloud, resident, settings);
        const Output* seen = reg.try_get<Output>(e);
        // A resident cloud at rest has no deformed data yet (its entry is new, or its rest was re-uploaded):
        // it needs an output even when nothing moved. A full output serves every frame; a preview one only
        // preview frames.
        const bool same_options = seen && Kind::options_match(*seen, settings);
        if (same_options && seen->seen == inputs.stamps && (!resident || resident->is_deformed()) &&
            (!seen->preview || budget > 0))
            continue;  // nothing this cloud depends on moved

        if (!seen) reg.emplace<Output>(e);
        Output& out = reg.template patch<Output>(e);
        const CloudLattices framed = cloud_lattices(reg, e, inputs.lattices);
        // The one staleness rule, where there is a page-wise output to build on.
        RedoPlan plan;
        if (same_options && !out.preview && budget == 0) {
            const PagePoints rest{cloud.origin, cloud.positions};
            plan =
                plan_redeform(out.seen, out.paged, inputs.stamps, pages, framed.span(), Kind::reads(), &rest);
        }
        out.seen = inputs.stamps;
        ++out.version;
        Kind::begin(reg, e, out, cloud, framed, settings, stats);

        out.preview = budget > 0;
        if (budget > 0) {
            out.paged = {};
            Kind::preview(reg, e, out, cloud, framed, budget, *resident, settings, stats);
            continue;
        }
        if (Kind::gpu(reg, e, out, cloud, framed, inputs, plan, resident, settings, stats)) {
            // The next plan builds on this output: the GPU path redoes its pages only while its own last
            // output is what is resident (state deformed_gpu), the CPU path only on its own arrays.
            record_pages(out.paged, pages, framed.span());
            continue;
        }
        if (plan.what == Redo::everything) {
            plan.pages.resize(page_count(pages.points));
            for (std::size_t p = 0; p < plan.pages.size(); ++p) plan.pages[p] = std::uint32_t(p);
        }
        const std::size_t redone = Kind::cpu(reg, e, out, cloud, framed, plan, resident, settings, stats);
        record_pages(out.paged, pages, framed.span());
        stats.pages_redeformed += redone;
        stats.last_pages = {redone, page_count(pages.points)};
    }
}

}  // namespace sffd::ffd
