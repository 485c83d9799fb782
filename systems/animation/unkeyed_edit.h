// Un-keyed edits (UnkeyedEdit, components.h): which one a lattice carries now, for the scene file and for
// the commands that tell the user about it (saving warns, info lists it, render and deform name it).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "runtime/ecs/registry.h"
#include "systems/animation/components.h"

namespace sffd {

// True when the clip time shows the edit (the one tolerance of key times, editing.h).
bool shows_unkeyed_edit(const UnkeyedEdit& edit, double clip_time);

// The lattice's un-keyed edit as a file keeps it: the shown control points, at the shown clip time, where
// they are not the clip's pose there (an edit made since, or the held one shown); otherwise the held edit
// of another time. Nothing for a lattice without a clip, with a clip that does not fit it, or unedited.
std::optional<UnkeyedEdit> current_unkeyed_edit(const ecs::Registry& registry, ecs::Entity lattice);

struct UnkeyedEditReport {
    ecs::Entity lattice = ecs::null_entity;
    std::string name;         // the lattice's Name, or "the lattice"
    double time = 0.0;        // clip time the edit belongs to
    std::size_t points = 0;   // control points off the clip's pose at that time
    double max_offset = 0.0;  // the largest of those offsets (lattice units)
};
// Every lattice's un-keyed edit, in entity order.
std::vector<UnkeyedEditReport> unkeyed_edits(const ecs::Registry& registry);
// "un-keyed edit at clip time 0 s (48 control points off the clip's pose, up to 1.79): shown at that time
// only, the clip's pose at every other" (callers name the lattice: "'sphere.lattice' has an " + ...)
std::string describe_unkeyed_edit(const UnkeyedEditReport& report);

}  // namespace sffd
