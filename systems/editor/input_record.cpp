#include "systems/editor/input_record.h"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "runtime/core/file_io.h"
#include "systems/editor/material_edit.h"
#include "systems/editor/point_settings.h"
#include "systems/editor/proportional.h"

namespace sffd::editor {

namespace {

constexpr std::array<std::string_view, 21> named_keys = {
    "escape", "enter", "tab",   "backspace", "delete", "space",    "left",   "right", "up",    "down", "home",
    "end",    "minus", "equal", "period",    "pageup", "pagedown", "insert", "comma", "slash", "plus"};

std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
}

bool parse_double(std::string_view word, double& out) {
    const auto [ptr, ec] = std::from_chars(word.data(), word.data() + word.size(), out);
    return ec == std::errc() && ptr == word.data() + word.size() && std::isfinite(out);
}

bool parse_mods(std::string_view word, std::uint8_t& out) {
    out = 0;
    while (!word.empty()) {
        const std::size_t plus = word.find('+');
        const std::string_view part = word.substr(0, plus);
        if (part == "shift") out |= mods::shift;
        else if (part == "ctrl") out |= mods::ctrl;
        else if (part == "alt") out |= mods::alt;
        else return false;
        if (plus == std::string_view::npos) break;
        word.remove_prefix(plus + 1);
        if (word.empty()) return false;
    }
    return true;
}

std::string mods_string(std::uint8_t m) {
    std::string s;
    auto add = [&](const char* name) {
        s += s.empty() ? "" : "+";
        s += name;
    };
    if (m & mods::shift) add("shift");
    if (m & mods::ctrl) add("ctrl");
    if (m & mods::alt) add("alt");
    return s;
}

const char* button_name(MouseButton b) {
    switch (b) {
        case MouseButton::left: return "left";
        case MouseButton::right: return "right";
        case MouseButton::middle: return "middle";
    }
    return "left";
}

std::string format_number(double v) {
    char buf[64];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact round trip
    return ec == std::errc() ? std::string(buf, ptr) : std::string("0");
}

}  // namespace

bool is_known_key(std::string_view name) {
    if (name.size() == 1 && ((name[0] >= 'a' && name[0] <= 'z') || (name[0] >= '0' && name[0] <= '9')))
        return true;
    if (name.size() >= 2 && name.size() <= 3 && name[0] == 'f') {
        int n = 0;
        const auto [ptr, ec] = std::from_chars(name.data() + 1, name.data() + name.size(), n);
        return ec == std::errc() && ptr == name.data() + name.size() && n >= 1 && n <= 12;
    }
    for (auto k : named_keys)
        if (k == name) return true;
    return false;
}

