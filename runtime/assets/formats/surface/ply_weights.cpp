#include "runtime/assets/formats/surface/ply_weights.h"

#include <algorithm>
#include <cstring>

#include "runtime/assets/formats/surface/ply_mapped.h"
#include "runtime/core/log.h"

namespace sffd::assets {

int ply_weight_property(const ply::Element& vertex) {
    const int i = vertex.find(kPlyWeightProperty);
    return i >= 0 && !vertex.properties[std::size_t(i)].is_list ? i : -1;
}

Status check_ply_weights(std::span<const double> values, std::size_t rows, std::uint64_t first,
                         const std::string& path) {
    for (std::size_t r = 0; r < rows && r < values.size(); ++r)
        if (!(values[r] >= 0.0 && values[r] <= 1.0))  // NaN fails both
            return make_error(path + ": vertex " + std::to_string(first + r) + ": weight " +
                              std::to_string(values[r]) + " is not in [0, 1]");
    return {};
}

Result<PointWeights> read_ply_weights(const std::filesystem::path& path) {
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    const ply::Header& h = reader->header();
    const int vi = h.find("vertex");
    if (vi < 0) return PointWeights{};
    const ply::Element& ve = h.elements[std::size_t(vi)];
    const int col = ply_weight_property(ve);
    if (col < 0) return PointWeights{};
    const std::string where = path.string();
    PointWeights out;
    // The usual layout (binary little endian, float weights, no lists before): straight from the mapping.
    if (ve.properties[std::size_t(col)].type == ply::Type::float32) {
        if (auto m = ply::MappedElement::map(path, h, "vertex")) {
            const std::size_t n = std::size_t(m->count()), stride = m->row_size();
            const unsigned char* p = m->rows() + m->property_offset(col);
            out.values.resize(n);
            for (std::size_t r = 0; r < n; ++r) std::memcpy(&out.values[r], p + r * stride, sizeof(float));
            if (m->changed()) return make_error(where + ": the file changed while it was read");
            for (std::size_t r = 0; r < n; ++r)
                if (!(out.values[r] >= 0.0f && out.values[r] <= 1.0f))
                    return make_error(where + ": vertex " + std::to_string(r) + ": weight " +
                                      std::to_string(out.values[r]) + " is not in [0, 1]");
            return out;
        }
    }
    if (Status s = reader->seek_element("vertex"); !s) return s.error();
    out.values.reserve(std::size_t(ve.count));
    ply::Chunk chunk;
    while (true) {
        auto rows = reader->read_rows(1 << 16, chunk);
        if (!rows) return rows.error();
        if (*rows == 0) break;
        const std::vector<double>& w = chunk.columns[std::size_t(col)].values;
        if (Status s = check_ply_weights(w, *rows, out.values.size(), where); !s) return s.error();
        for (std::size_t r = 0; r < *rows; ++r) out.values.push_back(float(w[r]));
    }
    return out;
}

Result<PointWeights> cloud_weights_of_file(const std::filesystem::path& path, std::size_t points) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".ply") return PointWeights{};
    auto header = ply::Reader::open(path);
    if (!header) return header.error();
    const int vi = header->header().find("vertex");
    if (vi < 0 || ply_weight_property(header->header().elements[std::size_t(vi)]) < 0) return PointWeights{};
    const int fi = header->header().find("face");
    const bool faces = fi >= 0 && header->header().elements[std::size_t(fi)].count > 0;
    const std::uint64_t vertices = header->header().elements[std::size_t(vi)].count;
    if (faces || vertices != points) {
        log::warn(path.string(), ": the vertex property 'weight' is not used: the cloud's ", points,
                  " points are not the file's ", vertices, " vertices (sampled from its faces, or thinned)");
        return PointWeights{};
    }
    return read_ply_weights(path);
}

}  // namespace sffd::assets
