#include "systems/point_edit/point_edit.h"

#include <algorithm>
#include <utility>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"

namespace sffd::point_edit {

namespace {

constexpr std::uint8_t kSelectMask = kPointSelected | kPointGone;

std::size_t cloud_size(const ecs::Registry& r, ecs::Entity e) {
    if (!r.valid(e)) return 0;
    if (const SplatCloud* c = r.try_get<SplatCloud>(e)) return c->size();
    if (const GaussianCloud* c = r.try_get<GaussianCloud>(e)) return c->size();
    return 0;
}

bool has_cloud(const ecs::Registry& r, ecs::Entity e) {
    return r.valid(e) && (r.has<SplatCloud>(e) || r.has<GaussianCloud>(e));
}

// The flags of e's cloud when they hold one byte a point (else null: no point is selected or hidden).
const std::vector<std::uint8_t>* flag_bits(const ecs::Registry& r, ecs::Entity e) {
    if (!has_cloud(r, e)) return nullptr;
    const PointFlags* f = r.try_get<PointFlags>(e);
    if (!f || f->bits.empty() || f->bits.size() != cloud_size(r, e)) return nullptr;
    return &f->bits;
}

// The flag stamps of the pages `points` touches, of the groups the flipped bits belong to (selection,
// visibility): the cloud's columns are not written, so their page stamps stay.
void mark_flags(ecs::Registry& r, ecs::Entity e, const PointSet& points, std::uint8_t toggled) {
    points.for_each_page([&](std::size_t first, std::size_t count) {
        if (toggled & kPointSelected) mark_points_changed(r, e, PointColumn::selection, first, count);
        if (toggled & kPointGone) mark_points_changed(r, e, PointColumn::visibility, first, count);
    });
}

// Flips `toggled` on every point of the set (xor: the same call undoes and redoes).
void flip(ecs::Registry& r, ecs::Entity e, const PointSet& points, std::uint8_t toggled) {
    if (toggled == 0 || points.empty() || !has_cloud(r, e) || !r.has<PointFlags>(e)) return;
    std::vector<std::uint8_t>& bits = r.patch<PointFlags>(e).bits;
    const std::size_t n = bits.size();
    points.for_each([&](std::size_t i) {
        if (i < n) bits[i] ^= toggled;
    });
    mark_flags(r, e, points, toggled);
}

PointEditStep flag_step(ecs::Registry& r, ecs::Entity e, PointOp op, std::uint8_t mask, std::uint8_t want,
                        std::uint8_t toggled, const char* label) {
    PointEditStep step;
    step.op = op, step.cloud = e, step.toggled = toggled, step.label = label;
    if (const std::vector<std::uint8_t>* bits = flag_bits(r, e))
        step.points = PointSet::where(*bits, mask, want);
    flip(r, e, step.points, toggled);
    return step;
}

template <class T>
std::vector<T> gather(const std::vector<T>& column, const PointSet& points, std::size_t per_point = 1) {
    std::vector<T> out;
    if (column.empty()) return out;
    out.reserve(points.size() * per_point);
    points.for_each([&](std::size_t i) {
        const T* p = column.data() + i * per_point;
        out.insert(out.end(), p, p + per_point);
    });
    return out;
}

SplatCloud extract(const SplatCloud& c, const PointSet& s) {
    SplatCloud out;
    out.origin = c.origin;
    out.positions = gather(c.positions, s);
    out.normals = gather(c.normals, s);
    out.axis_u = gather(c.axis_u, s);
    out.axis_v = gather(c.axis_v, s);
    out.colors = gather(c.colors, s);
    out.uvs = gather(c.uvs, s);
    out.uv_axes = gather(c.uv_axes, s);
    out.texture = c.texture;
    return out;
}

GaussianCloud extract(const GaussianCloud& c, const PointSet& s) {
    GaussianCloud out;
    out.origin = c.origin;
    out.positions = gather(c.positions, s);
    out.scales = gather(c.scales, s);
    out.rotations = gather(c.rotations, s);
    out.opacities = gather(c.opacities, s);
    out.sh_degree = c.sh_degree;
    out.sh = gather(c.sh, s, std::size_t(sh_coeffs(c.sh_degree)) * 3);
    out.sh_frames = gather(c.sh_frames, s);
    return out;
}

template <class T>
void copy_component(ecs::Registry& r, ecs::Entity from, ecs::Entity to) {
    if (const T* c = std::as_const(r).try_get<T>(from)) r.emplace<T>(to, *c);
}

PointEditStep extract_step(ecs::Registry& r, ecs::Entity e, PointOp op, std::uint8_t toggled,
                           const char* label, const char* suffix) {
    PointEditStep step;
    step.op = op, step.cloud = e, step.toggled = toggled, step.label = label;
    const std::vector<std::uint8_t>* bits = flag_bits(r, e);
    if (!bits) return step;
    step.points = PointSet::where(*bits, kSelectMask, kPointSelected);
    if (step.points.empty()) return step;
    step.created = extract_points(r, e, step.points, suffix);
    flip(r, e, step.points, toggled);
    return step;
}

const char* suffix_of(PointOp op) { return op == PointOp::separate ? ".part" : ".copy"; }

}  // namespace

// ---- PointSet -----------------------------------------------------------------------------------------

PointSet PointSet::where(const std::vector<std::uint8_t>& bits, std::uint8_t mask, std::uint8_t want) {
    PointSet s;
    const std::size_t n = bits.size();
    std::vector<std::uint16_t> offsets;
    offsets.reserve(kMaskAbove + 1);
    for (std::size_t page = 0; page < page_count(n); ++page) {
        const PageRange range = page_range(page, n);
        const std::uint8_t* b = bits.data() + range.first;
        // Offsets until they would outgrow a mask; then the rest of the page goes into a mask.
        offsets.clear();
        std::size_t k = 0, count = 0;
        for (; k < range.count && offsets.size() <= kMaskAbove; ++k)
            if ((b[k] & mask) == want) offsets.push_back(std::uint16_t(k));
        count = offsets.size();
        if (count == 0) continue;
        Page p{std::uint32_t(page), std::uint32_t(s.m_data.size()), 0};
        if (count <= kMaskAbove) {
            p.count = std::uint32_t(count);
            s.m_data.insert(s.m_data.end(), offsets.begin(), offsets.end());
        } else {
            s.m_data.resize(s.m_data.size() + kMaskWords, 0);
            std::uint16_t* m = s.m_data.data() + p.begin;
            for (std::uint16_t o : offsets) m[o >> 4] |= std::uint16_t(1u << (o & 15));
            for (; k < range.count; ++k)
                if ((b[k] & mask) == want) m[k >> 4] |= std::uint16_t(1u << (k & 15)), ++count;
            p.count = std::uint32_t(count);
        }
        s.m_count += count;
        s.m_pages.push_back(p);
    }
    s.m_pages.shrink_to_fit();
    s.m_data.shrink_to_fit();
    return s;
}

std::size_t PointSet::bytes() const {
    return sizeof(PointSet) + m_pages.capacity() * sizeof(Page) + m_data.capacity() * sizeof(std::uint16_t);
}

std::size_t PointEditStep::bytes() const {
    return sizeof(PointEditStep) - sizeof(PointSet) + points.bytes() + label.capacity();
}

// ---- operations ---------------------------------------------------------------------------------------

PointEditStep hide_selected(ecs::Registry& r, ecs::Entity e) {
    return flag_step(r, e, PointOp::hide, kSelectMask, kPointSelected, kPointHidden | kPointSelected, "hide");
}

PointEditStep unhide_all(ecs::Registry& r, ecs::Entity e) {
    return flag_step(r, e, PointOp::unhide, kPointGone, kPointHidden, kPointHidden, "unhide all");
}

PointEditStep delete_selected(ecs::Registry& r, ecs::Entity e) {
    return flag_step(r, e, PointOp::erase, kSelectMask, kPointSelected, kPointDeleted | kPointSelected,
                     "delete");
}

PointEditStep duplicate_selected(ecs::Registry& r, ecs::Entity e) {
    return extract_step(r, e, PointOp::duplicate, 0, "duplicate", suffix_of(PointOp::duplicate));
}

PointEditStep separate_selected(ecs::Registry& r, ecs::Entity e) {
    return extract_step(r, e, PointOp::separate, kPointDeleted | kPointSelected, "separate",
                        suffix_of(PointOp::separate));
}

ecs::Entity extract_points(ecs::Registry& r, ecs::Entity source, const PointSet& points,
                           const std::string& name_suffix) {
    if (!has_cloud(r, source)) return {};
    const ecs::Registry& cr = r;
    const ecs::Entity e = r.create();
    if (const SplatCloud* c = cr.try_get<SplatCloud>(source)) r.emplace<SplatCloud>(e, extract(*c, points));
    else r.emplace<GaussianCloud>(e, extract(cr.get<GaussianCloud>(source), points));
    if (const PointWeights* w = cr.try_get<PointWeights>(source); w && !w->values.empty())
        r.emplace<PointWeights>(e, PointWeights{gather(w->values, points)});
    copy_component<Transform>(r, source, e);
    copy_component<SplatMaterial>(r, source, e);
    const Name* name = cr.try_get<Name>(source);
    r.emplace<Name>(e,
                    Name{(name && !name->value.empty() ? name->value : std::string("cloud")) + name_suffix});
    mark_cloud_replaced(r, e);
    return e;
}

void undo(ecs::Registry& r, PointEditStep& step) {
    if (step.empty()) return;
    flip(r, step.cloud, step.points, step.toggled);
    if (step.op == PointOp::duplicate || step.op == PointOp::separate) {
        if (r.valid(step.created)) r.destroy(step.created);
        step.created = {};
    }
}

ecs::Entity redo(ecs::Registry& r, PointEditStep& step) {
    if (step.empty()) return {};
    if (step.op == PointOp::duplicate || step.op == PointOp::separate)
        step.created = extract_points(r, step.cloud, step.points, suffix_of(step.op));
    flip(r, step.cloud, step.points, step.toggled);
    return step.created;
}

PointCounts count_points(const ecs::Registry& r, ecs::Entity e) {
    PointCounts c;
    c.points = cloud_size(r, e);
    const std::vector<std::uint8_t>* bits = flag_bits(r, e);
    if (!bits) return c;
    for (std::uint8_t b : *bits) {
        c.selected += (b & kSelectMask) == kPointSelected;
        c.hidden += (b & kPointHidden) != 0;
        c.deleted += (b & kPointDeleted) != 0;
    }
    return c;
}

}  // namespace sffd::point_edit
