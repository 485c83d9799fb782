// The Gaussian sources of lod_build.h: a 3DGS PLY streamed through ply::Reader, procedural Gaussians,
// a cloud in memory.
#include <algorithm>
#include <cmath>

#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/lod/lod_build.h"

namespace sffd::lod {
namespace fs = std::filesystem;

namespace {
constexpr std::size_t kChunkRows = 65536;
}

Result<GaussianSource> ply_gaussian_source(const fs::path& path) {
    const std::string name = path.string();
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    const int v = reader->header().find("vertex");
    if (v < 0) return make_error(name + ": no vertex element");
    if (!gaussian::is_gaussian_element(reader->header().elements[std::size_t(v)]))
        return make_error(name + ": not a 3DGS PLY (no f_dc_0, opacity, scale_0, rot_0 on its vertices)");
    auto layout = gaussian::ply_layout(reader->header().elements[std::size_t(v)], name);
    if (!layout) return layout.error();
    GaussianSource s;
    s.name = name;
    s.scan = [path, name,
              layout = *layout](const std::function<Status(const GaussianCloud&)>& sink) -> Status {
        auto r = ply::Reader::open(path);
        if (!r) return r.error();
        if (Status st = r->seek_element("vertex"); !st) return st;
        ply::Chunk chunk;
        GaussianCloud g;
        std::uint64_t row = 0;
        while (true) {
            auto rows = r->read_rows(kChunkRows, chunk);
            if (!rows) return rows.error();
            if (*rows == 0) break;
            g = GaussianCloud{};
            g.sh_degree = layout.degree;
            if (Status st = gaussian::append_from_chunk(chunk, layout, row, name, g); !st) return st;
            if (Status st = gaussian::validate(g, name, row); !st) return st;
            if (Status st = sink(g); !st) return st;
            row += *rows;
        }
        return {};
    };
    return s;
}

GaussianSource synthetic_gaussian_source(std::uint64_t count, int sh_degree) {
    GaussianSource s;
    s.name = "synthetic-gaussians:" + std::to_string(count);
    s.scan = [count, sh_degree](const std::function<Status(const GaussianCloud&)>& sink) -> Status {
        const double golden = M_PI * (3.0 - std::sqrt(5.0));
        const double radius = 10.0;
        // Spacing of count points on the sphere: the Gaussians' size, so the surface closes.
        const double spacing = radius * std::sqrt(4.0 * M_PI / double(std::max<std::uint64_t>(count, 1)));
        const std::size_t K3 = std::size_t(sh_coeffs(sh_degree)) * 3;
        GaussianCloud g;
        for (std::uint64_t first = 0; first < count; first += kChunkRows) {
            const std::size_t n = std::size_t(std::min<std::uint64_t>(kChunkRows, count - first));
            g = GaussianCloud{};
            g.sh_degree = sh_degree;
            g.positions.resize(n), g.scales.resize(n), g.rotations.resize(n), g.opacities.resize(n);
            g.sh.assign(n * K3, 0.0f);
            for (std::size_t j = 0; j < n; ++j) {
                const double i = double(first + j);
                const double y = 1.0 - 2.0 * (i + 0.5) / double(count);
                const double r = std::sqrt(std::max(0.0, 1.0 - y * y)), phi = golden * i;
                const glm::dvec3 dir(r * std::cos(phi), y, r * std::sin(phi));
                const double ripple = 1.0 + 0.05 * std::sin(7.0 * phi) * std::sin(5.0 * y);
                g.positions[j] = glm::vec3(dir * radius * ripple);
                // Flat along the normal, 0.7 of the spacing across it.
                g.scales[j] = glm::vec3(float(0.7 * spacing), float(0.7 * spacing), float(0.05 * spacing));
                // The rotation taking z onto the outward direction.
                const glm::dvec3 axis = glm::cross(glm::dvec3(0, 0, 1), dir);
                const double c = dir.z, len = glm::length(axis);
                const double half = 0.5 * std::atan2(len, c);
                const glm::dvec3 a = len > 1e-12 ? axis / len : glm::dvec3(1, 0, 0);
                g.rotations[j] = glm::quat(float(std::cos(half)), float(a.x * std::sin(half)),
                                           float(a.y * std::sin(half)), float(a.z * std::sin(half)));
                g.opacities[j] = float(0.5 + 0.45 * std::sin(0.001 * i));
                for (int ch = 0; ch < 3; ++ch)
                    g.sh[j * K3 + std::size_t(ch)] = float(0.8 * dir[ch] + 0.1 * std::sin(3.0 * phi + ch));
                for (std::size_t k = 3; k < K3; ++k)
                    g.sh[j * K3 + k] = float(0.05 * std::sin(0.37 * i + double(k)));
            }
            if (Status st = sink(g); !st) return st;
        }
        return {};
    };
    return s;
}

GaussianSource cloud_gaussian_source(const GaussianCloud& cloud, std::string name) {
    GaussianSource s;
    s.name = std::move(name);
    s.scan = [&cloud](const std::function<Status(const GaussianCloud&)>& sink) -> Status {
        const std::size_t K3 = std::size_t(sh_coeffs(cloud.sh_degree)) * 3;
        GaussianCloud g;
        for (std::size_t first = 0; first < cloud.size(); first += kChunkRows) {
            const std::size_t n = std::min(kChunkRows, cloud.size() - first);
            g = GaussianCloud{};
            g.origin = cloud.origin;
            g.sh_degree = cloud.sh_degree;
            const auto from = [&](const auto& v, std::size_t per) {
                return std::vector<typename std::decay_t<decltype(v)>::value_type>(
                    v.begin() + long(first * per), v.begin() + long((first + n) * per));
            };
            g.positions = from(cloud.positions, 1), g.scales = from(cloud.scales, 1);
            g.rotations = from(cloud.rotations, 1), g.opacities = from(cloud.opacities, 1);
            g.sh = from(cloud.sh, K3);
            if (Status st = sink(g); !st) return st;
        }
        return {};
    };
    return s;
}

}  // namespace sffd::lod
