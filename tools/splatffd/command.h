// Subcommand registry for the `splatffd` tool. A command is a free function taking its arguments
// (argv after the subcommand name) and returning the process exit code. Each command file registers
// itself:  SFFD_COMMAND(deform, "deform a PLY file with a lattice", run_deform);
// Exit codes: 0 success, 1 failure (bad input: the message names the file and the problem),
// 2 usage error or not implemented.
#pragma once

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.h"

namespace sffd::cli {

using Args = std::span<const std::string>;
using CommandFn = int (*)(Args args);

struct Command {
    std::string name;
    std::string summary;
    CommandFn run = nullptr;
};

std::vector<Command>& commands();

// The one number parser of every command's options: the whole text must be a decimal integer in
// [min, max]. Error: "--splats: expected an integer in 1..1000000000, got '-5'".
Result<long long> parse_integer(std::string_view option, std::string_view text, long long min, long long max);
// Same for real numbers (finite, in [min, max]).
Result<double> parse_number(std::string_view option, std::string_view text, double min, double max);
// Two integers in [min, max] separated by `sep` ("0:95", "1280x720"), each through parse_integer.
Status parse_integer_pair(std::string_view option, std::string_view text, char sep, long long min,
                          long long max, long& a, long& b);

// ---- The one grammar of every command (help, usage errors, --frames, renamed options, progress) ----

// `--help` or `-h`.
bool is_help(std::string_view arg);
// `splatffd X --help`: the usage text on stdout; returns 0, the exit code of a help request.
int help(std::string_view usage_text);
// A usage error: "splatffd X: MESSAGE" and then the usage text on stderr; returns 2. An empty message
// prints the usage text alone.
int usage_error(std::string_view command, std::string_view message, std::string_view usage_text);
// Every command's error line on stderr: "splatffd X: MESSAGE" (Magnum's one form, `function(): reason`).
// A message that already starts with "splatffd " is printed as it is. Returns `code` (default 1, a
// failure: `return cli::command_error("render", st.message());`).
int command_error(std::string_view command, std::string_view message, int code = 1);
// An old option spelling that still works: one line on stderr,
// "splatffd X: --screenshot is deprecated; use --out".
void warn_deprecated(std::string_view command, std::string_view old_name, std::string_view new_name);

// --frames has one meaning in every command: "N" is the N frames 0..N-1, "A:B" the frames A..B
// (inclusive). Errors name the option: "--frames: expected N or A:B with 0 <= A <= B, got '5:2'".
struct FrameRange {
    long first = 0, last = 0;
    long count() const { return last - first + 1; }
};
Result<FrameRange> parse_frames(std::string_view text, long max_frame = 99'999'999);

// Progress lines (rewritten in place with \r) go to stderr only when it is a terminal: logs and pipes
// get the command's result lines and nothing else.
bool stderr_is_terminal();

struct Registrar {
    Registrar(const char* name, const char* summary, CommandFn run);
};

}  // namespace sffd::cli

#define SFFD_COMMAND(name, summary, fn) \
    static const ::sffd::cli::Registrar sffd_command_registrar_##name(#name, summary, fn)
