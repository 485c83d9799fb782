#include "runtime/assets/formats/gaussian/gaussian_io.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_infinity.h"
#include "runtime/assets/formats/gaussian/gaussian_ksplat.h"
#include "runtime/assets/formats/gaussian/gaussian_ply_fast.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kChunkRows = 1 << 16;

std::string rest_name(int i) { return "f_rest_" + std::to_string(i); }

}  // namespace

float sigmoid(double x) { return float(1.0 / (1.0 + std::exp(-x))); }

double logit(double p) {
    if (!(p > 0.0)) return -kMaxLogit;
    if (!(p < 1.0)) return kMaxLogit;
    return std::clamp(std::log(p / (1.0 - p)), -kMaxLogit, kMaxLogit);
}

bool is_gaussian_element(const ply::Element& v) {
    return v.find("f_dc_0") >= 0 && v.find("opacity") >= 0 && v.find("scale_0") >= 0 && v.find("rot_0") >= 0;
}

Result<PlyLayout> ply_layout(const ply::Element& v, const std::string& name) {
    PlyLayout l;
    std::string missing;
    auto need = [&](const std::string& prop, int& slot) {
        slot = v.find(prop);
        if (slot < 0) missing += (missing.empty() ? "" : ", ") + prop;
        else if (v.properties[std::size_t(slot)].is_list)
            missing += (missing.empty() ? "" : ", ") + prop + " (is a list)";
    };
    need("x", l.x), need("y", l.y), need("z", l.z);
    for (int c = 0; c < 3; ++c) need("f_dc_" + std::to_string(c), l.dc[c]);
    need("opacity", l.opacity);
    for (int c = 0; c < 3; ++c) need("scale_" + std::to_string(c), l.scale[c]);
    for (int c = 0; c < 4; ++c) need("rot_" + std::to_string(c), l.rot[c]);
    if (!missing.empty()) return make_error(name + ": not a 3DGS PLY: vertex element lacks " + missing);
    int count = 0;
    for (const ply::Property& p : v.properties)
        if (p.name.rfind("f_rest_", 0) == 0) ++count;
    for (int i = 0; i < count; ++i) {
        const int at = v.find(rest_name(i));
        if (at < 0 || v.properties[std::size_t(at)].is_list)
            return make_error(name + ": " + std::to_string(count) + " f_rest properties but no scalar " +
                              rest_name(i));
        l.rest.push_back(at);
    }
    l.degree = -1;
    for (int d = 0; d <= 3; ++d)
        if (count == 3 * (sh_coeffs(d) - 1)) l.degree = d;
    if (l.degree < 0)
        return make_error(name + ": " + std::to_string(count) +
                          " f_rest properties: expected 0, 9, 24 or 45 (SH degree 0, 1, 2 or 3)");
    return l;
}

