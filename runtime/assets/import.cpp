#include "runtime/assets/import.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <queue>
#include <sstream>
#include <unordered_map>

#include <nanoflann.hpp>
#include <stb/stb_image.h>
#include <tbb/parallel_for.h>

#include "runtime/assets/gltf_io.h"
#include "runtime/assets/ply.h"
#include "runtime/assets/splat_estimation.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"

namespace sffd::assets {
namespace fs = std::filesystem;

namespace {

std::string lower_ext(const fs::path& p) {
    std::string e = p.extension().string();
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

std::uint32_t pack_rgba(double r, double g, double b, double a) {
    auto q = [](double v) { return static_cast<std::uint32_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
    return q(r) | (q(g) << 8) | (q(b) << 16) | (q(a) << 24);
}

glm::vec4 unpack_rgba(std::uint32_t c) {
    return glm::vec4(static_cast<float>(c & 255u), static_cast<float>((c >> 8) & 255u), static_cast<float>((c >> 16) & 255u),
                     static_cast<float>(c >> 24)) /
           255.0f;
}

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

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
Status check_geometry(const Geometry& g) {
    const std::size_t n = g.positions.size();
    for (std::size_t i = 0; i < n; ++i)
        if (!finite3(g.positions[i])) return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite coordinate");
    for (std::size_t i = 0; i < g.normals.size(); ++i)
        if (!finite3(glm::dvec3(g.normals[i]))) return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite normal");
    for (std::size_t i = 0; i < g.uvs.size(); ++i)
        if (!std::isfinite(g.uvs[i].x) || !std::isfinite(g.uvs[i].y))
            return make_error(g.source + ": point " + std::to_string(i) + " has a non-finite texture coordinate");
    for (std::size_t i = 0; i < g.axis_u.size(); ++i)
        if (!finite3(glm::dvec3(g.axis_u[i])) || !finite3(glm::dvec3(g.axis_v[i])))
            return make_error(g.source + ": point " + std::to_string(i) + " has non-finite splat axes");
    if ((!g.normals.empty() && g.normals.size() != n) || (!g.colors.empty() && g.colors.size() != n) ||
        (!g.uvs.empty() && g.uvs.size() != n) || g.axis_u.size() != g.axis_v.size() || (!g.axis_u.empty() && g.axis_u.size() != n))
        return make_error(g.source + ": attribute arrays do not match the point count");
    for (std::size_t i = 0; i < g.triangles.size(); ++i)
        if (g.triangles[i] >= n)
            return make_error(g.source + ": face " + std::to_string(i / 3) + " refers to vertex " + std::to_string(g.triangles[i]) +
                              " but there are only " + std::to_string(n));
    for (std::int32_t m : g.triangle_material)
        if (m >= static_cast<std::int32_t>(g.materials.size())) return make_error(g.source + ": bad material index");
    for (const MeshMaterial& m : g.materials)
        if (m.texture >= static_cast<int>(g.textures.size())) return make_error(g.source + ": bad texture index");
    return {};
}

// ------------------------------------------------------------------------------------------------
// PLY

int find_any(const ply::Element& e, std::initializer_list<const char*> names) {
    for (const char* n : names)
        if (int i = e.find(n); i >= 0) return i;
    return -1;
}

// Colour channel scale: integer channels are 0..max of their type, float channels 0..1.
double channel_scale(ply::Type t) {
    switch (t) {
        case ply::Type::uint8: return 1.0 / 255.0;
        case ply::Type::uint16: return 1.0 / 65535.0;
        case ply::Type::float32:
        case ply::Type::float64: return 1.0;
        default: return 1.0 / 255.0;
    }
}

}  // namespace

glm::dvec3 choose_origin(const std::vector<glm::dvec3>& positions) {
    if (positions.empty()) return glm::dvec3(0.0);
    glm::dvec3 lo(positions[0]), hi(positions[0]);
    for (const auto& p : positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::dvec3 centre = 0.5 * (lo + hi);
    const double extent = glm::length(hi - lo);
    // Float offsets lose precision once the distance from 0 dwarfs the cloud: recentre then.
    const double distance = glm::length(centre);
    if (distance > 1e3 || distance > 16.0 * std::max(extent, 1e-30)) return centre;
    return glm::dvec3(0.0);
}

namespace {

// Decoded texture budget per imported file (all of an OBJ's map_Kd images together), and per image; both
// are checked on the sizes the image headers declare, before anything is decoded.
constexpr std::uint64_t kMaxImagePixels = 8192ull * 8192ull;
constexpr std::uint64_t kDecodedTextureBudget = std::uint64_t(1) << 30;
// Fan triangulation turns a face of k indices into k - 2 triangles: a hostile file can declare lists of
// 2^20 one-byte indices. Refused past this many triangles (400 MB of indices) before expanding further.
constexpr std::size_t kMaxTriangles = std::size_t(1) << 25;
constexpr std::uint32_t kMaxFaceVertices = 1u << 16;  // a polygon of more vertices is not a mesh face

Result<Image> decode_image(const fs::path& path, std::uint64_t* budget_left) {
    auto bytes = read_file(path, kMaxResourceBytes);
    if (!bytes) return bytes.error();
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes->data());
    const int size = static_cast<int>(std::min<std::size_t>(bytes->size(), 0x7fffffff));
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(data, size, &w, &h, &comp) || w <= 0 || h <= 0)
        return make_error(path.string() + ": cannot decode image: " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown format"));
    const std::uint64_t pixels = static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h);
    if (pixels > kMaxImagePixels)
        return make_error(path.string() + ": image is " + std::to_string(w) + "x" + std::to_string(h) + ", larger than 8192x8192");
    if (budget_left) {
        if (pixels * 4 > *budget_left)
            return make_error(path.string() + ": image is " + std::to_string(w) + "x" + std::to_string(h) + "; the textures of one file may decode to at most " +
                              std::to_string(kDecodedTextureBudget >> 20) + " MiB in total");
        *budget_left -= pixels * 4;
    }
    stbi_uc* pixels_rgba = stbi_load_from_memory(data, size, &w, &h, &comp, 4);
    if (!pixels_rgba) return make_error(path.string() + ": cannot decode image: " + (stbi_failure_reason() ? stbi_failure_reason() : "?"));
    Image img;
    img.width = w;
    img.height = h;
    img.rgba8.assign(pixels_rgba, pixels_rgba + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
    stbi_image_free(pixels_rgba);
    return img;
}

// A texture or material library named inside `owner`: refused (an error) when it lies outside owner's
// folder or is not a regular file; a missing one is only a warning (the geometry is still usable).
Result<Image> load_named_image(const fs::path& owner, const std::string& name, const std::string& source, std::uint64_t* budget_left,
                               bool& missing) {
    missing = false;
    auto where = resolve_resource(owner, name);
    if (!where) {
        missing = where.message().size() >= 9 && where.message().compare(where.message().size() - 9, 9, "not found") == 0;
        return where.error();
    }
    auto img = decode_image(*where, budget_left);
    if (!img) return make_error(source + ": texture '" + name + "': " + img.message());
    return img;
}

}  // namespace

Result<Image> load_image(const fs::path& path) { return decode_image(path, nullptr); }

Result<Geometry> read_ply_geometry(const fs::path& path) {
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    const ply::Header& h = reader->header();
    Geometry g;
    g.source = path.string();
    const int vi = h.find("vertex");
    if (vi < 0) return make_error(g.source + ": no 'vertex' element");
    const ply::Element& ve = h.elements[vi];
    const int px = ve.find("x"), py = ve.find("y"), pz = ve.find("z");
    if (px < 0 || py < 0 || pz < 0) return make_error(g.source + ": vertex element has no x, y, z properties");
    for (int i : {px, py, pz})
        if (ve.properties[i].is_list) return make_error(g.source + ": vertex property '" + ve.properties[i].name + "' is a list");
    auto scalar = [&](int i) { return i >= 0 && !ve.properties[i].is_list ? i : -1; };
    const int nx = scalar(ve.find("nx")), ny = scalar(ve.find("ny")), nz = scalar(ve.find("nz"));
    const int cr = scalar(find_any(ve, {"red", "diffuse_red", "r"})), cg = scalar(find_any(ve, {"green", "diffuse_green", "g"}));
    const int cb = scalar(find_any(ve, {"blue", "diffuse_blue", "b"})), ca = scalar(find_any(ve, {"alpha", "diffuse_alpha", "a"}));
    const int tu = scalar(find_any(ve, {"u", "s", "texture_u", "texture_s"})), tv = scalar(find_any(ve, {"v", "t", "texture_v", "texture_t"}));
    const int ax[6] = {scalar(ve.find("axis_ux")), scalar(ve.find("axis_uy")), scalar(ve.find("axis_uz")),
                       scalar(ve.find("axis_vx")), scalar(ve.find("axis_vy")), scalar(ve.find("axis_vz"))};
    const bool has_axes = std::all_of(ax, ax + 6, [](int i) { return i >= 0; });
    const bool has_normals = nx >= 0 && ny >= 0 && nz >= 0;
    const bool has_colors = cr >= 0 && cg >= 0 && cb >= 0;
    const bool has_uvs = tu >= 0 && tv >= 0;
    for (const auto& p : ve.properties) g.attributes.push_back(std::string(ply::type_name(p.type)) + (p.is_list ? "[] " : " ") + p.name);

    for (const std::string& c : h.comments) {
        if (c.rfind("sffd_origin ", 0) == 0) {
            std::istringstream s(c.substr(12));
            glm::dvec3 o;
            if (s >> o.x >> o.y >> o.z && finite3(o)) {
                g.has_origin = true;
                g.origin = o;
            } else {
                return make_error(g.source + ": malformed 'sffd_origin' comment");
            }
        } else if (c.rfind("TextureFile ", 0) == 0) {
            g.splat_material.texture_path = c.substr(12);
        }
    }

    const std::size_t n = static_cast<std::size_t>(ve.count);
    g.positions.reserve(n);
    if (has_normals) g.normals.reserve(n);
    if (has_colors) g.colors.reserve(n);
    if (has_uvs) g.uvs.reserve(n);
    if (has_axes) {
        g.axis_u.reserve(n);
        g.axis_v.reserve(n);
    }
    if (auto s = reader->seek_element("vertex"); !s) return s.error();
    ply::Chunk chunk;
    while (true) {
        auto rows = reader->read_rows(1 << 16, chunk);
        if (!rows) return rows.error();
        if (*rows == 0) break;
        const auto col = [&](int i) -> const std::vector<double>& { return chunk.columns[i].values; };
        for (std::size_t r = 0; r < *rows; ++r) {
            g.positions.emplace_back(col(px)[r], col(py)[r], col(pz)[r]);
            if (has_normals) g.normals.emplace_back(col(nx)[r], col(ny)[r], col(nz)[r]);
            if (has_colors) {
                const double a = ca >= 0 ? col(ca)[r] * channel_scale(ve.properties[ca].type) : 1.0;
                const double sr = channel_scale(ve.properties[cr].type);
                const double sg = channel_scale(ve.properties[cg].type);
                const double sb = channel_scale(ve.properties[cb].type);
                if (!std::isfinite(col(cr)[r] + col(cg)[r] + col(cb)[r] + a))
                    return make_error(g.source + ": vertex " + std::to_string(g.positions.size() - 1) + " has a non-finite colour");
                g.colors.push_back(pack_rgba(col(cr)[r] * sr, col(cg)[r] * sg, col(cb)[r] * sb, a));
            }
            if (has_uvs) g.uvs.emplace_back(col(tu)[r], col(tv)[r]);
            if (has_axes) {
                g.axis_u.emplace_back(col(ax[0])[r], col(ax[1])[r], col(ax[2])[r]);
                g.axis_v.emplace_back(col(ax[3])[r], col(ax[4])[r], col(ax[5])[r]);
            }
        }
    }
    // Faces (any element named "face" with a vertex index list), triangulated as fans.
    if (const int fi = h.find("face"); fi >= 0 && static_cast<std::size_t>(fi) > static_cast<std::size_t>(vi)) {
        const ply::Element& fe = h.elements[fi];
        const int li = find_any(fe, {"vertex_indices", "vertex_index"});
        if (li < 0 || !fe.properties[li].is_list) return make_error(g.source + ": face element has no vertex_indices list");
        if (auto s = reader->seek_element("face"); !s) return s.error();
        std::size_t faces_done = 0;
        while (true) {
            auto rows = reader->read_rows(1 << 16, chunk);
            if (!rows) return rows.error();
            if (*rows == 0) break;
            const ply::Column& c = chunk.columns[li];
            const std::size_t faces_seen = faces_done;
            faces_done += *rows;
            for (std::size_t r = 0; r < *rows; ++r) {
                const std::uint32_t b = c.offsets[r], e = c.offsets[r + 1];
                for (std::uint32_t k = b; k < e; ++k)
                    if (c.values[k] < 0 || c.values[k] >= static_cast<double>(n))
                        return make_error(g.source + ": face refers to vertex " + std::to_string(static_cast<long long>(c.values[k])) +
                                          " but there are only " + std::to_string(n));
                if (e - b > kMaxFaceVertices)
                    return make_error(g.source + ": face " + std::to_string(faces_seen + r) + " has " + std::to_string(e - b) + " vertices; at most " +
                                      std::to_string(kMaxFaceVertices) + " per face (fan triangulation budget)");
                if (e - b > 2 && g.triangles.size() / 3 + (e - b - 2) > kMaxTriangles)
                    return make_error(g.source + ": faces expand to more than " + std::to_string(kMaxTriangles) +
                                      " triangles (the import budget); face lists of up to " + std::to_string(e - b) + " vertices");
                for (std::uint32_t k = b + 1; k + 1 < e; ++k) {
                    g.triangles.push_back(static_cast<std::uint32_t>(c.values[b]));
                    g.triangles.push_back(static_cast<std::uint32_t>(c.values[k]));
                    g.triangles.push_back(static_cast<std::uint32_t>(c.values[k + 1]));
                }
            }
        }
    } else if (fi >= 0) {
        log::warn(g.source, ": face element comes before the vertex element; faces ignored");
    }
    if (!g.splat_material.texture_path.empty()) {
        std::uint64_t budget = kDecodedTextureBudget;
        bool missing = false;
        if (auto img = load_named_image(path, g.splat_material.texture_path, g.source, &budget, missing); img) {
            g.splat_material.texture_width = img->width;
            g.splat_material.texture_height = img->height;
            g.splat_material.texture_rgba8 = std::move(img->rgba8);
        } else if (missing) {
            log::warn(g.source, ": texture not loaded: ", img.message());
        } else {
            return img.error();
        }
    }
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

// ------------------------------------------------------------------------------------------------
// OBJ (v, vn, vt, f, mtllib/usemtl with Kd and map_Kd; vertex colours "v x y z r g b")

namespace {

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

bool to_double(std::string_view t, double& v) {
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && p == t.data() + t.size();
}

bool to_long(std::string_view t, long long& v) {
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

// Loads `name` (an mtllib line of the OBJ `obj`): an error when it is outside the OBJ's folder or not a
// regular file, a warning when missing. Its map_Kd textures resolve inside the MTL's own folder.
Status load_mtl(const fs::path& obj, const std::string& name, Geometry& g, std::unordered_map<std::string, int>& by_name,
                std::uint64_t& texture_budget) {
    auto mtl_path = resolve_resource(obj, name);
    if (!mtl_path) {
        if (mtl_path.message().size() >= 9 && mtl_path.message().compare(mtl_path.message().size() - 9, 9, "not found") == 0) {
            log::warn(g.source, ": material library not loaded: ", mtl_path.message());
            return {};
        }
        return mtl_path.error();
    }
    auto text = read_file(*mtl_path, 64u << 20);
    if (!text) return make_error(g.source + ": material library: " + text.message());
    std::string error;
    int current = -1;
    for_each_line(*text, [&](std::string_view line, std::size_t) {
        LineCursor c{line};
        std::string_view key;
        if (!c.next(key)) return true;
        if (key == "newmtl") {
            current = static_cast<int>(g.materials.size());
            g.materials.push_back({});
            by_name[c.rest()] = current;
        } else if (current >= 0 && key == "Kd") {
            std::string_view a, b, d;
            double r = 1, gg = 1, bb = 1;
            if (c.next(a) && c.next(b) && c.next(d) && to_double(a, r) && to_double(b, gg) && to_double(d, bb) &&
                std::isfinite(r + gg + bb))
                g.materials[current].base_color = glm::vec4(static_cast<float>(r), static_cast<float>(gg), static_cast<float>(bb),
                                                            g.materials[current].base_color.w);
        } else if (current >= 0 && key == "d") {
            std::string_view a;
            double d = 1;
            if (c.next(a) && to_double(a, d) && std::isfinite(d)) g.materials[current].base_color.w = static_cast<float>(d);
        } else if (current >= 0 && key == "map_Kd") {
            std::string file = c.rest();
            // Options such as "-s 1 1 1" come before the file name; the name is the last word.
            if (auto sp = file.find_last_of(' '); sp != std::string::npos) file = file.substr(sp + 1);
            bool missing = false;
            auto img = load_named_image(*mtl_path, file, g.source, &texture_budget, missing);
            if (!img) {
                if (!missing) {
                    error = img.message();
                    return false;
                }
                log::warn(g.source, ": texture not loaded: ", img.message());
                return true;
            }
            g.materials[current].texture = static_cast<int>(g.textures.size());
            g.textures.push_back(std::move(*img));
        }
        return true;
    });
    if (!error.empty()) return make_error(error);
    return {};
}

}  // namespace

Result<Geometry> read_obj_geometry(const fs::path& path) {
    std::uint64_t texture_budget = kDecodedTextureBudget;
    auto text = read_file(path, kMaxTextFileBytes);
    if (!text) return text.error();
    Geometry g;
    g.source = path.string();
    std::vector<glm::dvec3> v;
    std::vector<std::uint32_t> vcolor;
    std::vector<glm::vec3> vn;
    std::vector<glm::vec2> vt;
    struct Corner {
        long long v, t, n;
    };
    std::vector<Corner> corners;        // 3 per triangle
    std::vector<std::int32_t> tri_mat;
    std::unordered_map<std::string, int> materials;
    int current_material = -1;
    std::string error;
    for_each_line(*text, [&](std::string_view line, std::size_t line_no) {
        LineCursor c{line};
        std::string_view key;
        if (!c.next(key) || key[0] == '#') return true;
        auto fail = [&](const std::string& why) {
            error = g.source + ":" + std::to_string(line_no) + ": " + why;
            return false;
        };
        if (key == "v" || key == "vn" || key == "vt") {
            double d[7];
            int count = 0;
            std::string_view tok;
            while (count < 7 && c.next(tok)) {
                if (!to_double(tok, d[count])) return fail("malformed number '" + std::string(tok.substr(0, 40)) + "'");
                if (!std::isfinite(d[count])) return fail("non-finite number");
                ++count;
            }
            if (key == "v") {
                if (count < 3) return fail("vertex needs 3 coordinates");
                v.emplace_back(d[0], d[1], d[2]);
                if (count >= 6) vcolor.push_back(pack_rgba(d[3], d[4], d[5], 1.0));
            } else if (key == "vn") {
                if (count < 3) return fail("normal needs 3 coordinates");
                vn.emplace_back(d[0], d[1], d[2]);
            } else {
                if (count < 1) return fail("texture coordinate needs a value");
                vt.emplace_back(d[0], 1.0 - (count > 1 ? d[1] : 0.0));  // OBJ v=0 is the bottom row
            }
        } else if (key == "f") {
            std::vector<Corner> poly;
            std::string_view tok;
            while (c.next(tok)) {
                Corner k{0, 0, 0};
                long long* slots[3] = {&k.v, &k.t, &k.n};
                std::size_t start = 0;
                for (int s = 0; s < 3 && start <= tok.size(); ++s) {
                    std::size_t slash = tok.find('/', start);
                    if (slash == std::string_view::npos) slash = tok.size();
                    const std::string_view part = tok.substr(start, slash - start);
                    if (!part.empty() && !to_long(part, *slots[s])) return fail("malformed face index '" + std::string(tok.substr(0, 40)) + "'");
                    start = slash + 1;
                }
                // Negative indices count back from the latest element; resolve to 1-based now.
                auto resolve = [](long long& i, std::size_t size) {
                    if (i < 0) i = static_cast<long long>(size) + i + 1;
                };
                resolve(k.v, v.size());
                resolve(k.t, vt.size());
                resolve(k.n, vn.size());
                if (k.v < 1 || k.v > static_cast<long long>(v.size())) return fail("face refers to missing vertex " + std::to_string(k.v));
                if (k.t < 0 || k.t > static_cast<long long>(vt.size())) return fail("face refers to missing texture coordinate");
                if (k.n < 0 || k.n > static_cast<long long>(vn.size())) return fail("face refers to missing normal");
                poly.push_back(k);
            }
            if (poly.size() < 3) return fail("face with fewer than 3 vertices");
            for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
                corners.push_back(poly[0]);
                corners.push_back(poly[i]);
                corners.push_back(poly[i + 1]);
                tri_mat.push_back(current_material);
            }
        } else if (key == "mtllib") {
            if (Status st = load_mtl(path, c.rest(), g, materials, texture_budget); !st) {
                error = st.message();
                return false;
            }
        } else if (key == "usemtl") {
            auto it = materials.find(c.rest());
            current_material = it == materials.end() ? -1 : it->second;
        }
        return true;
    });
    if (!error.empty()) return make_error(error);
    if (!vcolor.empty() && vcolor.size() != v.size()) vcolor.clear();  // colours on some vertices only: ignore
    const bool by_corner = std::any_of(corners.begin(), corners.end(), [](const Corner& k) { return k.t > 0 || k.n > 0; });
    if (!by_corner) {
        g.positions = std::move(v);
        g.colors = std::move(vcolor);
        for (const Corner& k : corners) g.triangles.push_back(static_cast<std::uint32_t>(k.v - 1));
    } else {
        // Texture seams and hard edges need separate vertices: one per distinct (v, vt, vn) triple.
        std::unordered_map<std::uint64_t, std::uint32_t> seen;
        const bool has_t = !vt.empty(), has_n = !vn.empty();
        auto key_of = [](const Corner& k) {
            return (static_cast<std::uint64_t>(k.v) * 0x9E3779B1ull) ^ (static_cast<std::uint64_t>(k.t) << 42) ^
                   (static_cast<std::uint64_t>(k.n) << 21);
        };
        std::vector<Corner> uniq;
        for (const Corner& k : corners) {
            std::uint64_t key = key_of(k);
            auto [it, inserted] = seen.try_emplace(key, static_cast<std::uint32_t>(uniq.size()));
            // Hash collisions: fall back to a fresh vertex (never merge different triples).
            if (!inserted) {
                const Corner& o = uniq[it->second];
                if (o.v != k.v || o.t != k.t || o.n != k.n) {
                    g.triangles.push_back(static_cast<std::uint32_t>(uniq.size()));
                    uniq.push_back(k);
                    continue;
                }
            } else {
                uniq.push_back(k);
            }
            g.triangles.push_back(it->second);
        }
        for (const Corner& k : uniq) {
            g.positions.push_back(v[static_cast<std::size_t>(k.v - 1)]);
            if (!vcolor.empty()) g.colors.push_back(vcolor[static_cast<std::size_t>(k.v - 1)]);
            if (has_t) g.uvs.push_back(k.t > 0 ? vt[static_cast<std::size_t>(k.t - 1)] : glm::vec2(0.0f));
            if (has_n) g.normals.push_back(k.n > 0 ? vn[static_cast<std::size_t>(k.n - 1)] : glm::vec3(0.0f));
        }
        // Normals given on some corners only are unusable for interpolation.
        if (has_n && std::any_of(uniq.begin(), uniq.end(), [](const Corner& k) { return k.n == 0; })) g.normals.clear();
    }
    if (!g.materials.empty() && !tri_mat.empty()) g.triangle_material = std::move(tri_mat);
    g.attributes = {"position"};
    if (!g.normals.empty()) g.attributes.push_back("normal");
    if (!g.uvs.empty()) g.attributes.push_back("texcoord");
    if (!g.colors.empty()) g.attributes.push_back("color");
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

// ------------------------------------------------------------------------------------------------
// OFF ([ST][C][N]OFF; vertex line: x y z [nx ny nz] [r g b [a]] [s t]; face line: n i0 .. [colour])

Result<Geometry> read_off_geometry(const fs::path& path) {
    auto text = read_file(path, kMaxTextFileBytes);
    if (!text) return text.error();
    Geometry g;
    g.source = path.string();
    std::vector<std::string_view> lines;
    for_each_line(*text, [&](std::string_view line, std::size_t) {
        const std::size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        if (line.find_first_not_of(" \t\r") != std::string_view::npos) lines.push_back(line);
        return true;
    });
    if (lines.empty()) return make_error(g.source + ": empty file (not an OFF file)");
    LineCursor head{lines[0]};
    std::string_view magic;
    head.next(magic);
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF") return make_error(g.source + ": not an OFF file (bad magic)");
    std::string_view prefix = magic.substr(0, magic.size() - 3);
    bool has_st = false, has_c = false, has_n = false;
    if (prefix.substr(0, 2) == "ST") { has_st = true; prefix.remove_prefix(2); }
    if (!prefix.empty() && prefix[0] == 'C') { has_c = true; prefix.remove_prefix(1); }
    if (!prefix.empty() && prefix[0] == 'N') { has_n = true; prefix.remove_prefix(1); }
    if (!prefix.empty()) return make_error(g.source + ": unsupported OFF variant '" + std::string(magic) + "'");
    std::size_t li = 1;
    LineCursor counts = head;  // counts may follow the magic on the same line
    std::string_view a, b;
    if (!counts.next(a)) {
        if (lines.size() < 2) return make_error(g.source + ": truncated OFF header");
        counts = LineCursor{lines[1]};
        li = 2;
        counts.next(a);
    }
    long long nv = 0, nf = 0;
    if (!counts.next(b) || !to_long(a, nv) || !to_long(b, nf) || nv < 0 || nf < 0)
        return make_error(g.source + ": bad vertex/face counts");
    if (static_cast<unsigned long long>(nv) > lines.size() || static_cast<unsigned long long>(nf) > lines.size() ||
        li + static_cast<std::size_t>(nv) + static_cast<std::size_t>(nf) > lines.size())
        return make_error(g.source + ": counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                          " faces) exceed the file's " + std::to_string(lines.size()) + " lines");
    for (long long i = 0; i < nv; ++i, ++li) {
        LineCursor c{lines[li]};
        std::vector<double> d;
        std::string_view tok;
        while (c.next(tok)) {
            double x;
            if (!to_double(tok, x)) return make_error(g.source + ": vertex " + std::to_string(i) + ": malformed number '" + std::string(tok.substr(0, 40)) + "'");
            d.push_back(x);
        }
        const std::size_t need = 3 + (has_n ? 3 : 0) + (has_c ? 3 : 0) + (has_st ? 2 : 0);
        if (d.size() < need) return make_error(g.source + ": vertex " + std::to_string(i) + " has too few values");
        std::size_t k = 0;
        g.positions.emplace_back(d[0], d[1], d[2]);
        k = 3;
        if (has_n) { g.normals.emplace_back(d[k], d[k + 1], d[k + 2]); k += 3; }
        if (has_c) {
            const std::size_t nc = d.size() - need >= 1 ? 4 : 3;
            const double scale = (d[k] > 1.0 || d[k + 1] > 1.0 || d[k + 2] > 1.0) ? 1.0 / 255.0 : 1.0;
            g.colors.push_back(pack_rgba(d[k] * scale, d[k + 1] * scale, d[k + 2] * scale, nc == 4 ? d[k + 3] * scale : 1.0));
            k += nc;
        }
        if (has_st) g.uvs.emplace_back(d[k], d[k + 1]);
    }
    for (long long i = 0; i < nf; ++i, ++li) {
        LineCursor c{lines[li]};
        std::string_view tok;
        long long n = 0;
        if (!c.next(tok) || !to_long(tok, n) || n < 0 || n > 1 << 20)
            return make_error(g.source + ": face " + std::to_string(i) + ": bad vertex count");
        std::vector<std::uint32_t> idx;
        for (long long k = 0; k < n; ++k) {
            long long x;
            if (!c.next(tok) || !to_long(tok, x)) return make_error(g.source + ": face " + std::to_string(i) + ": too few or malformed indices");
            if (x < 0 || x >= nv)
                return make_error(g.source + ": face " + std::to_string(i) + " refers to vertex " + std::to_string(x) + " but there are only " +
                                  std::to_string(nv));
            idx.push_back(static_cast<std::uint32_t>(x));
        }
        if (idx.size() > 2 && g.triangles.size() / 3 + idx.size() - 2 > kMaxTriangles)
            return make_error(g.source + ": faces expand to more than " + std::to_string(kMaxTriangles) + " triangles (the import budget)");
        for (std::size_t k = 1; k + 1 < idx.size(); ++k) {
            g.triangles.push_back(idx[0]);
            g.triangles.push_back(idx[k]);
            g.triangles.push_back(idx[k + 1]);
        }
    }
    g.attributes = {"position"};
    if (has_n) g.attributes.push_back("normal");
    if (has_c) g.attributes.push_back("color");
    if (has_st) g.attributes.push_back("texcoord");
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

Result<Geometry> read_geometry(const fs::path& path) {
    const std::string ext = lower_ext(path);
    std::error_code ec;
    if (!fs::exists(path, ec)) return make_error(path.string() + ": no such file");
    if (ext == ".ply") return read_ply_geometry(path);
    if (ext == ".obj") return read_obj_geometry(path);
    if (ext == ".off") return read_off_geometry(path);
    if (ext == ".gltf" || ext == ".glb") return read_gltf_geometry(path);
    return make_error(path.string() + ": unknown file type '" + ext + "' (expected .ply, .obj, .off, .gltf or .glb)");
}

// ------------------------------------------------------------------------------------------------
// Sampling

namespace {

struct Adaptor3d {
    const std::vector<glm::dvec3>* pts;
    std::size_t kdtree_get_point_count() const { return pts->size(); }
    double kdtree_get_pt(std::size_t i, std::size_t d) const { return (*pts)[i][static_cast<int>(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const { return false; }
};
using Tree3d = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor3d>, Adaptor3d, 3, std::uint32_t>;

// Weighted sample elimination (Yuksel 2015): removes the most crowded point until `keep` remain.
// `area` is the surface area the points cover (for the neighbourhood radius). Returns the kept indices
// in ascending order.
std::vector<std::uint32_t> eliminate(const std::vector<glm::dvec3>& pts, std::size_t keep, double area) {
    const std::size_t n = pts.size();
    std::vector<std::uint32_t> kept;
    if (keep >= n) {
        kept.resize(n);
        std::iota(kept.begin(), kept.end(), 0u);
        return kept;
    }
    const double r_max = std::sqrt(area / (2.0 * std::sqrt(3.0) * static_cast<double>(keep)));
    const double r2 = 2.0 * r_max;
    Adaptor3d adaptor{&pts};
    Tree3d tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree.buildIndex();
    // Neighbour lists in parallel blocks (the search dominates), concatenated in point order.
    constexpr std::size_t kBlock = 8192;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::vector<std::uint32_t>> block_nbr(blocks), block_count(blocks);
    std::vector<std::vector<float>> block_dist(blocks);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
        std::vector<std::pair<std::uint32_t, double>> found;
        nanoflann::SearchParams params(32, 0.0f, false);
        const std::size_t end = std::min(n, (b + 1) * kBlock);
        for (std::size_t i = b * kBlock; i < end; ++i) {
            const double q[3] = {pts[i].x, pts[i].y, pts[i].z};
            found.clear();
            tree.radiusSearch(q, r2 * r2, found, params);
            std::uint32_t taken = 0;
            for (const auto& [j, d2] : found) {
                if (j == i) continue;
                if (taken >= 64) break;  // duplicates piled on one spot: bound the work
                ++taken;
                block_nbr[b].push_back(j);
                block_dist[b].push_back(static_cast<float>(std::sqrt(d2)));
            }
            block_count[b].push_back(taken);
        }
    });
    std::vector<std::uint32_t> offsets(n + 1, 0);
    std::vector<std::uint32_t> nbr;
    std::vector<float> dist;
    for (std::size_t b = 0; b < blocks; ++b) {
        const std::size_t first = b * kBlock;
        for (std::size_t k = 0; k < block_count[b].size(); ++k) offsets[first + k + 1] = offsets[first + k] + block_count[b][k];
        nbr.insert(nbr.end(), block_nbr[b].begin(), block_nbr[b].end());
        dist.insert(dist.end(), block_dist[b].begin(), block_dist[b].end());
        std::vector<std::uint32_t>().swap(block_nbr[b]);
        std::vector<float>().swap(block_dist[b]);
    }
    std::vector<double> weight(n, 0.0);
    auto w = [&](float d) { const double x = 1.0 - static_cast<double>(d) / r2; return x * x * x * x * x * x * x * x; };
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) weight[i] += w(dist[e]);
    std::priority_queue<std::pair<double, std::uint32_t>> heap;
    for (std::size_t i = 0; i < n; ++i) heap.push({weight[i], static_cast<std::uint32_t>(i)});
    std::vector<char> removed(n, 0);
    std::size_t alive = n;
    while (alive > keep && !heap.empty()) {
        const auto [wt, i] = heap.top();
        heap.pop();
        if (removed[i] || wt != weight[i]) continue;  // stale entry (weights only decrease)
        removed[i] = 1;
        --alive;
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
            const std::uint32_t j = nbr[e];
            if (removed[j]) continue;
            weight[j] -= w(dist[e]);
            heap.push({weight[j], j});
        }
    }
    for (std::size_t i = 0; i < n; ++i)
        if (!removed[i]) kept.push_back(static_cast<std::uint32_t>(i));
    return kept;
}

glm::vec4 sample_texture(const Image& img, glm::vec2 uv) {
    if (img.width <= 0 || img.height <= 0) return glm::vec4(1.0f);
    const float fx = (uv.x - std::floor(uv.x)) * static_cast<float>(img.width) - 0.5f;
    const float fy = (uv.y - std::floor(uv.y)) * static_cast<float>(img.height) - 0.5f;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const float tx = fx - static_cast<float>(x0), ty = fy - static_cast<float>(y0);
    auto texel = [&](int x, int y) {
        x = ((x % img.width) + img.width) % img.width;
        y = ((y % img.height) + img.height) % img.height;
        const std::uint8_t* p = &img.rgba8[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x)) * 4];
        return glm::vec4(p[0], p[1], p[2], p[3]) / 255.0f;
    };
    return glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), tx), glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), tx), ty);
}

}  // namespace

