#include "tools/splatffd/deform_hierarchy.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "systems/ffd/deform.h"
#include "systems/gaussian/gaussian_deform.h"
#include "tools/splatffd/lattice_source.h"
#include "tools/splatffd/progress.h"

namespace sffd::cli {
namespace fs = std::filesystem;

namespace {

int fail(const std::string& message) {
    std::fprintf(stderr, "splatffd deform: %s\n", message.c_str());
    return 1;
}

std::vector<glm::vec3> corners(const glm::dvec3& lo, const glm::dvec3& hi) {
    std::vector<glm::vec3> c;
    for (int i = 0; i < 8; ++i)
        c.emplace_back((i & 4) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 1) ? hi.z : lo.z);
    return c;
}

std::string joined(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
    return s;
}

struct Tally {
    std::uint64_t points = 0, inverted = 0, not_finite = 0;
    std::vector<std::uint64_t> inside;
};

void report(const std::string& out, const char* what, const Tally& t, const LatticeChain& chain, double s) {
    std::fprintf(
        stderr,
        "splatffd deform: wrote %s: %llu %s deformed by %zu lattice%s %s on the CPU and the hierarchy "
        "built again from them, %.2f s (%llu inverted, %llu not finite)\n",
        out.c_str(), (unsigned long long)t.points, what, chain.lattices.size(),
        chain.lattices.size() == 1 ? "" : "s", joined(chain.names).c_str(), s, (unsigned long long)t.inverted,
        (unsigned long long)t.not_finite);
    for (std::size_t i = 0; i < t.inside.size() && i < chain.names.size(); ++i)
        if (t.inside[i] == 0 && t.points > 0)
            std::fprintf(stderr,
                         "splatffd deform: warning: lattice '%s' contains none of the %llu %s: it deformed "
                         "nothing (is it the lattice of another cloud?)\n",
                         chain.names[i].c_str(), (unsigned long long)t.points, what);
}

int deform_sog(const fs::path& in, const fs::path& out, const ChainFor& chain_for) {
    const auto t0 = std::chrono::steady_clock::now();
    auto sog = lod::open_streamed_sog(in);
    if (!sog) return fail(sog.message());
    const lod::LodNode& root = sog->nodes.front();
    auto chain = chain_for(corners(root.lo, root.hi), glm::dvec3(0.0));
    if (!chain) return fail(chain.message());
    Tally tally;
    tally.inside.assign(chain->lattices.size(), 0);
    // The finest level, unit after unit: a unit is what decodes whole.
    lod::GaussianSource source;
    source.name = in.string();
    source.scan = [&](const std::function<Status(const GaussianCloud&)>& sink) -> Status {
        tally = Tally{};
        tally.inside.assign(chain->lattices.size(), 0);
        for (std::uint32_t u = 0; u < sog->units.size(); ++u) {
            if (sog->units[u].level != 0) continue;
            auto g = lod::read_unit(*sog, u);
            if (!g) return g.error();
            for (std::size_t i = 0; i < chain->lattices.size(); ++i) {
                auto st = gaussian::deform(chain->lattices[i], *g, *g, {});
                if (!st) return make_error(chain->names[i] + ": " + st.message());
                tally.inverted += st->inverted, tally.not_finite += st->not_finite,
                    tally.inside[i] += st->inside;
            }
            gaussian::bake_sh_frames(*g);
            tally.points += g->size();
            if (Status s = sink(*g); !s) return s;
        }
        return {};
    };
    ProgressPrinter printer("deform", ProgressPrinter::mode_for(false));
    lod::LodBuildOptions o;
    o.levels = sog->levels;
    o.progress = printer.fn();
    auto built = lod::build_streamed_sog(source, out, o);
    if (!built) return fail(built.message());
    report(out.string(), "Gaussians", tally, *chain,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

int deform_potree(const fs::path& in, const fs::path& out, const ChainFor& chain_for) {
    const auto t0 = std::chrono::steady_clock::now();
    auto oc = assets::open_potree2(in);
    if (!oc) return fail(oc.message());
    if (!oc->attribute("sffd_axis_u") || !oc->attribute("sffd_axis_v") || !oc->attribute("normal"))
        return fail(in.string() +
                    ": a Potree 2 octree without splat axes (not written by splatffd): deform it into a .ply "
                    "instead (its normals and radii are estimated)");
    auto root = assets::read_potree2_nodes(*oc, {0});  // the origin and the texture
    if (!root) return fail(root.message());
    const glm::dvec3 origin = root->origin;
    auto chain = chain_for(corners(oc->lo - origin, oc->hi - origin), origin);
    if (!chain) return fail(chain.message());
    Tally tally;
    assets::SplatSource source;
    source.name = in.string();
    source.texture = root->texture;
    source.scan = [&](const std::function<Status(const SplatCloud&)>& sink) -> Status {
        tally = Tally{};
        tally.inside.assign(chain->lattices.size(), 0);
        // Every node's points at their own radii: together the finest detail.
        for (std::uint32_t n = 0; n < oc->nodes.size(); ++n) {
            if (oc->nodes[n].points == 0) continue;
            auto p = assets::read_potree2_node_points(*oc, n);
            if (!p) return p.error();
            SplatCloud& c = p->cloud;
            const auto ptr = [](std::vector<glm::vec3>& v) { return v.empty() ? nullptr : v.data(); };
            for (std::size_t i = 0; i < chain->lattices.size(); ++i) {
                const ffd::PointsIn pin{c.positions.data(), ptr(c.normals), ptr(c.axis_u),
                                        ptr(c.axis_v),      c.size(),       c.origin};
                const ffd::PointsOut pout{c.positions.data(), ptr(c.normals), ptr(c.axis_u), ptr(c.axis_v)};
                auto st = ffd::deform(chain->lattices[i], pin, pout);
                if (!st) return make_error(chain->names[i] + ": " + st.message());
                tally.inverted += st->inverted, tally.inside[i] += st->inside;
            }
            for (const glm::vec3& x : c.positions)
                if (!std::isfinite(x.x + x.y + x.z))
                    return make_error(in.string() + ": a deformed point is not finite");
            tally.points += c.size();
            if (Status s = sink(c); !s) return s;
        }
        return {};
    };
    ProgressPrinter printer("deform", ProgressPrinter::mode_for(false));
    assets::Potree2BuildOptions o;
    o.progress = printer.fn();
    auto built = assets::build_potree2(source, out, o);
    if (!built) return fail(built.message());
    report(out.string(), "splats", tally, *chain,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

}  // namespace

bool is_hierarchy_path(const std::string& path) {
    const fs::path p(path);
    return p.filename() == "lod-meta.json" || p.filename() == "metadata.json";
}

int deform_hierarchy(const std::string& in, const std::string& out, const ChainFor& chain) {
    const fs::path i(in), o(out);
    if (i.filename() != o.filename())
        return fail(out + ": a hierarchy deforms into one of its own kind (" + i.filename().string() +
                    " into " + i.filename().string() + ")");
    std::error_code ec;
    if (fs::weakly_canonical(i.parent_path(), ec) == fs::weakly_canonical(o.parent_path(), ec))
        return fail(out + ": the output folder is the input's; choose another folder");
    return i.filename() == "lod-meta.json" ? deform_sog(i, o, chain) : deform_potree(i, o, chain);
}

}  // namespace sffd::cli
