// Text that goes into JSON output (pick results, manifests, scene files) must be valid UTF-8: file names
// and glTF strings are arbitrary bytes on Linux, and one stray 0xFF byte makes the whole document
// unreadable to every JSON parser (nlohmann's dump() even throws on it). Invalid sequences are replaced
// by U+FFFD, as nlohmann's error_handler_t::replace does, so the two agree.
#pragma once

#include <string>
#include <string_view>

namespace sffd {

// `text` with every byte that is not part of a well-formed UTF-8 sequence (overlong forms, surrogates,
// code points above U+10FFFF, truncated sequences) replaced by U+FFFD.
std::string valid_utf8(std::string_view text);

// `text` as a JSON string literal, quotes included: valid UTF-8, with `"`, `\` and control characters
// escaped.
std::string json_quote(std::string_view text);

}  // namespace sffd