Result<Geometry> sample_surface(const Geometry& mesh, std::size_t count, std::uint32_t seed) {
    const std::size_t nt = mesh.triangle_count();
    if (nt == 0) return make_error(mesh.source + ": no triangles to sample");
    if (count == 0) return make_error(mesh.source + ": cannot sample 0 splats");
    std::vector<double> cumulative(nt);
    double total = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
        const glm::dvec3& a = mesh.positions[mesh.triangles[3 * t]];
        const glm::dvec3& b = mesh.positions[mesh.triangles[3 * t + 1]];
        const glm::dvec3& c = mesh.positions[mesh.triangles[3 * t + 2]];
        total += 0.5 * glm::length(glm::cross(b - a, c - a));
        cumulative[t] = total;
    }
    if (!(total > 0.0) || !std::isfinite(total)) return make_error(mesh.source + ": the mesh has no surface area");
    // Candidates: 4x the target (1x beyond 4M splats to bound memory), then thin to exactly `count`.
    const std::size_t candidates = count <= (std::size_t(4) << 20) ? 4 * count : count;
    Rng rng(seed);
    std::vector<glm::dvec3> pos(candidates);
    std::vector<std::uint32_t> tri(candidates);
    std::vector<glm::dvec2> bary(candidates);
    for (std::size_t i = 0; i < candidates; ++i) {
        const double r = rng.uniform() * total;
        const std::size_t t = std::min<std::size_t>(static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin()), nt - 1);
        double u = rng.uniform(), v = rng.uniform();
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        const glm::dvec3& a = mesh.positions[mesh.triangles[3 * t]];
        const glm::dvec3& b = mesh.positions[mesh.triangles[3 * t + 1]];
        const glm::dvec3& c = mesh.positions[mesh.triangles[3 * t + 2]];
        pos[i] = a + u * (b - a) + v * (c - a);
        tri[i] = static_cast<std::uint32_t>(t);
        bary[i] = glm::dvec2(u, v);
    }
    std::vector<std::uint32_t> kept = eliminate(pos, count, total);
    // Spatial locality for the renderer and the cache: order samples by triangle.
    std::stable_sort(kept.begin(), kept.end(), [&](std::uint32_t x, std::uint32_t y) { return tri[x] < tri[y]; });

    Geometry out;
    out.source = mesh.source;
    out.attributes = mesh.attributes;
    const bool vertex_normals = mesh.normals.size() == mesh.positions.size();
    const bool bake_colour = !mesh.colors.empty() || !mesh.materials.empty();
    out.positions.reserve(count);
    out.normals.reserve(count);
    if (bake_colour) out.colors.reserve(count);
    for (std::uint32_t i : kept) {
        const std::size_t t = tri[i];
        const std::uint32_t ia = mesh.triangles[3 * t], ib = mesh.triangles[3 * t + 1], ic = mesh.triangles[3 * t + 2];
        const double u = bary[i].x, v = bary[i].y, w0 = 1.0 - u - v;
        out.positions.push_back(pos[i]);
        const glm::dvec3 face = glm::cross(mesh.positions[ib] - mesh.positions[ia], mesh.positions[ic] - mesh.positions[ia]);
        glm::dvec3 n = glm::length(face) > 0.0 ? glm::normalize(face) : glm::dvec3(0, 0, 1);
        if (vertex_normals) {
            const glm::dvec3 vn = w0 * glm::dvec3(mesh.normals[ia]) + u * glm::dvec3(mesh.normals[ib]) + v * glm::dvec3(mesh.normals[ic]);
            if (glm::length(vn) > 1e-12) n = glm::normalize(vn);
        }
        out.normals.emplace_back(n);
        if (bake_colour) {
            glm::vec4 col(1.0f);
            if (!mesh.colors.empty())
                col = static_cast<float>(w0) * unpack_rgba(mesh.colors[ia]) + static_cast<float>(u) * unpack_rgba(mesh.colors[ib]) +
                      static_cast<float>(v) * unpack_rgba(mesh.colors[ic]);
            const int m = mesh.triangle_material.empty() ? (mesh.materials.size() == 1 ? 0 : -1) : mesh.triangle_material[t];
            if (m >= 0) {
                const MeshMaterial& mat = mesh.materials[static_cast<std::size_t>(m)];
                col *= mat.base_color;
                if (mat.texture >= 0 && !mesh.uvs.empty()) {
                    const glm::vec2 uv = static_cast<float>(w0) * mesh.uvs[ia] + static_cast<float>(u) * mesh.uvs[ib] +
                                         static_cast<float>(v) * mesh.uvs[ic];
                    col *= sample_texture(mesh.textures[static_cast<std::size_t>(mat.texture)], uv);
                }
            }
            out.colors.push_back(pack_rgba(col.x, col.y, col.z, col.w));
        }
    }
    return out;
}

