#include "runtime/scene/point_order.h"

#include "runtime/scene/point_pages.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

namespace sffd {

namespace {

// Spreads the low 21 bits of v so that bit b lands at bit 3b.
std::uint64_t spread3(std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// Gathers `column` (elements of `width` values per point) by perm; an empty column stays empty.
template <class T>
void gather(std::vector<T>& column, std::span<const std::uint32_t> perm, std::size_t width = 1) {
    if (column.empty()) return;
    std::vector<T> out(column.size());
    for (std::size_t t = 0; t < perm.size(); ++t)
        std::copy_n(column.begin() + std::ptrdiff_t(std::size_t(perm[t]) * width), width,
                    out.begin() + std::ptrdiff_t(t * width));
    column = std::move(out);
}

Status check_column(const char* name, std::size_t size, std::size_t expected) {
    if (size == 0 || size == expected) return {};
    return make_error("permute(): column '" + std::string(name) + "' has " + std::to_string(size) +
                      " values, the cloud's points need " + std::to_string(expected));
}

}  // namespace

std::uint64_t morton_code(glm::u32vec3 q) { return spread3(q.x) << 2 | spread3(q.y) << 1 | spread3(q.z); }

std::vector<std::uint64_t> morton_codes(std::span<const glm::vec3> positions) {
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const glm::vec3& p : positions)
        if (finite(p)) lo = glm::min(lo, glm::dvec3(p)), hi = glm::max(hi, glm::dvec3(p));
    constexpr double kCells = double(1u << kMortonBits);
    std::vector<std::uint64_t> codes(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const glm::vec3& p = positions[i];
        if (!finite(p)) {
            codes[i] = std::numeric_limits<std::uint64_t>::max();
            continue;
        }
        glm::u32vec3 q(0);
        for (int a = 0; a < 3; ++a) {
            const double extent = hi[a] - lo[a];
            if (extent > 0)
                q[a] = std::uint32_t(std::clamp((double(p[a]) - lo[a]) / extent * kCells, 0.0, kCells - 1.0));
        }
        codes[i] = morton_code(q);
    }
    return codes;
}

std::vector<std::uint32_t> morton_order(std::span<const glm::vec3> positions) {
    const std::vector<std::uint64_t> codes = morton_codes(positions);
    std::vector<std::uint32_t> perm(positions.size());
    std::iota(perm.begin(), perm.end(), 0u);
    std::sort(perm.begin(), perm.end(), [&](std::uint32_t a, std::uint32_t b) {
        return codes[a] != codes[b] ? codes[a] < codes[b] : a < b;
    });
    return perm;
}

bool is_permutation_of(std::span<const std::uint32_t> perm, std::size_t n) {
    if (perm.size() != n) return false;
    std::vector<bool> seen(n, false);
    for (std::uint32_t i : perm) {
        if (i >= n || seen[i]) return false;
        seen[i] = true;
    }
    return true;
}

PageCompactness page_compactness(std::span<const glm::vec3> positions) {
    const auto box = [&](std::size_t first, std::size_t count, glm::dvec3& lo, glm::dvec3& hi) {
        lo = glm::dvec3(std::numeric_limits<double>::infinity()), hi = -lo;
        for (std::size_t i = first; i < first + count; ++i)
            if (finite(positions[i]))
                lo = glm::min(lo, glm::dvec3(positions[i])), hi = glm::max(hi, glm::dvec3(positions[i]));
    };
    PageCompactness r;
    r.pages = page_count(positions.size());
    glm::dvec3 clo, chi;
    box(0, positions.size(), clo, chi);
    if (r.pages == 0 || !(clo.x <= chi.x)) return r;
    const glm::dvec3 cext = chi - clo;
    std::size_t counted = 0;
    for (std::size_t p = 0; p < r.pages; ++p) {
        const PageRange pr = page_range(p, positions.size());
        glm::dvec3 lo, hi;
        box(pr.first, pr.count, lo, hi);
        if (!(lo.x <= hi.x)) continue;
        const glm::dvec3 ext = hi - lo;
        double volume = 1.0;
        for (int a = 0; a < 3; ++a)
            if (cext[a] > 0) volume *= ext[a] / cext[a];
        const double diagonal = glm::length(cext) > 0 ? glm::length(ext) / glm::length(cext) : 0.0;
        r.mean_volume_share += volume, r.mean_diagonal_share += diagonal, ++counted;
    }
    if (counted) r.mean_volume_share /= double(counted), r.mean_diagonal_share /= double(counted);
    return r;
}

Status permute(SplatCloud& c, std::span<const std::uint32_t> perm) {
    const std::size_t n = c.size();
    if (!is_permutation_of(perm, n))
        return make_error("permute(): the order is not a permutation of the cloud's " + std::to_string(n) +
                          " points");
    for (auto [name, size] : {std::pair{"normals", c.normals.size()},
                              {"axis_u", c.axis_u.size()},
                              {"axis_v", c.axis_v.size()},
                              {"colors", c.colors.size()},
                              {"uvs", c.uvs.size()},
                              {"uv_axes", c.uv_axes.size()}})
        if (Status s = check_column(name, size, n); !s) return s;
    gather(c.positions, perm);
    gather(c.normals, perm);
    gather(c.axis_u, perm);
    gather(c.axis_v, perm);
    gather(c.colors, perm);
    gather(c.uvs, perm);
    gather(c.uv_axes, perm);
    return {};
}

Status permute(GaussianCloud& g, std::span<const std::uint32_t> perm) {
    const std::size_t n = g.size();
    if (!is_permutation_of(perm, n))
        return make_error("permute(): the order is not a permutation of the cloud's " + std::to_string(n) +
                          " points");
    const std::size_t sh_width = std::size_t(sh_coeffs(g.sh_degree)) * 3;
    for (auto [name, size] : {std::pair{"scales", g.scales.size()},
                              {"rotations", g.rotations.size()},
                              {"opacities", g.opacities.size()},
                              {"sh_frames", g.sh_frames.size()}})
        if (Status s = check_column(name, size, n); !s) return s;
    if (Status s = check_column("sh", g.sh.size(), n * sh_width); !s) return s;
    gather(g.positions, perm);
    gather(g.scales, perm);
    gather(g.rotations, perm);
    gather(g.opacities, perm);
    gather(g.sh, perm, sh_width);
    gather(g.sh_frames, perm);
    return {};
}

}  // namespace sffd