// One vertex row into the cloud's slot `at` (arrays already sized); the checks in the order they report.
// Opacity and scale go through the one infinity mapping (gaussian_infinity.h), counted in `inf`.
Status convert_row(const ply::Chunk& chunk, const PlyLayout& l, std::size_t r, std::uint64_t first_row,
                   const std::string& name, GaussianCloud& out, std::size_t at, InfinityCount& inf) {
    const int K = sh_coeffs(l.degree);
    auto col = [&](int i) -> const std::vector<double>& { return chunk.columns[std::size_t(i)].values; };
    auto bad = [&](int prop, const char* why) {
        return make_error(name + ": vertex " + std::to_string(first_row + r) + ": " + why + " '" +
                          chunk.element.properties[std::size_t(prop)].name + "'");
    };
    // Every other read column must be finite (NaN scales or rotations would poison a whole render).
    for (int p : {l.x, l.y, l.z, l.dc[0], l.dc[1], l.dc[2], l.rot[0], l.rot[1], l.rot[2], l.rot[3]})
        if (!std::isfinite(col(p)[r])) return bad(p, "non-finite");
    for (int p : l.rest)
        if (!std::isfinite(col(p)[r])) return bad(p, "non-finite");
    out.positions[at] = glm::vec3(float(col(l.x)[r]), float(col(l.y)[r]), float(col(l.z)[r]));
    glm::vec3 s;
    for (int c = 0; c < 3; ++c)
        if (!scale_from_log(col(l.scale[c])[r], s[c], inf))
            return bad(l.scale[c], std::isnan(col(l.scale[c])[r])
                                       ? "non-finite"
                                       : "scale overflows (log scale too large) in");
    out.scales[at] = s;
    if (!normalize_quaternion(col(l.rot[0])[r], col(l.rot[1])[r], col(l.rot[2])[r], col(l.rot[3])[r],
                              out.rotations[at]))
        return bad(l.rot[0], "zero-length rotation quaternion at");
    if (!opacity_from_logit(col(l.opacity)[r], out.opacities[at], inf)) return bad(l.opacity, "non-finite");
    float* sh = &out.sh[at * std::size_t(K) * 3];
    for (int k = 0; k < K; ++k)
        for (int c = 0; c < 3; ++c)
            *sh++ =
                k == 0 ? float(col(l.dc[c])[r]) : float(col(l.rest[std::size_t(c * (K - 1) + (k - 1))])[r]);
    return {};
}

// Appends the chunk's rows, converted in parallel. On bad input the cloud is left partly filled and the
// error is the one of the first bad row in file order (each range stops at its own first bad row; the
// smallest of those is re-run for its message).
Status append_from_chunk(const ply::Chunk& chunk, const PlyLayout& l, std::uint64_t first_row,
                         const std::string& name, GaussianCloud& out, InfinityCount* mapped) {
    const std::size_t base = out.positions.size(), n = base + chunk.rows;
    const std::size_t K = std::size_t(sh_coeffs(l.degree));
    out.positions.resize(n), out.scales.resize(n), out.rotations.resize(n), out.opacities.resize(n);
    out.sh.resize(n * K * 3);
    std::atomic<std::size_t> first_bad{chunk.rows}, opacity_inf{0}, scale_inf{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunk.rows, 2048),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          InfinityCount inf;
                          for (std::size_t r = range.begin(); r != range.end(); ++r)
                              if (!convert_row(chunk, l, r, first_row, name, out, base + r, inf)) {
                                  std::size_t seen = first_bad.load();
                                  while (r < seen && !first_bad.compare_exchange_weak(seen, r)) {
                                  }
                                  break;
                              }
                          opacity_inf += inf.opacity;
                          scale_inf += inf.scale;
                      });
    if (const std::size_t r = first_bad.load(); r < chunk.rows) {
        InfinityCount ignored;
        return convert_row(chunk, l, r, first_row, name, out, base + r, ignored);
    }
    if (mapped) mapped->opacity += opacity_inf.load(), mapped->scale += scale_inf.load();
    return {};
}