Result<SplatCloud> make_splat_cloud(const Geometry& input, const ImportOptions& options) {
    const Geometry* g = &input;
    Geometry resampled;
    bool resampled_points = false;
    constexpr std::size_t kMaxSplats = std::size_t(1) << 28;  // 268M: beyond that memory, not the file, is the limit
    if (options.splats > kMaxSplats)
        return make_error(input.source + ": " + std::to_string(options.splats) + " splats requested; at most " + std::to_string(kMaxSplats));
    std::size_t mesh_splats = options.splats;
    if (input.triangle_count() > 0 && mesh_splats == 0 && options.min_mesh_splats > 0) {
        std::vector<char> used(input.positions.size(), 0);
        for (std::uint32_t v : input.triangles) used[v] = 1;
        if (static_cast<std::size_t>(std::count(used.begin(), used.end(), 1)) < options.min_mesh_splats) mesh_splats = options.min_mesh_splats;
    }
    if (input.triangle_count() > 0 && mesh_splats == 0) {
        // One splat per vertex used by a face (stray vertices are not part of the surface); normals are
        // the area-weighted face normals unless the file has its own.
        std::vector<glm::dvec3> acc(input.positions.size(), glm::dvec3(0.0));
        std::vector<char> used(input.positions.size(), 0);
        std::vector<std::int32_t> material_of(input.positions.size(), -1);
        for (std::size_t t = 0; t < input.triangle_count(); ++t) {
            const std::uint32_t a = input.triangles[3 * t], b = input.triangles[3 * t + 1], c = input.triangles[3 * t + 2];
            const glm::dvec3 n = glm::cross(input.positions[b] - input.positions[a], input.positions[c] - input.positions[a]);
            const std::int32_t m = input.triangle_material.empty() ? (input.materials.size() == 1 ? 0 : -1) : input.triangle_material[t];
            for (std::uint32_t v : {a, b, c}) {
                acc[v] += n;
                used[v] = 1;
                if (m >= 0) material_of[v] = m;
            }
        }
        const bool bake = std::any_of(material_of.begin(), material_of.end(), [](std::int32_t m) { return m >= 0; });
        const bool file_normals = input.normals.size() == input.positions.size();
        resampled.source = input.source;
        resampled.attributes = input.attributes;
        resampled.splat_material = input.splat_material;
        resampled.has_origin = input.has_origin;
        resampled.origin = input.origin;
        for (std::size_t i = 0; i < input.positions.size(); ++i) {
            if (!used[i]) continue;
            resampled.positions.push_back(input.positions[i]);
            const double len = glm::length(acc[i]);
            resampled.normals.push_back(file_normals ? input.normals[i] : (len > 0.0 ? glm::vec3(acc[i] / len) : glm::vec3(0.0f)));
            if (bake) {
                // Vertex colour x base colour x texture at the vertex's uv (materials are not kept per splat).
                glm::vec4 col = input.colors.empty() ? glm::vec4(1.0f) : unpack_rgba(input.colors[i]);
                if (const std::int32_t m = material_of[i]; m >= 0) {
                    const MeshMaterial& mat = input.materials[static_cast<std::size_t>(m)];
                    col *= mat.base_color;
                    if (mat.texture >= 0 && !input.uvs.empty()) col *= sample_texture(input.textures[static_cast<std::size_t>(mat.texture)], input.uvs[i]);
                }
                resampled.colors.push_back(pack_rgba(col.x, col.y, col.z, col.w));
            } else if (!input.colors.empty()) {
                resampled.colors.push_back(input.colors[i]);
            }
            if (!input.uvs.empty()) resampled.uvs.push_back(input.uvs[i]);
        }
        // Degenerate faces only: let PCA decide.
        if (std::any_of(resampled.normals.begin(), resampled.normals.end(), [](const glm::vec3& n) { return glm::length(n) < 0.5f; }))
            resampled.normals.clear();
        g = &resampled;
        resampled_points = true;
    } else if (input.triangle_count() > 0) {
        auto s = sample_surface(input, mesh_splats, options.seed);
        if (!s) return s.error();
        resampled = std::move(*s);
        g = &resampled;
        resampled_points = true;
    } else if (options.splats && options.splats != input.positions.size()) {
        if (options.splats > input.positions.size())
            return make_error(input.source + ": cannot make " + std::to_string(options.splats) + " splats from " +
                              std::to_string(input.positions.size()) + " points without faces");
        // Thin evenly: the area estimate only sets the neighbourhood radius; use the bbox surface.
        glm::dvec3 lo(input.positions[0]), hi(input.positions[0]);
        for (const auto& p : input.positions) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        const glm::dvec3 e = hi - lo;
        const double area = std::max(2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) * 0.5, 1e-30);
        const auto kept = eliminate(input.positions, options.splats, area);
        resampled.source = input.source;
        resampled.attributes = input.attributes;
        resampled.splat_material = input.splat_material;
        resampled.has_origin = input.has_origin;
        resampled.origin = input.origin;
        for (std::uint32_t i : kept) {
            resampled.positions.push_back(input.positions[i]);
            if (!input.normals.empty()) resampled.normals.push_back(input.normals[i]);
            if (!input.colors.empty()) resampled.colors.push_back(input.colors[i]);
            if (!input.uvs.empty()) resampled.uvs.push_back(input.uvs[i]);
        }
        g = &resampled;
        resampled_points = true;
    }
    if (g->positions.empty()) return make_error(input.source + ": no points");

    SplatCloud cloud;
    cloud.origin = g->has_origin ? g->origin : choose_origin(g->positions);
    cloud.positions.resize(g->positions.size());
    for (std::size_t i = 0; i < g->positions.size(); ++i) cloud.positions[i] = glm::vec3(g->positions[i] - cloud.origin);
    bool normals_ok = g->normals.size() == g->positions.size();
    if (normals_ok) {
        cloud.normals = g->normals;
        for (glm::vec3& n : cloud.normals) {
            const float len = glm::length(n);
            if (!(len > 1e-6f)) {
                normals_ok = false;
                break;
            }
            if (std::abs(len - 1.0f) > 1e-5f) n /= len;
        }
    }
    cloud.colors = g->colors;
    cloud.material = g->splat_material;
    if (g->uvs.size() == g->positions.size()) cloud.uvs = g->uvs;
    const bool axes_ok = !resampled_points && g->axis_u.size() == g->positions.size();
    if (axes_ok) {
        cloud.axis_u = g->axis_u;
        cloud.axis_v = g->axis_v;
    }
    EstimateOptions est;
    est.normals = options.estimate_normals || !normals_ok;
    est.radii = options.estimate_radii || !axes_ok || est.normals;
    est.k = options.neighbours;
    if (!normals_ok) cloud.normals.clear();
    estimate_splats(cloud, est);
    return cloud;
}

Result<SplatCloud> import_splat_cloud(const fs::path& path, const ImportOptions& options) {
    // Our own single-cloud glTF/GLB files come back exactly as stored (no float re-centring).
    const std::string ext = lower_ext(path);
    const bool defaults = options.splats == 0 && !options.estimate_normals && !options.estimate_radii;
    if (defaults && (ext == ".glb" || ext == ".gltf")) {
        auto contents = read_gltf(path);
        if (!contents) return contents.error();
        const Transform identity;
        if (contents->clouds.size() == 1 && contents->other.positions.empty()) {
            const GltfCloudIn& c = contents->clouds[0];
            if (c.transform.translation == identity.translation && c.transform.rotation == identity.rotation &&
                c.transform.scale == identity.scale && c.cloud.axis_u.size() == c.cloud.size() && c.cloud.normals.size() == c.cloud.size())
                return c.cloud;
        }
    }
    auto g = read_geometry(path);
    if (!g) return g.error();
    return make_splat_cloud(*g, options);
}

}  // namespace sffd::assets