Result<std::vector<InputEvent>> parse_input_recording(std::string_view text, std::string_view source) {
    std::vector<InputEvent> events;
    std::size_t line_no = 0;
    std::uint64_t last_frame = 0;
    while (!text.empty()) {
        const std::size_t eol = text.find('\n');
        std::string_view line = text.substr(0, eol);
        text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
        ++line_no;
        const auto fail = [&](const std::string& problem) {
            return make_error(std::string(source) + ":" + std::to_string(line_no) + ": " + problem);
        };
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos)
            line = line.substr(0, hash);
        const std::vector<std::string_view> w = split_words(line);
        if (w.empty()) continue;
        if (w.size() < 2) return fail("expected '<frame> <event> ...'");

        InputEvent e;
        {
            const auto [ptr, ec] = std::from_chars(w[0].data(), w[0].data() + w[0].size(), e.frame);
            if (ec != std::errc() || ptr != w[0].data() + w[0].size())
                return fail("bad frame number '" + std::string(w[0]) + "'");
        }
        if (e.frame < last_frame)
            return fail("frame " + std::to_string(e.frame) + " is before frame " +
                        std::to_string(last_frame));
        last_frame = e.frame;

        const std::string_view kind = w[1];
        std::size_t mods_at = 0;  // index of the optional modifier word
        if (kind == "move") {
            if (w.size() != 4) return fail("'move' takes x y");
            if (!parse_double(w[2], e.position.x) || !parse_double(w[3], e.position.y))
                return fail("bad cursor position");
            e.kind = InputKind::move;
        } else if (kind == "press" || kind == "release") {
            e.kind = kind == "press" ? InputKind::press : InputKind::release;
            if (w.size() < 3 || w.size() > 4)
                return fail("'" + std::string(kind) + "' takes a button and optional mods");
            if (w[2] == "left") e.button = MouseButton::left;
            else if (w[2] == "right") e.button = MouseButton::right;
            else if (w[2] == "middle") e.button = MouseButton::middle;
            else return fail("unknown mouse button '" + std::string(w[2]) + "' (left, right, middle)");
            mods_at = 3;
        } else if (kind == "scroll") {
            e.kind = InputKind::scroll;
            if (w.size() < 3 || w.size() > 4) return fail("'scroll' takes dy and optional mods");
            if (!parse_double(w[2], e.scroll)) return fail("bad scroll amount '" + std::string(w[2]) + "'");
            mods_at = 3;
        } else if (kind == "key") {
            e.kind = InputKind::key;
            if (w.size() < 3 || w.size() > 4) return fail("'key' takes a key name and optional mods");
            if (!is_known_key(w[2])) return fail("unknown key '" + std::string(w[2]) + "'");
            e.key = std::string(w[2]);
            mods_at = 3;
        } else if (kind == "set") {
            e.kind = InputKind::set;
            if (w.size() != 4) return fail("'set' takes a field and a value");
            if (!material_field(w[2]) && !is_proportional_field(w[2]) && !is_point_field(w[2]))
                return fail(
                    "unknown field '" + std::string(w[2]) + "' (" + std::string(material_field_names()) +
                    ", proportional.enabled, proportional.radius, proportional.falloff, point.mode, "
                    "point.brush_radius, point.sphere_radius, point.colour_tolerance, "
                    "point.grow_distance, weight.radius, weight.falloff, view.lattice, view.weights)");
            if (w[2] == "point.mode" || w[2] == "weight.falloff") {
                const std::optional<double> v = parse_point_field_value(w[2], w[3]);
                if (!v)
                    return fail("unknown " + std::string(w[2] == "point.mode" ? "mode" : "falloff") + " '" +
                                std::string(w[3]) +
                                (w[2] == "point.mode" ? "' (set, add, remove, intersect)"
                                                      : "' (smooth, sphere, linear, sharp, constant)"));
                e.value = *v;
            } else if (w[2] == "proportional.falloff") {
                const std::optional<Falloff> f = falloff_from_name(w[3]);
                if (!f)
                    return fail("unknown falloff '" + std::string(w[3]) +
                                "' (smooth, sphere, linear, sharp, constant)");
                e.value = double(int(*f));
            } else if (!parse_double(w[3], e.value)) {
                return fail("bad value '" + std::string(w[3]) + "'");
            }
            e.key = std::string(w[2]);
        } else if (kind == "text") {
            e.kind = InputKind::text;
            // Rest of the line after the word "text", one separating space dropped.
            const std::size_t at = static_cast<std::size_t>(w[1].data() - line.data()) + 4;
            std::string_view rest = line.substr(at);
            if (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
            while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\r')) rest.remove_suffix(1);
            if (rest.empty()) return fail("'text' needs a string");
            e.key = std::string(rest);
        } else {
            return fail("unknown event '" + std::string(kind) +
                        "' (move, press, release, scroll, key, text, set)");
        }
        if (mods_at && w.size() > mods_at && !parse_mods(w[mods_at], e.modifiers))
            return fail("bad modifiers '" + std::string(w[mods_at]) + "' (shift, ctrl, alt joined by +)");
        events.push_back(std::move(e));
    }
    return events;
}

Result<std::vector<InputEvent>> load_input_recording(const std::string& path) {
    auto text = read_file(path, kMaxTextFileBytes);  // runtime/core/file_io.h: regular files only
    if (!text) return make_error(path + ": cannot open input recording (" + text.message() + ")");
    return parse_input_recording(*text, path);
}

std::string format_input_recording(std::span<const InputEvent> events) {
    std::string out = "# splatffd input recording: <frame> <event> ... (systems/editor/README.md)\n";
    for (const InputEvent& e : events) {
        out += std::to_string(e.frame);
        std::string m = mods_string(e.modifiers);
        switch (e.kind) {
            case InputKind::move:
                out += " move " + format_number(e.position.x) + " " + format_number(e.position.y);
                m.clear();
                break;
            case InputKind::press: out += std::string(" press ") + button_name(e.button); break;
            case InputKind::release: out += std::string(" release ") + button_name(e.button); break;
            case InputKind::scroll: out += " scroll " + format_number(e.scroll); break;
            case InputKind::key: out += " key " + e.key; break;
            case InputKind::text:
                out += " text " + e.key;
                m.clear();
                break;
            case InputKind::set:
                out += " set " + e.key + " " +
                       (e.key == "proportional.falloff" ? std::string(falloff_name(Falloff(int(e.value))))
                        : !point_field_word(e.key, e.value).empty()
                            ? std::string(point_field_word(e.key, e.value))
                            : format_number(e.value));
                m.clear();
                break;
        }
        if (!m.empty()) out += " " + m;
        out += "\n";
    }
    return out;
}

std::vector<InputEvent> InputReplayer::take(std::uint64_t frame) {
    std::vector<InputEvent> out;
    while (m_next < m_events.size() && m_events[m_next].frame <= frame) out.push_back(m_events[m_next++]);
    return out;
}

}  // namespace sffd::editor