ply::Element ply_element(int degree, std::uint64_t count) {
    ply::Element e;
    e.name = "vertex";
    e.count = count;
    auto add = [&](const std::string& n) {
        e.properties.push_back({n, ply::Type::float32, false, ply::Type::uint8});
    };
    for (const char* n : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"}) add(n);
    for (int i = 0; i < 3 * (sh_coeffs(degree) - 1); ++i) add(rest_name(i));
    add("opacity");
    for (const char* n : {"scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"}) add(n);
    return e;
}

void fill_chunk(const GaussianCloud& g, std::size_t first, std::size_t count, ply::Chunk& chunk) {
    const std::size_t K = std::size_t(sh_coeffs(g.sh_degree));
    // The columns are kept from the last chunk (same layout): reallocated per chunk, their fresh pages
    // were a large part of writing a big cloud. Filled column by column: sequential stores.
    ply::Element e = ply_element(g.sh_degree, count);
    if (chunk.columns.size() != e.properties.size()) chunk.reset(e);
    else chunk.element = std::move(e);
    chunk.rows = count;
    for (ply::Column& c : chunk.columns) c.values.resize(count);
    auto col = [&](std::size_t i) { return chunk.columns[i].values.data(); };
    const std::size_t rest0 = 9, opacity = rest0 + 3 * (K - 1), scale0 = opacity + 1, rot0 = scale0 + 3;
    for (std::size_t c = 0; c < 3; ++c) {
        double* pos = col(c);
        double* normal = col(3 + c);
        double* scale = col(scale0 + c);
        for (std::size_t r = 0; r < count; ++r) {
            pos[r] = g.origin[int(c)] + double(g.positions[first + r][int(c)]);
            normal[r] = 0.0;
            // log(0) is -inf: a flat Gaussian keeps a tiny finite log scale instead.
            scale[r] = std::log(std::max(double(g.scales[first + r][int(c)]), 1e-30));
        }
        for (std::size_t k = 0; k < K; ++k) {
            double* v = col(k == 0 ? 6 + c : rest0 + c * (K - 1) + (k - 1));
            const float* sh = g.sh.data() + (first * K + k) * 3 + c;
            for (std::size_t r = 0; r < count; ++r) v[r] = sh[r * K * 3];
        }
    }
    double* op = col(opacity);
    double* rot[4] = {col(rot0), col(rot0 + 1), col(rot0 + 2), col(rot0 + 3)};
    for (std::size_t r = 0; r < count; ++r) {
        op[r] = logit(g.opacities[first + r]);
        const glm::quat q = g.rotations[first + r];
        rot[0][r] = q.w, rot[1][r] = q.x, rot[2][r] = q.y, rot[3][r] = q.z;
    }
}

Result<GaussianCloud> read_ply(const fs::path& path) {
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    const std::string name = path.string();
    const int vi = reader->header().find("vertex");
    if (vi < 0) return make_error(name + ": no vertex element");
    // PlayCanvas's compressed layout (chunk + packed vertex elements) has its own reader.
    if (is_compressed_ply(reader->header())) return read_compressed_ply(path);
    const ply::Element& ve = reader->header().elements[std::size_t(vi)];
    auto layout = ply_layout(ve, name);
    if (!layout) return layout.error();
    if (ve.count > kMaxGaussians)
        return make_error(name + ": declares " + std::to_string(ve.count) + " Gaussians, more than the " +
                          std::to_string(kMaxGaussians) + "-Gaussian limit");
    GaussianCloud g;
    g.sh_degree = layout->degree;
    InfinityCount mapped;
    // float32 binary rows (what trainers write) are decoded in place; other files go through the columns.
    if (auto fast = detail::read_ply_float32(path, reader->header(), *layout, g, mapped)) {
        if (!*fast) return fast->error();
        report_infinities(name, mapped);
        return g;
    }
    // ply::Reader::open() refused counts the file cannot hold, so reserving the declared count is safe.
    g.positions.reserve(ve.count), g.scales.reserve(ve.count), g.rotations.reserve(ve.count);
    g.opacities.reserve(ve.count), g.sh.reserve(ve.count * std::uint64_t(sh_coeffs(g.sh_degree)) * 3);
    if (auto s = reader->seek_element("vertex"); !s) return s.error();
    ply::Chunk chunk;
    std::uint64_t row = 0;
    while (true) {
        auto rows = reader->read_rows(kChunkRows, chunk);
        if (!rows) return rows.error();
        if (*rows == 0) break;
        if (auto s = append_from_chunk(chunk, *layout, row, name, g, &mapped); !s) return s.error();
        row += *rows;
    }
    report_infinities(name, mapped);
    return g;
}

Status write_ply(const fs::path& path, const GaussianCloud& g, ply::Format format,
                 std::span<const float> weights) {
    if (auto s = validate(g, path.string()); !s) return s;
    if (!weights.empty() && weights.size() != g.size())
        return make_error(path.string() + ": " + std::to_string(weights.size()) + " weights for " +
                          std::to_string(g.size()) + " Gaussians");
    ply::Header h;
    h.format = format;
    h.comments.push_back("3D Gaussian splats (3DGS layout) written by splatffd");
    h.elements.push_back(ply_element(g.sh_degree, g.size()));
    if (!weights.empty()) h.elements.back().properties.push_back({"weight", ply::Type::float32});
    // ply::Writer writes `<path>.tmp-<pid>`, fsyncs and renames: the same atomic save as
    // runtime/core/atomic_file.h, streaming (no second copy of the file in memory).
    auto writer = ply::Writer::create(path, h);
    if (!writer) return writer.error();
    ply::Chunk chunk;
    for (std::size_t first = 0; first < g.size(); first += kChunkRows) {
        const std::size_t count = std::min(kChunkRows, g.size() - first);
        fill_chunk(g, first, count, chunk);
        if (!weights.empty()) {  // the last column, after the 3DGS layout
            chunk.element.properties.push_back({"weight", ply::Type::float32});
            chunk.columns.emplace_back();
            chunk.columns.back().values.assign(weights.begin() + std::ptrdiff_t(first),
                                               weights.begin() + std::ptrdiff_t(first + count));
        }
        if (auto s = writer->write_rows(chunk); !s) return s;
    }
    return writer->finish();
}

namespace {

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// The one place `.splat` opens its file (to be switched to the shared read-file helper).
Result<File> open_splat_file(const fs::path& path, std::uint64_t& size) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        return make_error(path.string() + ": " +
                          (fs::exists(path, ec) ? "not a regular file" : "no such file"));
    size = fs::file_size(path, ec);
    if (ec) return make_error(path.string() + ": cannot stat: " + ec.message());
    File f(std::fopen(path.c_str(), "rb"));
    if (!f) return make_error(path.string() + ": cannot open: " + std::strerror(errno));
    return f;
}

}  // namespace

