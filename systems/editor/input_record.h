// Recorded editor input: mouse and keyboard events tagged with the frame they happen in. The window
// (GLFW callbacks) and the replayer (--replay FILE) both produce the same InputEvent values, and the
// editor's input system consumes them, so a replay drives exactly the code a person drives.
//
// Text format (one event per line; `#` starts a comment; blank lines ignored), documented in
// systems/editor/README.md:
//   <frame> move <x> <y>                       cursor position in window pixels, (0,0) top left
//   <frame> press <left|right|middle> [mods]   mouse button down at the current cursor position
//   <frame> release <left|right|middle> [mods]
//   <frame> scroll <dy> [mods]                 wheel notches (positive: away from the user, zoom in)
//   <frame> key <name> [mods]                  key pressed (and released) in that frame
//   <frame> text <string>                      typed text (numeric entry), rest of the line
//   <frame> set <field> <value>                what an inspector slider does, as one whole gesture:
//                                              material.specular, material.shininess,
//                                              material.base_color.r/g/b/a (material_edit.h),
//                                              proportional.*, point.*, weight.*, view.lattice
//                                              (proportional.h, point_settings.h)
// mods: any of shift ctrl alt joined by '+', e.g. `12 key z ctrl+shift`.
// Key names: a..z, 0..9, escape, enter, tab, backspace, delete, space, left, right, up, down, home,
// end, f1..f12, minus, equal, plus (the keypad's +), period, pageup, pagedown, insert, comma, slash.
// Frames must not decrease.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"

namespace sffd::editor {

enum class InputKind : std::uint8_t { move, press, release, scroll, key, text, set };
enum class MouseButton : std::uint8_t { left, right, middle };

namespace mods {
inline constexpr std::uint8_t shift = 1, ctrl = 2, alt = 4;
}

struct InputEvent {
    std::uint64_t frame = 0;
    InputKind kind = InputKind::move;
    glm::dvec2 position{0.0};                // move
    MouseButton button = MouseButton::left;  // press, release
    double scroll = 0.0;                     // scroll
    std::string key;     // key: canonical name (lower case); text: the typed string; set: the field
    double value = 0.0;  // set
    std::uint8_t modifiers = 0;

    bool operator==(const InputEvent&) const = default;
};

// Parses a recording; errors name `source` and the line: "<source>:<line>: <problem>".
Result<std::vector<InputEvent>> parse_input_recording(std::string_view text, std::string_view source);
Result<std::vector<InputEvent>> load_input_recording(const std::string& path);
// Writes events in the text format (parse_input_recording(format(...)) gives them back exactly).
std::string format_input_recording(std::span<const InputEvent> events);
bool is_known_key(std::string_view name);

// Hands out the recorded events frame by frame.
class InputReplayer {
public:
    InputReplayer() = default;
    explicit InputReplayer(std::vector<InputEvent> events) : m_events(std::move(events)) {}
    // Events recorded for `frame` (and any earlier ones not yet handed out), in file order.
    std::vector<InputEvent> take(std::uint64_t frame);
    bool finished() const { return m_next >= m_events.size(); }
    std::uint64_t last_frame() const { return m_events.empty() ? 0 : m_events.back().frame; }

private:
    std::vector<InputEvent> m_events;
    std::size_t m_next = 0;
};

}  // namespace sffd::editor
