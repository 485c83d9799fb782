// Option values shared by every command (command.h): one parser, so every command reports a bad number
// the same way, naming the option (`--splats -5` used to wrap to 18446744073709551611).
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cctype>
#include <cstdlib>
#include <string>

#include "tools/splatffd/command.h"

namespace sffd::cli {

Result<long long> parse_integer(std::string_view option, std::string_view text, long long min, long long max) {
    const std::string s(text);
    const std::string range = std::to_string(min) + ".." + std::to_string(max);
    errno = 0;
    char* end = nullptr;
    const long long v = s.empty() ? 0 : std::strtoll(s.c_str(), &end, 10);
    const bool digits = !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '-' || s[0] == '+');
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

Status parse_integer_pair(std::string_view option, std::string_view text, char sep, long long min, long long max,
                          long& a, long& b) {
    const auto at = text.find(sep);
    if (at == std::string_view::npos)
        return make_error(std::string(option) + ": expected two integers separated by '" + std::string(1, sep) + "', got '" +
                          std::string(text) + "'");
    auto x = parse_integer(option, text.substr(0, at), min, max);
    if (!x) return x.error();
    auto y = parse_integer(option, text.substr(at + 1), min, max);
    if (!y) return y.error();
    a = static_cast<long>(*x);
    b = static_cast<long>(*y);
    return {};
}

}  // namespace sffd::cli
