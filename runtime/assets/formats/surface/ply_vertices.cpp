#include "runtime/assets/formats/surface/ply_vertices.h"

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/import_detail.h"
#include "runtime/assets/formats/surface/ply_mapped.h"

namespace sffd::assets::detail {

namespace {

struct Field {
    std::size_t offset = 0;
    ply::Type type = ply::Type::float32;
};

template <class T>
inline double as(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return double(v);
}

// The value of one field of a row (little endian, as the mapping requires); the switch is on the column's
// type, the same for every row, so it predicts perfectly.
inline double value(const unsigned char* row, const Field& f) {
    const unsigned char* p = row + f.offset;
    switch (f.type) {
        case ply::Type::int8: return as<std::int8_t>(p);
        case ply::Type::uint8: return as<std::uint8_t>(p);
        case ply::Type::int16: return as<std::int16_t>(p);
        case ply::Type::uint16: return as<std::uint16_t>(p);
        case ply::Type::int32: return as<std::int32_t>(p);
        case ply::Type::uint32: return as<std::uint32_t>(p);
        case ply::Type::float32: return as<float>(p);
        case ply::Type::float64: return as<double>(p);
    }
    return 0.0;
}

}  // namespace

std::optional<Status> read_ply_vertices_mapped(const std::filesystem::path& path, const ply::Header& header,
                                               const PlyVertexColumns& c, Geometry& g) {
    auto m = ply::MappedElement::map(path, header, "vertex");
    if (!m) return std::nullopt;
    const ply::Element& e = m->element();
    auto field = [&](int p) {
        return p < 0 ? Field{} : Field{m->property_offset(p), e.properties[std::size_t(p)].type};
    };
    Field pos[3], nor[3], col[4], uv[2], ax[6], uf[4];
    for (int i = 0; i < 3; ++i) pos[i] = field(c.pos[i]), nor[i] = field(c.normal[i]);
    for (int i = 0; i < 4; ++i) col[i] = field(c.color[i]), uf[i] = field(c.uv_frame[i]);
    for (int i = 0; i < 2; ++i) uv[i] = field(c.uv[i]);
    for (int i = 0; i < 6; ++i) ax[i] = field(c.axes[i]);
    const bool alpha = c.color[3] >= 0;

    const std::size_t n = std::size_t(m->count()), stride = m->row_size();
    // Every element is written below: the arrays are prefaulted in parallel rather than on first touch.
    resize_for_overwrite(g.positions, n);
    if (c.has_normals) resize_for_overwrite(g.normals, n);
    if (c.has_colors) resize_for_overwrite(g.colors, n);
    if (c.has_uvs) resize_for_overwrite(g.uvs, n);
    if (c.has_axes) resize_for_overwrite(g.axis_u, n), resize_for_overwrite(g.axis_v, n);
    if (c.has_uv_frame) resize_for_overwrite(g.uv_axes, n);
    const unsigned char* rows = m->rows();
    std::atomic<std::size_t> first_bad{n};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 8192), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t r = range.begin(); r != range.end(); ++r) {
                const unsigned char* row = rows + r * stride;
                g.positions[r] = glm::dvec3(value(row, pos[0]), value(row, pos[1]), value(row, pos[2]));
                if (c.has_normals)
                    g.normals[r] = glm::vec3(value(row, nor[0]), value(row, nor[1]), value(row, nor[2]));
                if (c.has_colors) {
                    const double a = alpha ? value(row, col[3]) * c.color_scale[3] : 1.0;
                    const double cr = value(row, col[0]), cg = value(row, col[1]), cb = value(row, col[2]);
                    if (!std::isfinite(cr + cg + cb + a)) {
                        std::size_t seen = first_bad.load();
                        while (r < seen && !first_bad.compare_exchange_weak(seen, r)) {
                        }
                        return;
                    }
                    g.colors[r] =
                        pack_rgba(cr * c.color_scale[0], cg * c.color_scale[1], cb * c.color_scale[2], a);
                }
                if (c.has_uvs) g.uvs[r] = glm::vec2(value(row, uv[0]), value(row, uv[1]));
                if (c.has_axes) {
                    g.axis_u[r] = glm::vec3(value(row, ax[0]), value(row, ax[1]), value(row, ax[2]));
                    g.axis_v[r] = glm::vec3(value(row, ax[3]), value(row, ax[4]), value(row, ax[5]));
                }
                if (c.has_uv_frame)
                    g.uv_axes[r] =
                        glm::vec4(value(row, uf[0]), value(row, uf[1]), value(row, uf[2]), value(row, uf[3]));
            }
        });
    if (m->changed()) return make_error(g.source + ": " + kChangedWhileRead);
    if (const std::size_t r = first_bad.load(); r < n)
        return make_error(g.source + ": vertex " + std::to_string(r) + " has a non-finite colour");
    return Status{};
}

}  // namespace sffd::assets::detail
