// Compact undo steps for the components whose edits touch a few entries of a long array: a lattice drag
// moves some control points of up to 11³ (a before/after snapshot of an 11³ lattice is 128 KB; the
// points of eight moved ones are under 0.5 KB), and an un-keyed edit holds the whole pose. A change whose
// frame is unchanged (the lattice box, divisions, basis and array lengths) keeps only the entries that
// differ, compared bit for bit so undo and redo stay exact (-0.0, NaN payloads). Any other change keeps
// whole snapshots (ComponentChange in undo_stack.h).
//
// SparseUndo<C> is the hook: `diff` returns the delta, or nothing when the frame changed; `apply` writes
// its before (forward = false) or after values into a component that is in the other state (the stack is
// linear, so an undo always finds the step's after state); `bytes` is the delta's memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/animation/components.h"
#include "systems/picking/components.h"

namespace sffd::editor {

// The entries of two equally long arrays that differ bit for bit.
struct PointsDelta {
    std::vector<std::uint32_t> index;
    std::vector<glm::dvec3> before;
    std::vector<glm::dvec3> after;

    static PointsDelta between(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
        PointsDelta d;
        for (std::size_t i = 0; i < a.size(); ++i)
            if (std::memcmp(&a[i], &b[i], sizeof(glm::dvec3)) != 0) {
                d.index.push_back(std::uint32_t(i));
                d.before.push_back(a[i]);
                d.after.push_back(b[i]);
            }
        return d;
    }
    void apply(std::vector<glm::dvec3>& points, bool forward) const {
        const std::vector<glm::dvec3>& values = forward ? after : before;
        for (std::size_t k = 0; k < index.size(); ++k)
            if (index[k] < points.size()) points[index[k]] = values[k];
    }
    bool empty() const { return index.empty(); }
    std::size_t bytes() const {
        return index.capacity() * sizeof(std::uint32_t) +
               (before.capacity() + after.capacity()) * sizeof(glm::dvec3);
    }
};

template <class C>
struct SparseUndo {
    static constexpr bool enabled = false;
    struct Delta {};  // never made: every change of C keeps whole snapshots
    static bool empty(const Delta&) { return true; }
    static std::size_t bytes(const Delta&) { return 0; }
};

// Heap memory of a whole snapshot: the arrays of the components the editor records (others own none or
// little: their size is counted by the command).
inline std::size_t undo_heap_bytes(const Lattice& l) {
    return (l.rest.capacity() + l.current.capacity()) * sizeof(glm::dvec3);
}
inline std::size_t undo_heap_bytes(const UnkeyedEdit& u) { return u.points.capacity() * sizeof(glm::dvec3); }
inline std::size_t undo_heap_bytes(const AnimationClip& c) {
    std::size_t n = c.name.capacity() + c.tracks.capacity() * sizeof(AnimationTrack);
    for (const AnimationTrack& t : c.tracks)
        n += t.name.capacity() + t.points.capacity() * sizeof(std::uint32_t) +
             t.keys.capacity() * sizeof(Keyframe);
    return n;
}
inline std::size_t undo_heap_bytes(const SplatCloud& c) {
    return c.positions.capacity() * sizeof(glm::vec3) + c.normals.capacity() * sizeof(glm::vec3) +
           c.axis_u.capacity() * sizeof(glm::vec3) + c.axis_v.capacity() * sizeof(glm::vec3) +
           c.colors.capacity() * sizeof(std::uint32_t) + c.uvs.capacity() * sizeof(glm::vec2) +
           c.uv_axes.capacity() * sizeof(glm::vec4);
}
inline std::size_t undo_heap_bytes(const picking::LatticeSelection& s) {
    return s.indices.capacity() * sizeof(std::uint32_t);
}
inline std::size_t undo_heap_bytes(const Deformers& d) { return d.lattices.capacity() * sizeof(ecs::Entity); }
inline std::size_t undo_heap_bytes(const Name& n) { return n.value.capacity(); }
inline std::size_t undo_heap_bytes(const AnimationState& s) {
    return s.last_pose.capacity() * sizeof(glm::dvec3) + s.error.capacity();
}
template <class C>
std::size_t undo_heap_bytes(const C&) {
    return 0;
}

template <>
struct SparseUndo<Lattice> {
    static constexpr bool enabled = true;
    struct Delta {
        PointsDelta rest, current;
    };
    static std::optional<Delta> diff(const Lattice& a, const Lattice& b) {
        const bool same_frame = a.origin == b.origin && a.axes == b.axes && a.divisions == b.divisions &&
                                a.basis == b.basis && a.rest.size() == b.rest.size() &&
                                a.current.size() == b.current.size();
        if (!same_frame) return std::nullopt;
        Delta d;
        d.rest = PointsDelta::between(a.rest, b.rest);
        d.current = PointsDelta::between(a.current, b.current);
        d.rest.index.shrink_to_fit(), d.rest.before.shrink_to_fit(), d.rest.after.shrink_to_fit();
        d.current.index.shrink_to_fit(), d.current.before.shrink_to_fit(), d.current.after.shrink_to_fit();
        return d;
    }
    static void apply(Lattice& l, const Delta& d, bool forward) {
        d.rest.apply(l.rest, forward);
        d.current.apply(l.current, forward);
    }
    static bool empty(const Delta& d) { return d.rest.empty() && d.current.empty(); }
    static std::size_t bytes(const Delta& d) { return d.rest.bytes() + d.current.bytes(); }
};

template <>
struct SparseUndo<UnkeyedEdit> {
    static constexpr bool enabled = true;
    struct Delta {
        double time_before = 0.0, time_after = 0.0;
        PointsDelta points;
    };
    static std::optional<Delta> diff(const UnkeyedEdit& a, const UnkeyedEdit& b) {
        if (a.points.size() != b.points.size()) return std::nullopt;
        Delta d{a.time, b.time, PointsDelta::between(a.points, b.points)};
        d.points.index.shrink_to_fit(), d.points.before.shrink_to_fit(), d.points.after.shrink_to_fit();
        return d;
    }
    static void apply(UnkeyedEdit& u, const Delta& d, bool forward) {
        u.time = forward ? d.time_after : d.time_before;
        d.points.apply(u.points, forward);
    }
    static bool empty(const Delta& d) {
        return std::memcmp(&d.time_before, &d.time_after, sizeof(double)) == 0 && d.points.empty();
    }
    static std::size_t bytes(const Delta& d) { return d.points.bytes(); }
};

}  // namespace sffd::editor
