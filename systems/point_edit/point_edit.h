// Operations on the points of a cloud (SplatCloud or GaussianCloud entity) through its PointFlags
// (runtime/scene/point_columns.h): hide the selection, unhide all, delete the selection, duplicate and
// separate the selection into a new entity. Pure functions over the registry, no UI; each returns a step
// (PointEditStep) that undo() and redo() replay exactly, and whose memory is proportional to what changed.
//
// What "selected" means for every operation: kPointSelected set and neither kPointHidden nor kPointDeleted
// (a gone point is never operated on). A cloud without PointFlags, or with empty bits, has no selection.
//
//   hide_selected     the selected points become hidden and leave the selection (SuperSplat: a hidden
//                     splat is not selectable either)
//   unhide_all        every hidden point that is not deleted becomes visible (not selected)
//   delete_selected   the selected points become deleted and leave the selection. The cloud's arrays keep
//                     them, so undo is a bit flip; saving and export drop them
//   duplicate_selected  a NEW entity of the same kind holding copies of the selected points; the originals
//                     stay as they are (SuperSplat's "Duplicate Selection" makes a new splat too)
//   separate_selected a NEW entity of the same kind holding the selected points; the originals are marked
//                     deleted (and leave the selection)
//
// The new entity of duplicate/separate gets: the cloud with every authored column of those points in
// source order (surface: positions, normals, axes, colours, uvs, uv axes, the texture and the origin;
// Gaussians: positions, scales, rotations, opacities, SH at the source's degree, SH frames if any, the
// origin), the optional PointWeights of those points, the source's Transform and SplatMaterial, and
// Name "<source name>.part" (separate) or "<source name>.copy" (duplicate). It has no PointFlags (nothing
// selected, hidden or deleted), no Deformers (it is free to get its own lattice) and none of the source's
// derived or exact-surface components (ExactSphere/ExactMesh describe the whole source, not the part).
//
// Change stamps: every flag edit goes through registry.patch<PointFlags>() (its stamp moves) and
// mark_points_changed() on the pages it touched (PointColumn::selection / visibility); a new entity is
// mark_cloud_replaced(). The cloud's arrays are never written by these operations, so nothing is re-deformed.
//
// Undo and redo. The steps are linear like the editor's undo stack: undo() is called on the state the
// step left, redo() on the state before it. A step stores the points it changed (PointSet: per touched
// page, sorted 16-bit offsets or a 65,536-bit mask, whichever is smaller: at most 2 bytes a point plus a
// constant per page) and the bits it flipped; undo and redo flip them back and forth, so the flags are
// bit-identical after any number of round trips. Undo of duplicate/separate destroys the new entity;
// redo re-extracts it from the source points, which are still in the source cloud (deletion keeps them),
// into a new entity (a new id: redo returns it and stores it in `created`; an editor that keeps an entity
// map maps the old id to it). `cloud` and `created` are plain fields: a caller whose entities were
// re-created by other steps rewrites them before calling undo/redo.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/ecs/registry.h"

namespace sffd::point_edit {

// A set of point indices of one cloud, stored by page (runtime/scene/point_pages.h: 65,536 points a page):
// each touched page keeps either its points' sorted 16-bit offsets (2 bytes a point) or a 65,536-bit mask
// (8 KB), whichever is smaller. bytes() <= 2 * size() + kPageOverhead * pages() + sizeof(PointSet).
class PointSet {
public:
    // Bytes of a touched page's record besides its offsets or mask.
    static constexpr std::size_t kPageOverhead = 12;

    // Indices i < bits.size() with (bits[i] & mask) == want.
    static PointSet where(const std::vector<std::uint8_t>& bits, std::uint8_t mask, std::uint8_t want);

    std::size_t size() const { return m_count; }  // points in the set
    bool empty() const { return m_count == 0; }
    std::size_t pages() const { return m_pages.size(); }
    std::size_t bytes() const;  // heap and object memory held

