#include "tools/splatffd/unkeyed_note.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "systems/animation/components.h"
#include "systems/animation/unkeyed_edit.h"

namespace sffd::cli {

void note_unkeyed_edits(std::string_view command, const ecs::Registry& registry, std::optional<double> fps) {
    for (const UnkeyedEditReport& edit : unkeyed_edits(registry)) {
        std::string tail;
        char text[160];
        if (fps) {
            const double frame = edit.time * *fps;
            if (std::abs(frame - std::round(frame)) <= 1e-6 * std::max(1.0, frame))
                std::snprintf(text, sizeof text, " (frame %.0f at %g fps)", std::round(frame), *fps);
            else
                std::snprintf(text, sizeof text,
                              " (between frames %.0f and %.0f at %g fps: no frame shows it)",
                              std::floor(frame), std::floor(frame) + 1, *fps);
            tail = text;
        } else {
            const AnimationState* state = registry.try_get<AnimationState>(edit.lattice);
            const double saved = state ? state->time : 0.0;
            const bool uses_edit = shows_unkeyed_edit(UnkeyedEdit{edit.time, {}}, saved);
            std::snprintf(text, sizeof text, "; the scene was saved at clip time %.6g s, so this uses %s",
                          saved, uses_edit ? "the edit" : "the clip's pose there");
            tail = text;
        }
        std::fprintf(stderr, "splatffd %.*s: note: %s has an %s%s\n", int(command.size()), command.data(),
                     edit.name.c_str(), describe_unkeyed_edit(edit).c_str(), tail.c_str());
    }
}

}  // namespace sffd::cli
