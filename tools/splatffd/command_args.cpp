// Option values shared by every command (command.h): one parser, so every command reports a bad number
// the same way, naming the option (`--splats -5` used to wrap to 18446744073709551611).
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cctype>
#include <cstdlib>
#include <string>

#include <unistd.h>

#include "tools/splatffd/command.h"

namespace sffd::cli {

Result<long long> parse_integer(std::string_view option, std::string_view text, long long min,
                                long long max) {
    const std::string s(text);
    const std::string range = std::to_string(min) + ".." + std::to_string(max);
    errno = 0;
    char* end = nullptr;
    const long long v = s.empty() ? 0 : std::strtoll(s.c_str(), &end, 10);
    const bool digits =
        !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '-' || s[0] == '+');
    if (!digits || end != s.c_str() + s.size() || errno == ERANGE || v < min || v > max)
        return make_error(std::string(option) + ": expected an integer in " + range + ", got '" + s + "'");
    return v;
}

Result<double> parse_number(std::string_view option, std::string_view text, double min, double max) {
    const std::string s(text);
    char* end = nullptr;
    const double v = s.empty() ? std::nan("") : std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || v < min || v > max) {
        char range[96];
        std::snprintf(range, sizeof range, "%g..%g", min, max);
        return make_error(std::string(option) + ": expected a number in " + range + ", got '" + s + "'");
    }
    return v;
}

Status parse_integer_pair(std::string_view option, std::string_view text, char sep, long long min,
                          long long max, long& a, long& b) {
    const auto at = text.find(sep);
    if (at == std::string_view::npos)
        return make_error(std::string(option) + ": expected two integers separated by '" +
                          std::string(1, sep) + "', got '" + std::string(text) + "'");
    auto x = parse_integer(option, text.substr(0, at), min, max);
    if (!x) return x.error();
    auto y = parse_integer(option, text.substr(at + 1), min, max);
    if (!y) return y.error();
    a = static_cast<long>(*x);
    b = static_cast<long>(*y);
    return {};
}

bool is_help(std::string_view arg) { return arg == "--help" || arg == "-h"; }

int help(std::string_view usage_text) {
    std::fwrite(usage_text.data(), 1, usage_text.size(), stdout);
    return 0;
}

int usage_error(std::string_view command, std::string_view message, std::string_view usage_text) {
    if (!message.empty())
        std::fprintf(stderr, "splatffd %.*s: %.*s\n", int(command.size()), command.data(),
                     int(message.size()), message.data());
    std::fwrite(usage_text.data(), 1, usage_text.size(), stderr);
    return 2;
}

int command_error(std::string_view command, std::string_view message, int code) {
    if (message.substr(0, 9) == "splatffd ")
        std::fprintf(stderr, "%.*s\n", int(message.size()), message.data());
    else
        std::fprintf(stderr, "splatffd %.*s: %.*s\n", int(command.size()), command.data(),
                     int(message.size()), message.data());
    return code;
}

void warn_deprecated(std::string_view command, std::string_view old_name, std::string_view new_name) {
    std::fprintf(stderr, "splatffd %.*s: %.*s is deprecated; use %.*s\n", int(command.size()), command.data(),
                 int(old_name.size()), old_name.data(), int(new_name.size()), new_name.data());
}

Result<FrameRange> parse_frames(std::string_view text, long max_frame) {
    const auto bad = [&] {
        return make_error(
            "--frames: expected an integer N (frames 0..N-1) or a range A:B (frames A..B, 0 <= A <= B <= " +
            std::to_string(max_frame) + "), got '" + std::string(text) + "'");
    };
    FrameRange r;
    if (text.find(':') == std::string_view::npos) {
        auto n = parse_integer("--frames", text, 1, max_frame + 1);
        if (!n) return bad();
        r.first = 0, r.last = static_cast<long>(*n) - 1;
        return r;
    }
    if (!parse_integer_pair("--frames", text, ':', 0, max_frame, r.first, r.last) || r.last < r.first)
        return bad();
    return r;
}

bool stderr_is_terminal() { return isatty(STDERR_FILENO) != 0; }

}  // namespace sffd::cli
