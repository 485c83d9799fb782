#include "tools/splatffd/stream_options.h"

#include <cstdio>

namespace sffd::cli {

const char* const kStreamUsage =
    "  level-of-detail hierarchies (DIR/lod-meta.json, a Potree 2 DIR/metadata.json of splatffd's) stream:\n"
    "  --splat-budget N   splats a frame's cut may draw (view, profile: 1M; render: no limit)\n"
    "  --memory-budget MB pieces held in memory (default 1024); a cut that needs more is drawn as far\n"
    "                     as it fits (render refuses it)\n"
    "  --lod-error PX     refine while a node's detail projects larger than PX pixels (view, profile:\n"
    "                     1; render: 0, every node in view at full detail)\n"
    "  --full-detail      read the whole finest level instead of streaming\n";

StreamCli interactive_stream_defaults() {
    StreamCli c;
    c.settings.options.splat_budget = 1'000'000;
    c.settings.options.memory_budget = std::uint64_t(1024) << 20;
    c.settings.options.tau_pixels = 1.0;
    return c;
}

StreamCli final_render_stream_defaults() {
    StreamCli c = interactive_stream_defaults();
    c.settings.options.splat_budget = std::uint64_t(1) << 40;
    c.settings.options.tau_pixels = 0.0;
    c.settings.options.rebound_interval_s = 0.0;  // each frame's cut on its own lattices
    c.settings.wait = true;
    return c;
}

int parse_stream_option(std::string_view command, const Args& args, std::size_t& i, StreamCli& out) {
    const std::string& a = args[i];
    if (a == "--full-detail") {
        out.full_detail = true;
        return 1;
    }
    if (a != "--splat-budget" && a != "--memory-budget" && a != "--lod-error") return 0;
    if (i + 1 >= args.size()) {
        std::fprintf(stderr, "splatffd %.*s: %s needs a value\n", int(command.size()), command.data(),
                     a.c_str());
        return -1;
    }
    const std::string& v = args[++i];
    if (a == "--lod-error") {
        auto x = parse_number(a, v, 0.0, 1e6);
        if (!x) {
            std::fprintf(stderr, "splatffd %.*s: %s\n", int(command.size()), command.data(),
                         x.message().c_str());
            return -1;
        }
        out.settings.options.tau_pixels = *x;
        return 1;
    }
    auto n = parse_integer(a, v, 1, a == "--splat-budget" ? (1ll << 40) : (1ll << 24));
    if (!n) {
        std::fprintf(stderr, "splatffd %.*s: %s\n", int(command.size()), command.data(), n.message().c_str());
        return -1;
    }
    if (a == "--splat-budget") out.settings.options.splat_budget = std::uint64_t(*n);
    else out.settings.options.memory_budget = std::uint64_t(*n) << 20;
    return 1;
}

void apply_stream_options(ecs::Registry& registry, const StreamCli& options) {
    if (!options.full_detail) lod::enable_streaming(registry, options.settings);
}

}  // namespace sffd::cli
