#include "runtime/assets/formats/surface/ply.h"

#include <algorithm>
#include <charconv>
#include <cstring>

#include "runtime/assets/formats/surface/ply_detail.h"
#include "runtime/core/log.h"

// The PLY types, header parsing and printing. Reading rows is in ply_read.cpp, writing in ply_write.cpp.
namespace sffd::ply {
using namespace detail;

namespace {

std::string trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return std::string(s);
}

std::vector<std::string_view> split_words(std::string_view s) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
        std::size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r') ++j;
        if (j > i) words.push_back(s.substr(i, j - i));
        i = j;
    }
    return words;
}

}  // namespace

std::size_t type_size(Type t) { return info(t).size; }
const char* type_name(Type t) { return info(t).name; }
const char* format_name(Format f) {
    switch (f) {
        case Format::ascii: return "ascii";
        case Format::binary_little_endian: return "binary_little_endian";
        case Format::binary_big_endian: return "binary_big_endian";
    }
    return "?";
}

Result<Type> parse_type(std::string_view name) {
    for (const TypeInfo& t : kTypes)
        if (name == t.name || name == t.alias) return t.type;
    return make_error("unknown PLY type '" + std::string(name) + "'");
}

int Element::find(std::string_view property) const {
    for (std::size_t i = 0; i < properties.size(); ++i)
        if (properties[i].name == property) return static_cast<int>(i);
    return -1;
}

bool Element::has_lists() const {
    return std::any_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list; });
}

std::size_t Element::row_size() const {
    std::size_t n = 0;
    for (const Property& p : properties) n += p.is_list ? type_size(p.count_type) : type_size(p.type);
    return n;
}

int Header::find(std::string_view element) const {
    for (std::size_t i = 0; i < elements.size(); ++i)
        if (elements[i].name == element) return static_cast<int>(i);
    return -1;
}

std::string Header::to_string() const {
    std::string s = "ply\nformat ";
    s += format_name(format);
    s += " 1.0\n";
    for (const std::string& c : comments) {
        if (c.rfind("obj_info ", 0) == 0) s += c + "\n";
        else s += "comment " + c + "\n";
    }
    for (const Element& e : elements) {
        s += "element " + e.name + " " + std::to_string(e.count) + "\n";
        for (const Property& p : e.properties) {
            if (p.is_list)
                s += std::string("property list ") + type_name(p.count_type) + " " + type_name(p.type) + " " +
                     p.name + "\n";
            else s += std::string("property ") + type_name(p.type) + " " + p.name + "\n";
        }
    }
    s += "end_header\n";
    return s;
}

void Chunk::clear() {
    rows = 0;
    for (Column& c : columns) {
        c.values.clear();
        c.offsets.clear();
    }
}

void Chunk::reset(const Element& e) {
    element = e;
    rows = 0;
    columns.assign(e.properties.size(), Column{});
    for (std::size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].is_list) columns[i].offsets.push_back(0);
}

Result<Header> parse_header(std::string_view text, const std::string& name, std::size_t& header_bytes) {
    auto fail = [&](const std::string& why) { return make_error(name + ": " + why); };
    Header h;
    std::size_t pos = 0;
    int line_no = 0;
    bool have_format = false;
    constexpr int kMaxUnknownWarnings = 5;
    int unknown_lines = 0;
    auto next_line = [&](std::string_view& line) {
        if (pos >= text.size()) return false;
        const std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos) return false;  // a header line must end with a newline
        line = text.substr(pos, nl - pos);
        pos = nl + 1;
        ++line_no;
        return true;
    };
    std::string_view line;
    if (!next_line(line) || trim(line) != "ply")
        return fail(text.substr(0, 3) == "ply" ? "truncated PLY header"
                                               : "not a PLY file (bad magic: expected 'ply')");
    while (true) {
        if (!next_line(line)) return fail("truncated PLY header (no end_header)");
        const auto words = split_words(line);
        const std::string where = "header line " + std::to_string(line_no) + ": ";
        if (words.empty()) continue;
        const std::string_view key = words[0];
        if (key == "end_header") break;
        if (key == "comment") {
            const std::size_t at = line.find("comment") + 7;
            h.comments.push_back(trim(line.substr(std::min(line.size(), at + 1))));
        } else if (key == "obj_info") {
            h.comments.push_back("obj_info " +
                                 trim(line.substr(std::min(line.size(), line.find("obj_info") + 9))));
        } else if (key == "format") {
            if (have_format) return fail(where + "duplicate format line");
            if (words.size() != 3) return fail(where + "expected 'format <type> 1.0'");
            if (words[1] == "ascii") h.format = Format::ascii;
            else if (words[1] == "binary_little_endian") h.format = Format::binary_little_endian;
            else if (words[1] == "binary_big_endian") h.format = Format::binary_big_endian;
            else return fail(where + "unknown format '" + std::string(words[1]) + "'");
            if (words[2] != "1.0" && words[2] != "1")
                return fail(where + "unsupported PLY version '" + std::string(words[2]) + "'");
            have_format = true;
        } else if (key == "element") {
            if (words.size() != 3) return fail(where + "expected 'element <name> <count>'");
            Element e;
            e.name = std::string(words[1]);
            if (h.find(e.name) >= 0) return fail(where + "duplicate element '" + e.name + "'");
            const auto c = words[2];
            auto [ptr, ec] = std::from_chars(c.data(), c.data() + c.size(), e.count);
            if (ec != std::errc() || ptr != c.data() + c.size())
                return fail(where + "bad count '" + std::string(c) + "' for element '" + e.name + "'");
            h.elements.push_back(std::move(e));
        } else if (key == "property") {
            if (h.elements.empty()) return fail(where + "property before any element");
            Element& e = h.elements.back();
            Property p;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5)
                    return fail(where + "expected 'property list <count type> <type> <name>'");
                auto ct = parse_type(words[2]);
                if (!ct) return fail(where + ct.message());
                auto vt = parse_type(words[3]);
                if (!vt) return fail(where + vt.message());
                if (!is_integer(*ct)) return fail(where + "list count type must be an integer type");
                p.is_list = true;
                p.count_type = *ct;
                p.type = *vt;
                p.name = std::string(words[4]);
            } else {
                if (words.size() != 3) return fail(where + "expected 'property <type> <name>'");
                auto t = parse_type(words[1]);
                if (!t) return fail(where + t.message());
                p.type = *t;
                p.name = std::string(words[2]);
            }
            if (e.find(p.name) >= 0)
                return fail(where + "duplicate property '" + p.name + "' in element '" + e.name + "'");
            e.properties.push_back(std::move(p));
        } else {
            // Writers add their own lines (Blender 2.4's "Created by Blender3D ..." in assimp's Wuson.ply);
            // readers such as rply and assimp skip them. Skipped with a warning, a few at most, so a
            // hostile header of junk lines cannot flood the log (it still needs an end_header).
            if (++unknown_lines <= kMaxUnknownWarnings)
                log::warn(name, ": ", where, "unknown keyword '", std::string(key).substr(0, 64),
                          "', line ignored");
            else if (unknown_lines == kMaxUnknownWarnings + 1)
                log::warn(name, ": further unknown header lines ignored without a warning");
        }
    }
    if (!have_format) return fail("PLY header has no format line");
    for (const Element& e : h.elements)
        if (e.count > 0 && e.properties.empty())
            return fail("element '" + e.name + "' has rows but no properties");
    header_bytes = pos;
    return h;
}

}  // namespace sffd::ply
