// OBJ (v, vn, vt, f, mtllib/usemtl with Kd and map_Kd; vertex colours "v x y z r g b"). Material
// libraries and their textures resolve only inside the folder of the file that names them.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "runtime/assets/import_detail.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using namespace detail;

namespace {

// OBJ/MTL files written on Windows name files with backslashes (assimp's spider.mtl: "map_Kd
// .\SpiderTex.jpg"). A backslash is taken as a folder separator, so the name still goes through
// resolve_resource (".\..\x" becomes "./../x" and is refused as an escape like any other).
std::string portable_name(std::string name) {
    std::replace(name.begin(), name.end(), '\\', '/');
    return name;
}

// Loads `name` (an mtllib line of the OBJ `obj`): an error when it is outside the OBJ's folder or not a
// regular file, a warning when missing. Its map_Kd textures resolve inside the MTL's own folder.
Status load_mtl(const fs::path& obj, const std::string& name, Geometry& g,
                std::unordered_map<std::string, int>& by_name, std::uint64_t& texture_budget) {
    auto mtl_path = resolve_resource(obj, portable_name(name));
    if (!mtl_path) {
        if (mtl_path.message().size() >= 9 &&
            mtl_path.message().compare(mtl_path.message().size() - 9, 9, "not found") == 0) {
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
            if (c.next(a) && c.next(b) && c.next(d) && to_double(a, r) && to_double(b, gg) &&
                to_double(d, bb) && std::isfinite(r + gg + bb))
                g.materials[current].base_color =
                    glm::vec4(static_cast<float>(r), static_cast<float>(gg), static_cast<float>(bb),
                              g.materials[current].base_color.w);
        } else if (current >= 0 && key == "d") {
            std::string_view a;
            double d = 1;
            if (c.next(a) && to_double(a, d) && std::isfinite(d))
                g.materials[current].base_color.w = static_cast<float>(d);
        } else if (current >= 0 && key == "map_Kd") {
            std::string file = c.rest();
            // Options such as "-s 1 1 1" come before the file name; the name is the last word.
            if (auto sp = file.find_last_of(' '); sp != std::string::npos) file = file.substr(sp + 1);
            bool missing = false;
            auto img = load_named_image(*mtl_path, portable_name(file), g.source, &texture_budget, missing);
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
    std::vector<Corner> corners;  // 3 per triangle
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
                if (!to_double(tok, d[count]))
                    return fail("malformed number '" + std::string(tok.substr(0, 40)) + "'");
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
                    if (!part.empty() && !to_long(part, *slots[s]))
                        return fail("malformed face index '" + std::string(tok.substr(0, 40)) + "'");
                    start = slash + 1;
                }
                // Negative indices count back from the latest element; resolve to 1-based now.
                auto resolve = [](long long& i, std::size_t size) {
                    if (i < 0) i = static_cast<long long>(size) + i + 1;
                };
                resolve(k.v, v.size());
                resolve(k.t, vt.size());
                resolve(k.n, vn.size());
                if (k.v < 1 || k.v > static_cast<long long>(v.size()))
                    return fail("face refers to missing vertex " + std::to_string(k.v));
                if (k.t < 0 || k.t > static_cast<long long>(vt.size()))
                    return fail("face refers to missing texture coordinate");
                if (k.n < 0 || k.n > static_cast<long long>(vn.size()))
                    return fail("face refers to missing normal");
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
    if (!vcolor.empty() && vcolor.size() != v.size())
        vcolor.clear();  // colours on some vertices only: ignore
    const bool by_corner =
        std::any_of(corners.begin(), corners.end(), [](const Corner& k) { return k.t > 0 || k.n > 0; });
    if (!by_corner) {
        g.positions = std::move(v);
        g.colors = std::move(vcolor);
        for (const Corner& k : corners) g.triangles.push_back(static_cast<std::uint32_t>(k.v - 1));
    } else {
        // Texture seams and hard edges need separate vertices: one per distinct (v, vt, vn) triple.
        std::unordered_map<std::uint64_t, std::uint32_t> seen;
        const bool has_t = !vt.empty(), has_n = !vn.empty();
        auto key_of = [](const Corner& k) {
            return (static_cast<std::uint64_t>(k.v) * 0x9E3779B1ull) ^
                   (static_cast<std::uint64_t>(k.t) << 42) ^ (static_cast<std::uint64_t>(k.n) << 21);
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
        if (has_n && std::any_of(uniq.begin(), uniq.end(), [](const Corner& k) { return k.n == 0; }))
            g.normals.clear();
    }
    if (!g.materials.empty() && !tri_mat.empty()) g.triangle_material = std::move(tri_mat);
    g.attributes = {"position"};
    if (!g.normals.empty()) g.attributes.push_back("normal");
    if (!g.uvs.empty()) g.attributes.push_back("texcoord");
    if (!g.colors.empty()) g.attributes.push_back("color");
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

}  // namespace sffd::assets
