// splatffd schedule: the engine's frame, each system in run order with the components and resources it
// declares it reads and writes (systems/engine/engine.cpp). `--markdown` prints the top README's frame
// table (tools/update_frame_table.sh writes it there).
#include <cstdio>
#include <string>

#include "systems/engine/engine.h"
#include "tools/splatffd/command.h"

namespace sffd {
namespace {

constexpr const char* kUsage =
    "usage: splatffd schedule [--markdown]\n"
    "  prints each system of the frame in run order with its declared reads and writes\n"
    "  --markdown  the README's frame table (tools/update_frame_table.sh)\n";

int run_schedule(cli::Args args) {
    bool markdown = false;
    for (const std::string& a : args) {
        if (cli::is_help(a)) return cli::help(kUsage);
        if (a == "--markdown") markdown = true;
        else return cli::usage_error("schedule", "unknown option '" + a + "'", kUsage);
    }
    if (markdown) {
        std::fputs(frame_table_markdown().c_str(), stdout);
        return 0;
    }
    const Schedule s = make_engine_schedule({.present = true, .editor = true});
    for (std::size_t p = 0; p < phase_count; ++p) {
        const auto phase = static_cast<Phase>(p);
        std::printf("%s\n", phase_name(phase));
        for (const Schedule::Entry& e : s.systems(phase)) {
            std::printf("  %s\n", e.name.c_str());
            for (const ecs::TypeRef& t : e.access.read_types())
                std::printf("    reads  %.*s\n", int(t.name.size()), t.name.data());
            for (const ecs::TypeRef& t : e.access.write_types())
                std::printf("    writes %.*s\n", int(t.name.size()), t.name.data());
        }
    }
    return 0;
}

}  // namespace
}  // namespace sffd

SFFD_COMMAND(schedule, "list the frame's systems with the components and resources each reads and writes",
             sffd::run_schedule);