Result<GaussianCloud> read_splat(const fs::path& path) {
    const std::string name = path.string();
    std::uint64_t size = 0;
    auto file = open_splat_file(path, size);
    if (!file) return file.error();
    if (size == 0) return make_error(name + ": empty file (a .splat file holds 32 bytes per Gaussian)");
    if (size % 32 != 0)
        return make_error(name + ": size " + std::to_string(size) +
                          " bytes is not a multiple of 32 (.splat rows are 32 bytes; truncated?)");
    const std::size_t n = size / 32;
    if (n > kMaxGaussians)
        return make_error(name + ": holds " + std::to_string(n) + " Gaussians, more than the " +
                          std::to_string(kMaxGaussians) + "-Gaussian limit");
    GaussianCloud g;
    g.sh_degree = 0;
    g.positions.reserve(n), g.scales.reserve(n), g.rotations.reserve(n), g.opacities.reserve(n),
        g.sh.reserve(n * 3);
    std::vector<unsigned char> buf(32 * 8192);
    for (std::size_t first = 0; first < n; first += 8192) {
        const std::size_t rows = std::min<std::size_t>(8192, n - first);
        if (std::fread(buf.data(), 32, rows, file->get()) != rows)
            return make_error(name + ": truncated at splat " + std::to_string(first));
        for (std::size_t r = 0; r < rows; ++r) {
            const unsigned char* p = buf.data() + r * 32;
            float f[6];
            std::memcpy(f, p, sizeof f);  // little-endian host (checked in ply.cpp's kLittleEndianHost too)
            for (int k = 0; k < 6; ++k)
                if (!std::isfinite(f[k]))
                    return make_error(name + ": splat " + std::to_string(first + r) + ": non-finite " +
                                      (k < 3 ? "position" : "scale"));
            if (f[3] < 0 || f[4] < 0 || f[5] < 0)
                return make_error(name + ": splat " + std::to_string(first + r) + ": negative scale");
            g.positions.emplace_back(f[0], f[1], f[2]);
            g.scales.emplace_back(f[3], f[4], f[5]);
            const unsigned char* rgba = p + 24;
            for (int c = 0; c < 3; ++c) g.sh.push_back(float((rgba[c] / 255.0 - 0.5) / kShDc));
            g.opacities.push_back(float(rgba[3] / 255.0));
            const unsigned char* rb = p + 28;
            glm::dvec4 q((rb[0] - 128) / 128.0, (rb[1] - 128) / 128.0, (rb[2] - 128) / 128.0,
                         (rb[3] - 128) / 128.0);
            const double len = glm::length(q);
            if (!(len > 0.0))
                return make_error(name + ": splat " + std::to_string(first + r) + ": zero-length rotation");
            q /= len;
            g.rotations.emplace_back(float(q[0]), float(q[1]), float(q[2]), float(q[3]));
        }
    }
    return g;
}

