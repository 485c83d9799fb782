// The splat sources of potree2_write.h: a cloud in memory, a procedural sphere made in chunks, and our
// splat PLY streamed through ply::Reader.
#include <algorithm>
#include <cmath>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/potree2_write.h"

namespace sffd::assets {
namespace fs = std::filesystem;

namespace {
constexpr std::size_t kChunkRows = 65536;
}

SplatSource cloud_splat_source(const SplatCloud& cloud, std::string name) {
    SplatSource s;
    s.name = std::move(name);
    s.texture = cloud.texture;
    s.scan = [&cloud](const std::function<Status(const SplatCloud&)>& sink) { return sink(cloud); };
    return s;
}

SplatSource synthetic_splat_source(std::uint64_t count) {
    SplatSource s;
    s.name = "synthetic:" + std::to_string(count);
    s.scan = [count](const std::function<Status(const SplatCloud&)>& sink) -> Status {
        const double golden = M_PI * (3.0 - std::sqrt(5.0));
        const double n = double(std::max<std::uint64_t>(count, 1));
        // Each splat covers ~4 pi / count; 1.3x its equal-area disc radius overlaps the neighbours.
        const double splat_r = 1.3 * std::sqrt(4.0 / n);
        SplatCloud c;
        for (std::uint64_t start = 0; start < count; start += kChunkRows) {
            const std::uint64_t end = std::min<std::uint64_t>(count, start + kChunkRows);
            c = SplatCloud{};
            for (std::uint64_t i = start; i < end; ++i) {
                const double y = 1.0 - 2.0 * (double(i) + 0.5) / n;
                const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
                const double phi = golden * double(i);
                const glm::dvec3 nrm(std::cos(phi) * r, y, std::sin(phi) * r);
                const glm::dvec3 ref = std::abs(nrm.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
                const glm::dvec3 u = glm::normalize(glm::cross(ref, nrm));
                const glm::dvec3 v = glm::cross(nrm, u);
                c.positions.emplace_back(nrm);
                c.normals.emplace_back(nrm);
                c.axis_u.emplace_back(u * splat_r);
                c.axis_v.emplace_back(v * splat_r);
                const auto red = std::uint32_t(127.5 * (nrm.x + 1.0));
                const auto green = std::uint32_t(127.5 * (y + 1.0));
                c.colors.push_back(red | (green << 8) | (200u << 16) | (255u << 24));
            }
            if (Status st = sink(c); !st) return st;
        }
        return {};
    };
    return s;
}

Result<SplatSource> ply_splat_source(const fs::path& path) {
    const std::string name = path.string();
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    const int v = reader->header().find("vertex");
    if (v < 0) return make_error(name + ": no vertex element");
    const ply::Element& e = reader->header().elements[std::size_t(v)];
    static const char* kNeeded[] = {"x",       "y",       "z",       "nx",      "ny",      "nz",
                                    "axis_ux", "axis_uy", "axis_uz", "axis_vx", "axis_vy", "axis_vz"};
    std::vector<int> col;
    for (const char* p : kNeeded) {
        col.push_back(e.find(p));
        if (col.back() < 0) return make_error(name + ": not a splat PLY (no '" + std::string(p) + "')");
    }
    for (const char* p : {"red", "green", "blue", "alpha", "u", "v", "du_ds", "dv_ds", "du_dt", "dv_dt"})
        col.push_back(e.find(p));
    if (e.has_lists()) return make_error(name + ": a splat PLY's vertices have no lists");
    glm::dvec3 origin(0.0);
    for (const std::string& c : reader->header().comments)
        if (c.rfind("sffd_origin ", 0) == 0)
            std::sscanf(c.c_str() + 12, "%lf %lf %lf", &origin.x, &origin.y, &origin.z);
    SplatSource s;
    s.name = name;
    s.scan = [path, name, col, origin](const std::function<Status(const SplatCloud&)>& sink) -> Status {
        auto r = ply::Reader::open(path);
        if (!r) return r.error();
        if (Status st = r->seek_element("vertex"); !st) return st;
        ply::Chunk chunk;
        SplatCloud c;
        const bool colors = col[12] >= 0 && col[13] >= 0 && col[14] >= 0;
        const bool uvs = col[16] >= 0 && col[17] >= 0;
        const bool frames = uvs && col[18] >= 0 && col[19] >= 0 && col[20] >= 0 && col[21] >= 0;
        std::uint64_t row = 0;
        while (true) {
            auto rows = r->read_rows(kChunkRows, chunk);
            if (!rows) return rows.error();
            if (*rows == 0) break;
            c = SplatCloud{};
            c.origin = origin;
            const auto at = [&](int k, std::size_t i) {
                return chunk.columns[std::size_t(col[std::size_t(k)])].values[i];
            };
            for (std::size_t i = 0; i < *rows; ++i) {
                double vals[12];
                for (int k = 0; k < 12; ++k) {
                    vals[k] = at(k, i);
                    if (!std::isfinite(vals[k]))
                        return make_error(name + ": vertex " + std::to_string(row + i) +
                                          ": not a finite number");
                }
                c.positions.emplace_back(glm::dvec3(vals[0], vals[1], vals[2]) - origin);
                c.normals.emplace_back(vals[3], vals[4], vals[5]);
                c.axis_u.emplace_back(vals[6], vals[7], vals[8]);
                c.axis_v.emplace_back(vals[9], vals[10], vals[11]);
                if (colors) {
                    const auto byte = [&](int k) { return std::uint32_t(std::clamp(at(k, i), 0.0, 255.0)); };
                    c.colors.push_back(byte(12) | byte(13) << 8 | byte(14) << 16 |
                                       (col[15] >= 0 ? byte(15) : 255u) << 24);
                }
                if (uvs) c.uvs.emplace_back(at(16, i), at(17, i));
                if (frames) c.uv_axes.emplace_back(at(18, i), at(19, i), at(20, i), at(21, i));
            }
            if (Status st = sink(c); !st) return st;
            row += *rows;
        }
        return {};
    };
    return s;
}

}  // namespace sffd::assets
