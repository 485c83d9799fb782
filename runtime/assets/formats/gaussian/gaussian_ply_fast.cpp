#include "runtime/assets/formats/gaussian/gaussian_ply_fast.h"

#include <atomic>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/assets/formats/archive/fresh_array.h"
#include "runtime/assets/formats/surface/ply_mapped.h"

namespace sffd::gaussian::detail {

namespace {

// Byte offsets in a row of the columns the layout names, in the cloud's order.
struct Offsets {
    int pos[3], dc[3], rot[4], scale[3], opacity;
    std::vector<int> sh;  // K*3 entries: coefficient k channel c at sh[k*3+c] (k = 0 from f_dc)
};

inline double at(const unsigned char* row, int offset) {
    float v;
    std::memcpy(&v, row + offset, sizeof v);
    return double(v);
}

// convert_row() of gaussian_io.cpp on a float32 row: the checks in the order they report.
Status convert(const unsigned char* row, const Offsets& o, const PlyLayout& l, const ply::Element& e,
               std::uint64_t r, const std::string& name, GaussianCloud& out, std::size_t i,
               InfinityCount& inf) {
    auto bad = [&](int prop, const char* why) {
        return make_error(name + ": vertex " + std::to_string(r) + ": " + why + " '" +
                          e.properties[std::size_t(prop)].name + "'");
    };
    const int K = sh_coeffs(l.degree);
    const int props[] = {l.x, l.y, l.z, l.dc[0], l.dc[1], l.dc[2], l.rot[0], l.rot[1], l.rot[2], l.rot[3]};
    const int offs[] = {o.pos[0], o.pos[1], o.pos[2], o.dc[0],  o.dc[1],
                        o.dc[2],  o.rot[0], o.rot[1], o.rot[2], o.rot[3]};
    for (int p = 0; p < 10; ++p)
        if (!std::isfinite(at(row, offs[p]))) return bad(props[p], "non-finite");
    // f_rest_i in file-name order (what the column path checks first).
    for (std::size_t j = 0; j < l.rest.size(); ++j) {
        const int c = int(j) / (K - 1), k = int(j) % (K - 1) + 1;
        if (!std::isfinite(at(row, o.sh[std::size_t(k * 3 + c)]))) return bad(l.rest[j], "non-finite");
    }
    out.positions[i] =
        glm::vec3(float(at(row, o.pos[0])), float(at(row, o.pos[1])), float(at(row, o.pos[2])));
    glm::vec3 s;
    for (int c = 0; c < 3; ++c) {
        const double v = at(row, o.scale[c]);
        if (!scale_from_log(v, s[c], inf))
            return bad(l.scale[c], std::isnan(v) ? "non-finite" : "scale overflows (log scale too large) in");
    }
    out.scales[i] = s;
    if (!normalize_quaternion(at(row, o.rot[0]), at(row, o.rot[1]), at(row, o.rot[2]), at(row, o.rot[3]),
                              out.rotations[i]))
        return bad(l.rot[0], "zero-length rotation quaternion at");
    if (!opacity_from_logit(at(row, o.opacity), out.opacities[i], inf)) return bad(l.opacity, "non-finite");
    float* sh = &out.sh[i * std::size_t(K) * 3];
    for (int k = 0; k < K * 3; ++k) std::memcpy(sh + k, row + o.sh[std::size_t(k)], sizeof(float));
    return {};
}

}  // namespace

std::optional<Status> read_ply_float32(const std::filesystem::path& path, const ply::Header& header,
                                       const PlyLayout& l, GaussianCloud& out, InfinityCount& mapped) {
    auto m = ply::MappedElement::map(path, header, "vertex");
    if (!m) return std::nullopt;
    const ply::Element& e = m->element();
    std::vector<int> used = {l.x, l.y, l.z, l.opacity};
    for (int c = 0; c < 3; ++c) used.push_back(l.dc[c]), used.push_back(l.scale[c]);
    for (int c = 0; c < 4; ++c) used.push_back(l.rot[c]);
    used.insert(used.end(), l.rest.begin(), l.rest.end());
    for (int p : used)
        if (e.properties[std::size_t(p)].type != ply::Type::float32) return std::nullopt;
    const int K = sh_coeffs(l.degree);
    auto off = [&](int p) { return int(m->property_offset(p)); };
    Offsets o;
    for (int c = 0; c < 3; ++c) o.dc[c] = off(l.dc[c]), o.scale[c] = off(l.scale[c]);
    o.pos[0] = off(l.x), o.pos[1] = off(l.y), o.pos[2] = off(l.z), o.opacity = off(l.opacity);
    for (int c = 0; c < 4; ++c) o.rot[c] = off(l.rot[c]);
    o.sh.resize(std::size_t(K) * 3);
    for (int k = 0; k < K; ++k)
        for (int c = 0; c < 3; ++c)
            o.sh[std::size_t(k * 3 + c)] = k == 0 ? o.dc[c] : off(l.rest[std::size_t(c * (K - 1) + (k - 1))]);

    const std::size_t n = std::size_t(m->count()), stride = m->row_size();
    const std::string name = path.string();
    out.sh_degree = l.degree;
    // Every element is written below: the arrays are prefaulted in parallel rather than on first touch.
    assets::resize_for_overwrite(out.positions, n), assets::resize_for_overwrite(out.scales, n);
    assets::resize_for_overwrite(out.rotations, n), assets::resize_for_overwrite(out.opacities, n);
    assets::resize_for_overwrite(out.sh, n * std::size_t(K) * 3);
    const unsigned char* rows = m->rows();
    // As append_from_chunk: each range stops at its first bad row, the smallest is re-run for its message.
    std::atomic<std::size_t> first_bad{n}, opacity_inf{0}, scale_inf{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          InfinityCount inf;
                          for (std::size_t r = range.begin(); r != range.end(); ++r)
                              if (!convert(rows + r * stride, o, l, e, r, name, out, r, inf)) {
                                  std::size_t seen = first_bad.load();
                                  while (r < seen && !first_bad.compare_exchange_weak(seen, r)) {
                                  }
                                  break;
                              }
                          opacity_inf += inf.opacity;
                          scale_inf += inf.scale;
                      });
    if (m->changed()) return make_error(name + ": " + assets::kChangedWhileRead);
    if (const std::size_t r = first_bad.load(); r < n) {
        InfinityCount ignored;
        return convert(rows + r * stride, o, l, e, r, name, out, r, ignored);
    }
    mapped.opacity += opacity_inf.load(), mapped.scale += scale_inf.load();
    return Status{};
}

}  // namespace sffd::gaussian::detail