bool normalize_quaternion(double w, double x, double y, double z, glm::quat& out) {
    const double big = std::max({std::abs(w), std::abs(x), std::abs(y), std::abs(z)});
    if (!(big > 0.0) || !std::isfinite(big)) return false;
    const glm::dvec4 q = glm::dvec4(w, x, y, z) / big;
    const double len = glm::length(q);  // in [1, 2]: no overflow or underflow left
    out = glm::quat(float(q[0] / len), float(q[1] / len), float(q[2] / len), float(q[3] / len));
    return true;
}

namespace {

// validate()'s checks of Gaussian i, in the order they report.
Status check_gaussian(const GaussianCloud& g, std::size_t i, const std::string& what,
                      std::uint64_t first_index) {
    static const char* const kAxis[] = {"x", "y", "z"};
    const std::size_t K3 = std::size_t(sh_coeffs(g.sh_degree)) * 3;
    const auto fail = [&](const std::string& field, double v, const char* why) {
        char value[32];
        std::snprintf(value, sizeof value, "%.9g", v);
        return make_error(what + ": Gaussian " + std::to_string(first_index + i) + ": " + field + " = " +
                          value + ": " + why);
    };
    for (int c = 0; c < 3; ++c) {
        const double p = g.origin[c] + double(g.positions[i][c]);
        if (!std::isfinite(p)) return fail(std::string("position.") + kAxis[c], p, "not finite");
        if (std::abs(p) > kMaxCoordinate)
            return fail(std::string("position.") + kAxis[c], p, "beyond the +-1e10 coordinate bound");
        const double s = double(g.scales[i][c]);
        if (!std::isfinite(s)) return fail(std::string("scale.") + kAxis[c], s, "not finite");
        if (!(s >= 0.0)) return fail(std::string("scale.") + kAxis[c], s, "negative");
        if (s > kMaxScale) return fail(std::string("scale.") + kAxis[c], s, "beyond the 1e10 scale bound");
    }
    if (!(g.opacities[i] >= 0.0f && g.opacities[i] <= 1.0f))
        return fail("opacity", double(g.opacities[i]), "outside [0, 1]");
    const glm::quat q = g.rotations[i];
    const float q2 = glm::dot(q, q);
    if (!(std::abs(q2 - 1.0f) < 1e-3f))
        return fail("rotation (squared length)", double(q2), "not a unit quaternion");
    const float* sh = &g.sh[i * K3];
    // One pass without branches first (the common case: all fine), the per-value messages only when not.
    bool all_ok = true;
    for (std::size_t k = 0; k < K3; ++k)
        all_ok &= std::abs(double(sh[k])) <= kMaxShMagnitude;  // false for NaN
    if (all_ok) return {};
    for (std::size_t k = 0; k < K3; ++k) {
        const double v = double(sh[k]);
        if (!std::isfinite(v) || std::abs(v) > kMaxShMagnitude)
            return fail("sh[" + std::to_string(k / 3) + "]." + "rgb"[k % 3], v,
                        std::isfinite(v) ? "beyond the 1e6 SH bound" : "not finite");
    }
    return {};
}

}  // namespace

