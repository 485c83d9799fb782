// splatffd: the engine's command-line front end. See `splatffd --help`.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "runtime/core/allocator.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/core/paths.h"
#include "runtime/simd/simd.h"
#include "systems/engine/engine_frame.h"
#include "systems/gaussian/capture_up.h"
#include "tools/splatffd/command.h"

namespace sffd::cli {

std::vector<Command>& commands() {
    static std::vector<Command> all;
    return all;
}

Registrar::Registrar(const char* name, const char* summary, CommandFn run) {
    commands().push_back({name, summary, run});
}

}  // namespace sffd::cli

namespace {

// Every subcommand the tool knows, in help order; files register the implementations.
struct Known {
    const char* name;
    const char* summary;
};
constexpr Known known_commands[] = {
    {"view", "open the interactive editor on a scene"},
    {"render", "render frames of a scene to PNG/EXR (headless without a display)"},
    {"deform", "deform a PLY point cloud with a lattice"},
    {"profile", "measure frame time per system and pass"},
    {"pick", "ray-pick a control point or surface point and print it as JSON"},
    {"convert", "convert point clouds and meshes between formats, estimating normals and radii"},
    {"info", "print counts, bounds, attributes and lattices of a file"},
    {"schedule", "list the frame's systems with what each reads and writes"},
};

const sffd::cli::Command* find(const std::string& name) {
    for (const auto& c : sffd::cli::commands())
        if (c.name == name) return &c;
    return nullptr;
}

// On stdout for --help (exit 0); on stderr for a bare `splatffd` (a usage error, exit 2).
void print_help(std::FILE* to) {
    std::fprintf(
        to,
        "splatffd %s: real-time point-splat engine with free-form-deformation lattices\n\n"
        "usage: splatffd <command> [options]     (splatffd <command> --help for a command's options)\n\n"
        "commands:\n",
        SFFD_VERSION);
    for (const Known& k : known_commands) {
        const auto* c = find(k.name);
        std::fprintf(to, "  %-9s %s%s\n", k.name, c && !c->summary.empty() ? c->summary.c_str() : k.summary,
                     c ? "" : " (not implemented yet)");
    }
    for (const auto& c : sffd::cli::commands()) {
        const bool listed = std::any_of(std::begin(known_commands), std::end(known_commands),
                                        [&](const Known& k) { return c.name == k.name; });
        if (!listed) std::fprintf(to, "  %-9s %s\n", c.name.c_str(), c.summary.c_str());
    }
    std::fprintf(
        to,
        "\noptions:\n  --help     this text\n  --version  print the version and the SIMD target the CPU "
        "kernels run on\n"
        "  --paths    print where shaders, content and the cache are found\n"
        "  --allow-outside-resources  (with any command) let trusted files name textures, buffers and\n"
        "             material libraries outside their own folder (refused by default)\n"
        "  --up AXIS  (with any command) the up axis of Gaussian captures: -y (y down, as 3DGS, COLMAP,\n"
        "             SuperSplat and splat-transform store them: the default), y, z or -z; the same for "
        "every\n"
        "             Gaussian format (SPZ and KHR glTF are read into the PLY frame first); scene files "
        "keep\n"
        "             their own transform (systems/gaussian/README.md)\n"
        "\nenvironment:\n  SFFD_SIMD=<target>  pin the CPU kernels to one compiled SIMD target (see "
        "--version),\n"
        "             or scalar; a target this CPU cannot run is refused (exit 2)\n");
}

}  // namespace

int main(int argc, char** argv) {
    sffd::keep_freed_frame_memory();
    std::vector<std::string> args(argv + 1, argv + argc);
    // Global option: resources (textures, buffers, material libraries) may lie outside the folder of the
    // file that names them. Off by default: a scene from the web must not read local files.
    if (auto it = std::find(args.begin(), args.end(), "--allow-outside-resources"); it != args.end()) {
        sffd::set_allow_outside_resources(true);
        args.erase(it);
    }
    // Global option: the up axis of Gaussian captures that are loaded (systems/gaussian/capture_up.h).
    if (auto it = std::find(args.begin(), args.end(), "--up"); it != args.end()) {
        auto up = it + 1 != args.end() ? sffd::gaussian::parse_capture_up(*(it + 1))
                                       : sffd::Result<sffd::gaussian::CaptureUp>(
                                             sffd::make_error("--up: expected -y, y, z or -z after it"));
        if (!up) {
            std::fprintf(stderr, "splatffd: %s\n", up.message().c_str());
            return 2;
        }
        sffd::gaussian::set_capture_up(*up);
        args.erase(it, it + 2);
    }
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
        print_help(args.empty() ? stderr : stdout);
        return args.empty() ? 2 : 0;
    }
    // SFFD_SIMD pins the CPU kernels' target for the whole run; a name this binary or CPU cannot run is
    // refused before any work, so a farm node never renders with a target it was not asked for.
    if (sffd::Status st = sffd::simd::pin_from_environment(); !st) {
        std::fprintf(stderr, "splatffd: %s\n", st.message().c_str());
        return 2;
    }
    if (args[0] == "--version") {
        std::printf("splatffd %s\n%s\n", SFFD_VERSION, sffd::simd::version_line().c_str());
        return 0;
    }
    if (args[0] == "--paths") {  // shaders and content are found relative to the executable (paths.h)
        std::printf("shaders %s\ncontent %s\ncache %s\n", sffd::paths::shader_dir().c_str(),
                    sffd::paths::content_dir().c_str(), sffd::paths::cache_dir().c_str());
        return 0;
    }
    const std::string name = args[0];
    // SIGINT/SIGTERM remove unfinished outputs (runtime/core/atomic_file.h) and exit 130/143.
    static const std::string program = "splatffd " + name;
    sffd::install_interrupt_cleanup(program.c_str());
    if (const auto* c = find(name)) {
        // Budgets refuse declared sizes early; whatever still runs out of memory fails with a message.
        try {
            return c->run(sffd::cli::Args(args).subspan(1));
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr,
                         "splatffd %s: out of memory (the input needs more memory than is available)\n",
                         name.c_str());
            return 1;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "splatffd %s: %s\n", name.c_str(), e.what());
            return 1;
        }
    }
    for (const Known& k : known_commands)
        if (name == k.name) {
            std::fprintf(stderr, "splatffd %s: not implemented yet\n", name.c_str());
            return 2;
        }
    std::fprintf(stderr, "splatffd: unknown command '%s' (see splatffd --help)\n", name.c_str());
    return 2;
}
