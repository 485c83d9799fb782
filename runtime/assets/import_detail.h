// Shared by the importers in this folder (import.cpp: PLY and the splat-cloud step; obj.cpp; off.cpp;
// surface_sampling.cpp). Internal to sffd_assets: not part of its interface.
#pragma once

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/import.h"
#include "runtime/core/result.h"

namespace sffd::assets::detail {

// Decoded texture budget per imported file (all of an OBJ's map_Kd images together), and per image; both
// are checked on the sizes the image headers declare, before anything is decoded.
constexpr std::uint64_t kMaxImagePixels = 8192ull * 8192ull;
constexpr std::uint64_t kDecodedTextureBudget = std::uint64_t(1) << 30;
// Fan triangulation turns a face of k indices into k - 2 triangles: a hostile file can declare lists of
// 2^20 one-byte indices. Refused past this many triangles (400 MB of indices) before expanding further.
constexpr std::size_t kMaxTriangles = std::size_t(1) << 25;
constexpr std::uint32_t kMaxFaceVertices = 1u << 16;  // a polygon of more vertices is not a mesh face

inline std::string lower_ext(const std::filesystem::path& p) {
    std::string e = p.extension().string();
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

inline std::uint32_t pack_rgba(double r, double g, double b, double a) {
    auto q = [](double v) {
        return static_cast<std::uint32_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
    };
    return q(r) | (q(g) << 8) | (q(b) << 16) | (q(a) << 24);
}

inline glm::vec4 unpack_rgba(std::uint32_t c) {
    return glm::vec4(static_cast<float>(c & 255u), static_cast<float>((c >> 8) & 255u),
                     static_cast<float>((c >> 16) & 255u), static_cast<float>(c >> 24)) /
           255.0f;
}

inline bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Deterministic uniform doubles in [0, 1) (std distributions differ between standard libraries).
struct Rng {
    std::uint64_t s;
    explicit Rng(std::uint64_t seed) : s(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) {}
    std::uint64_t next() {  // splitmix64
        std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

// Validates the per-point arrays and triangle indices every reader produces.
Status check_geometry(const Geometry& g);

// Decodes an image file to RGBA8 after checking its declared size (per image, and against *budget_left
// when given, which it then reduces).
Result<Image> decode_image(const std::filesystem::path& path, std::uint64_t* budget_left);

// A texture named inside `owner`: refused (an error) when it lies outside owner's folder or is not a
// regular file; a missing one sets `missing` (callers warn: the geometry is still usable).
Result<Image> load_named_image(const std::filesystem::path& owner, const std::string& name,
                               const std::string& source, std::uint64_t* budget_left, bool& missing);

// Line-oriented text formats (OBJ, MTL, OFF).
struct LineCursor {
    std::string_view s;
    bool next(std::string_view& tok) {
        std::size_t i = 0;
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
        std::size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r') ++j;
        tok = s.substr(i, j - i);
        s = s.substr(j);
        return !tok.empty();
    }
    std::string rest() const {
        std::size_t i = 0;
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
        std::string r(s.substr(i));
        while (!r.empty() && (r.back() == '\r' || r.back() == ' ')) r.pop_back();
        return r;
    }
};

inline bool to_double(std::string_view t, double& v) {
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && p == t.data() + t.size();
}

inline bool to_long(std::string_view t, long long& v) {
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && p == t.data() + t.size();
}

template <class Fn>
void for_each_line(std::string_view text, Fn&& fn) {
    std::size_t pos = 0, line = 0;
    while (pos < text.size()) {
        std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos) nl = text.size();
        ++line;
        if (!fn(text.substr(pos, nl - pos), line)) return;
        pos = nl + 1;
    }
}

// Weighted sample elimination and bilinear texture lookup (surface_sampling.cpp), also used by
// make_splat_cloud() when thinning point sets and baking vertex colours.
std::vector<std::uint32_t> eliminate(const std::vector<glm::dvec3>& pts, std::size_t keep, double area,
                                     const ProgressFn& progress = {});
glm::vec4 sample_texture(const Image& img, glm::vec2 uv);

// The texture a mesh can keep as its splat cloud's material (a textured cloud, sampled per pixel by the
// renderer) instead of baking it into colours: every triangle's material names this one texture with a
// white base colour, the mesh has uvs and no vertex colours. -1 when any of that fails (then colours are
// baked, as before).
int single_texture(const Geometry& mesh);

// The gradients of a triangle's affine map from 3D to uv (in the triangle's plane): for x = a + s(b - a) +
// t(c - a), uv = ta + s(tb - ta) + t(tc - ta), and grad_u . (x - a) = u(x) - u(a) (likewise v).
// Zero for a degenerate triangle.
void triangle_uv_gradients(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, glm::dvec2 ta,
                           glm::dvec2 tb, glm::dvec2 tc, glm::dvec3& grad_u, glm::dvec3& grad_v);

// A splat's uv frame (SplatCloud::uv_axes) from the texture-space gradients and its axes.
inline glm::vec4 uv_frame(const glm::dvec3& grad_u, const glm::dvec3& grad_v, const glm::vec3& axis_u,
                          const glm::vec3& axis_v) {
    const glm::dvec3 au(axis_u), av(axis_v);
    return glm::vec4(float(glm::dot(grad_u, au)), float(glm::dot(grad_v, au)), float(glm::dot(grad_u, av)),
                     float(glm::dot(grad_v, av)));
}

}  // namespace sffd::assets::detail