    // Calls fn(index) for every index in ascending order.
    template <class Fn>
    void for_each(Fn&& fn) const;
    // Calls fn(first, count) once per touched page with the page's range of points (for change stamps).
    template <class Fn>
    void for_each_page(Fn&& fn) const;

private:
    struct Page {
        std::uint32_t page = 0;   // page number
        std::uint32_t begin = 0;  // first uint16 word in m_data (offsets, or 4,096 mask words)
        std::uint32_t count = 0;  // points of this page in the set; > kMaskAbove: stored as a mask
    };
    static constexpr std::uint32_t kMaskWords = 4096;  // 65,536 bits as uint16 words
    static constexpr std::uint32_t kMaskAbove = 4096;  // 4,096 offsets = 8 KB = one mask
    std::vector<Page> m_pages;
    std::vector<std::uint16_t> m_data;
    std::size_t m_count = 0;
};

enum class PointOp : std::uint8_t { hide, unhide, erase, duplicate, separate };

// One undoable operation on one cloud.
struct PointEditStep {
    PointOp op = PointOp::hide;
    ecs::Entity cloud;         // the source cloud's entity
    ecs::Entity created;       // duplicate/separate: the new entity while it exists (else null)
    std::uint8_t toggled = 0;  // flag bits flipped on `points` (xor: undo and redo are the same flip)
    PointSet points;           // the source points the operation changed or copied
    std::string label;         // "hide", "unhide all", "delete", "duplicate", "separate"

    bool empty() const { return points.empty(); }
    std::size_t bytes() const;  // memory the step holds (sizeof, the label, the set)
};

// Each operation applies itself and returns its step; an empty step (nothing selected, nothing hidden,
// no cloud) changed nothing. Both cloud kinds.
PointEditStep hide_selected(ecs::Registry& registry, ecs::Entity cloud);
PointEditStep unhide_all(ecs::Registry& registry, ecs::Entity cloud);
PointEditStep delete_selected(ecs::Registry& registry, ecs::Entity cloud);
PointEditStep duplicate_selected(ecs::Registry& registry, ecs::Entity cloud);
PointEditStep separate_selected(ecs::Registry& registry, ecs::Entity cloud);

// Undo on the state the step left / redo on the state before it. For duplicate/separate, undo destroys
// `created` and sets it null; redo creates the new entity again and returns it (null for other ops).
void undo(ecs::Registry& registry, PointEditStep& step);
ecs::Entity redo(ecs::Registry& registry, PointEditStep& step);

// The new entity duplicate/separate make, from the points of `source` in `points` (exposed for tests and
// tools: the same extraction redo uses). Returns null when `source` has no cloud.
ecs::Entity extract_points(ecs::Registry& registry, ecs::Entity source, const PointSet& points,
                           const std::string& name_suffix);

// Counts of a cloud's flags (for UI and tests): selected = selected and not gone.
struct PointCounts {
    std::size_t points = 0, selected = 0, hidden = 0, deleted = 0;
};
PointCounts count_points(const ecs::Registry& registry, ecs::Entity cloud);

// ---- inline -------------------------------------------------------------------------------------------

template <class Fn>
void PointSet::for_each(Fn&& fn) const {
    for (const Page& p : m_pages) {
        const std::size_t base = std::size_t(p.page) << 16;
        const std::uint16_t* d = m_data.data() + p.begin;
        if (p.count > kMaskAbove) {
            for (std::uint32_t w = 0; w < kMaskWords; ++w)
                for (std::uint32_t b = d[w]; b != 0; b &= b - 1)
                    fn(base + w * 16u + std::uint32_t(__builtin_ctz(b)));
        } else {
            for (std::uint32_t k = 0; k < p.count; ++k) fn(base + d[k]);
        }
    }
}

template <class Fn>
void PointSet::for_each_page(Fn&& fn) const {
    for (const Page& p : m_pages) fn(std::size_t(p.page) << 16, std::size_t(1) << 16);
}

}  // namespace sffd::point_edit