Status validate(const GaussianCloud& g, const std::string& what, std::uint64_t first_index) {
    const std::size_t n = g.size();
    if (g.sh_degree < 0 || g.sh_degree > 3)
        return make_error(what + ": SH degree " + std::to_string(g.sh_degree) + " outside 0..3");
    if (g.scales.size() != n || g.rotations.size() != n || g.opacities.size() != n ||
        g.sh.size() != n * std::size_t(sh_coeffs(g.sh_degree)) * 3)
        return make_error(what + ": array sizes differ from the " + std::to_string(n) + " positions");
    if (!std::isfinite(g.origin.x + g.origin.y + g.origin.z))
        return make_error(what + ": the cloud's origin is not finite");
    // In parallel; the first bad Gaussian in order is the one reported (each range stops at its own first).
    std::atomic<std::size_t> first_bad{n};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin();
                               i != r.end() && i < first_bad.load(std::memory_order_relaxed); ++i)
                              if (!check_gaussian(g, i, what, first_index)) {
                                  std::size_t seen = first_bad.load();
                                  while (i < seen && !first_bad.compare_exchange_weak(seen, i)) {
                                  }
                                  break;
                              }
                      });
    if (const std::size_t i = first_bad.load(); i < n) return check_gaussian(g, i, what, first_index);
    if (!g.sh_frames.empty())
        return make_error(
            what +
            ": the cloud carries per-splat SH frames (view-direction mode): bake_sh_frames() before writing");
    return {};
}

}  // namespace sffd::gaussian

namespace sffd::gaussian {

void store_to_chunk(const GaussianCloud& g, const PlyLayout& l, bool opacity, ply::Chunk& chunk) {
    const int K = sh_coeffs(g.sh_degree);
    auto col = [&](int i) -> std::vector<double>& { return chunk.columns[std::size_t(i)].values; };
    for (std::size_t r = 0; r < chunk.rows && r < g.size(); ++r) {
        const glm::dvec3 p = g.origin + glm::dvec3(g.positions[r]);
        const int xyz[3] = {l.x, l.y, l.z};
        for (int c = 0; c < 3; ++c) {
            // Unchanged values keep the file's exact number (a double column stays bit-exact).
            if (float(col(xyz[c])[r]) != float(p[c])) col(xyz[c])[r] = p[c];
            if (float(std::exp(col(l.scale[c])[r])) != g.scales[r][c])
                col(l.scale[c])[r] = std::log(std::max(double(g.scales[r][c]), 1e-30));
            col(l.dc[c])[r] = g.sh[r * std::size_t(K) * 3 + std::size_t(c)];
            for (int k = 1; k < K; ++k)
                col(l.rest[std::size_t(c * (K - 1) + (k - 1))])[r] =
                    g.sh[(r * std::size_t(K) + std::size_t(k)) * 3 + std::size_t(c)];
        }
        const glm::quat q = g.rotations[r];
        const double w = col(l.rot[0])[r], x = col(l.rot[1])[r], y = col(l.rot[2])[r], z = col(l.rot[3])[r];
        const double len = std::sqrt(w * w + x * x + y * y + z * z);
        if (glm::quat(float(w / len), float(x / len), float(y / len), float(z / len)) != q)
            col(l.rot[0])[r] = q.w, col(l.rot[1])[r] = q.x, col(l.rot[2])[r] = q.y, col(l.rot[3])[r] = q.z;
        if (opacity) col(l.opacity)[r] = logit(g.opacities[r]);
    }
}

}  // namespace sffd::gaussian
