// PLY geometry, read_geometry() dispatch, and the splat-cloud step (make_splat_cloud, import_splat_cloud).
// OBJ: obj.cpp, OFF: off.cpp, surface sampling: surface_sampling.cpp, shared helpers: import_detail.h.
#include "runtime/assets/import.h"

#include "runtime/assets/formats/surface/potree2.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/import_detail.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_vertices.h"
#include "runtime/assets/splat_estimation.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"

namespace sffd::assets {
namespace fs = std::filesystem;
using namespace detail;

namespace {

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
    // PlayCanvas's compressed Gaussian PLY packs positions into chunks: say so instead of "no x, y, z".
    if (h.find("chunk") >= 0 && ve.find("packed_position") >= 0)
        return make_error(g.source +
                          ": a compressed (PlayCanvas) Gaussian PLY, not a point cloud: read it as Gaussians "
                          "(convert --gaussians, render, view)");
    if (px < 0 || py < 0 || pz < 0)
        return make_error(g.source + ": vertex element has no x, y, z properties");
    for (int i : {px, py, pz})
        if (ve.properties[i].is_list)
            return make_error(g.source + ": vertex property '" + ve.properties[i].name + "' is a list");
    auto scalar = [&](int i) { return i >= 0 && !ve.properties[i].is_list ? i : -1; };
    const int nx = scalar(ve.find("nx")), ny = scalar(ve.find("ny")), nz = scalar(ve.find("nz"));
    const int cr = scalar(find_any(ve, {"red", "diffuse_red", "r"})),
              cg = scalar(find_any(ve, {"green", "diffuse_green", "g"}));
    const int cb = scalar(find_any(ve, {"blue", "diffuse_blue", "b"})),
              ca = scalar(find_any(ve, {"alpha", "diffuse_alpha", "a"}));
    const int tu = scalar(find_any(ve, {"u", "s", "texture_u", "texture_s"})),
              tv = scalar(find_any(ve, {"v", "t", "texture_v", "texture_t"}));
    const int ax[6] = {scalar(ve.find("axis_ux")), scalar(ve.find("axis_uy")), scalar(ve.find("axis_uz")),
                       scalar(ve.find("axis_vx")), scalar(ve.find("axis_vy")), scalar(ve.find("axis_vz"))};
    const bool has_axes = std::all_of(ax, ax + 6, [](int i) { return i >= 0; });
    const int uf[4] = {scalar(ve.find("du_ds")), scalar(ve.find("dv_ds")), scalar(ve.find("du_dt")),
                       scalar(ve.find("dv_dt"))};
    const bool has_uv_frame = has_axes && std::all_of(uf, uf + 4, [](int i) { return i >= 0; });
    const bool has_normals = nx >= 0 && ny >= 0 && nz >= 0;
    const bool has_colors = cr >= 0 && cg >= 0 && cb >= 0;
    const bool has_uvs = tu >= 0 && tv >= 0;
    for (const auto& p : ve.properties)
        g.attributes.push_back(std::string(ply::type_name(p.type)) + (p.is_list ? "[] " : " ") + p.name);

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
            g.splat_texture.path = c.substr(12);
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
    if (has_uv_frame) g.uv_axes.reserve(n);
    PlyVertexColumns columns;
    columns.pos[0] = px, columns.pos[1] = py, columns.pos[2] = pz;
    columns.normal[0] = nx, columns.normal[1] = ny, columns.normal[2] = nz;
    columns.color[0] = cr, columns.color[1] = cg, columns.color[2] = cb, columns.color[3] = ca;
    for (int c = 0; c < 4; ++c)
        if (columns.color[c] >= 0)
            columns.color_scale[c] = channel_scale(ve.properties[columns.color[c]].type);
    columns.uv[0] = tu, columns.uv[1] = tv;
    std::copy(ax, ax + 6, columns.axes), std::copy(uf, uf + 4, columns.uv_frame);
    columns.has_normals = has_normals, columns.has_colors = has_colors, columns.has_uvs = has_uvs;
    columns.has_axes = has_axes, columns.has_uv_frame = has_uv_frame;
    // Binary little-endian rows are decoded in place from the mapped file; other files go through the
    // columns.
    const auto mapped = read_ply_vertices_mapped(path, h, columns, g);
    if (mapped && !*mapped) return mapped->error();
    if (!mapped)
        if (auto s = reader->seek_element("vertex"); !s) return s.error();
    ply::Chunk chunk;
    while (!mapped) {
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
                    return make_error(g.source + ": vertex " + std::to_string(g.positions.size() - 1) +
                                      " has a non-finite colour");
                g.colors.push_back(pack_rgba(col(cr)[r] * sr, col(cg)[r] * sg, col(cb)[r] * sb, a));
            }
            if (has_uvs) g.uvs.emplace_back(col(tu)[r], col(tv)[r]);
            if (has_axes) {
                g.axis_u.emplace_back(col(ax[0])[r], col(ax[1])[r], col(ax[2])[r]);
                g.axis_v.emplace_back(col(ax[3])[r], col(ax[4])[r], col(ax[5])[r]);
            }
            if (has_uv_frame)
                g.uv_axes.emplace_back(col(uf[0])[r], col(uf[1])[r], col(uf[2])[r], col(uf[3])[r]);
        }
    }
    // Faces (any element named "face" with a vertex index list), triangulated as fans.
    if (const int fi = h.find("face");
        fi >= 0 && static_cast<std::size_t>(fi) > static_cast<std::size_t>(vi)) {
        const ply::Element& fe = h.elements[fi];
        const int li = find_any(fe, {"vertex_indices", "vertex_index"});
        if (li < 0 || !fe.properties[li].is_list)
            return make_error(g.source + ": face element has no vertex_indices list");
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
                        return make_error(g.source + ": face refers to vertex " +
                                          std::to_string(static_cast<long long>(c.values[k])) +
                                          " but there are only " + std::to_string(n));
                if (e - b > kMaxFaceVertices)
                    return make_error(g.source + ": face " + std::to_string(faces_seen + r) + " has " +
                                      std::to_string(e - b) + " vertices; at most " +
                                      std::to_string(kMaxFaceVertices) +
                                      " per face (fan triangulation budget)");
                if (e - b > 2 && g.triangles.size() / 3 + (e - b - 2) > kMaxTriangles)
                    return make_error(g.source + ": faces expand to more than " +
                                      std::to_string(kMaxTriangles) +
                                      " triangles (the import budget); face lists of up to " +
                                      std::to_string(e - b) + " vertices");
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
    if (!g.splat_texture.path.empty()) {
        std::uint64_t budget = kDecodedTextureBudget;
        bool missing = false;
        if (auto img = load_named_image(path, g.splat_texture.path, g.source, &budget, missing); img) {
            g.splat_texture.width = img->width;
            g.splat_texture.height = img->height;
            g.splat_texture.rgba8 = std::move(img->rgba8);
        } else if (missing) {
            log::warn(g.source, ": texture not loaded: ", img.message());
        } else {
            return img.error();
        }
    }
    if (auto s = check_geometry(g); !s) return s.error();
    return g;
}

Result<Geometry> read_geometry(const fs::path& path) {
    const std::string ext = lower_ext(path);
    std::error_code ec;
    if (!fs::exists(path, ec)) return make_error(path.string() + ": no such file");
    if (path.filename() == "metadata.json") return read_potree2_geometry(path);
    if (ext == ".ply") return read_ply_geometry(path);
    if (ext == ".obj") return read_obj_geometry(path);
    if (ext == ".off") return read_off_geometry(path);
    if (ext == ".gltf" || ext == ".glb") return read_gltf_geometry(path);
    return make_error(path.string() + ": unknown file type '" + ext +
                      "' (expected .ply, .obj, .off, .gltf, .glb or a Potree 2 octree's metadata.json)");
}

Result<SplatCloud> make_splat_cloud(const Geometry& input, const ImportOptions& options) {
    const Geometry* g = &input;
    Geometry resampled;
    bool resampled_points = false;
    constexpr std::size_t kMaxSplats = std::size_t(1)
                                       << 28;  // 268M: beyond that memory, not the file, is the limit
    if (options.splats > kMaxSplats)
        return make_error(input.source + ": " + std::to_string(options.splats) +
                          " splats requested; at most " + std::to_string(kMaxSplats));
    std::size_t mesh_splats = options.splats;
    if (input.triangle_count() > 0 && mesh_splats == 0 && options.min_mesh_splats > 0) {
        std::vector<char> used(input.positions.size(), 0);
        for (std::uint32_t v : input.triangles) used[v] = 1;
        if (static_cast<std::size_t>(std::count(used.begin(), used.end(), 1)) < options.min_mesh_splats)
            mesh_splats = options.min_mesh_splats;
    }
    // A stored uv frame (our files) as texture-space gradients, so it survives thinning and re-estimated
    // axes: the gradient in the span of the stored axes that reproduces the frame along them.
    std::vector<glm::vec3> file_grad_u, file_grad_v;
    if (const std::size_t n = input.positions.size();
        input.uv_axes.size() == n && input.axis_u.size() == n && input.uvs.size() == n) {
        file_grad_u.resize(n);
        file_grad_v.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::vec4 f = input.uv_axes[i];
            glm::dvec3 gu, gv;
            triangle_uv_gradients(glm::dvec3(0.0), glm::dvec3(input.axis_u[i]), glm::dvec3(input.axis_v[i]),
                                  glm::dvec2(0.0), glm::dvec2(f.x, f.y), glm::dvec2(f.z, f.w), gu, gv);
            file_grad_u[i] = glm::vec3(gu);
            file_grad_v[i] = glm::vec3(gv);
        }
    }
    if (input.triangle_count() > 0 && mesh_splats == 0) {
        // One splat per vertex used by a face (stray vertices are not part of the surface); normals are
        // the area-weighted face normals unless the file has its own.
        std::vector<glm::dvec3> acc(input.positions.size(), glm::dvec3(0.0));
        // One texture over the mesh: kept, with each vertex's uv gradients the area-weighted mean of its
        // triangles' (a vertex on a uv seam is a separate vertex in OBJ/glTF, so the mean stays on one side).
        const int texture = single_texture(input);
        std::vector<glm::dvec3> acc_gu, acc_gv;
        std::vector<double> acc_area;
        if (texture >= 0) {
            acc_gu.assign(input.positions.size(), glm::dvec3(0.0));
            acc_gv.assign(input.positions.size(), glm::dvec3(0.0));
            acc_area.assign(input.positions.size(), 0.0);
            for (std::size_t t = 0; t < input.triangle_count(); ++t) {
                const std::uint32_t a = input.triangles[3 * t], b = input.triangles[3 * t + 1],
                                    c = input.triangles[3 * t + 2];
                glm::dvec3 gu, gv;
                triangle_uv_gradients(input.positions[a], input.positions[b], input.positions[c],
                                      glm::dvec2(input.uvs[a]), glm::dvec2(input.uvs[b]),
                                      glm::dvec2(input.uvs[c]), gu, gv);
                const double area = 0.5 * glm::length(glm::cross(input.positions[b] - input.positions[a],
                                                                 input.positions[c] - input.positions[a]));
                for (std::uint32_t v : {a, b, c})
                    acc_gu[v] += area * gu, acc_gv[v] += area * gv, acc_area[v] += area;
            }
        }
        std::vector<char> used(input.positions.size(), 0);
        std::vector<std::int32_t> material_of(input.positions.size(), -1);
        for (std::size_t t = 0; t < input.triangle_count(); ++t) {
            const std::uint32_t a = input.triangles[3 * t], b = input.triangles[3 * t + 1],
                                c = input.triangles[3 * t + 2];
            const glm::dvec3 n =
                glm::cross(input.positions[b] - input.positions[a], input.positions[c] - input.positions[a]);
            const std::int32_t m = input.triangle_material.empty() ? (input.materials.size() == 1 ? 0 : -1)
                                                                   : input.triangle_material[t];
            for (std::uint32_t v : {a, b, c}) {
                acc[v] += n;
                used[v] = 1;
                if (m >= 0) material_of[v] = m;
            }
        }
        const bool bake =
            std::any_of(material_of.begin(), material_of.end(), [](std::int32_t m) { return m >= 0; });
        const bool file_normals = input.normals.size() == input.positions.size();
        resampled.source = input.source;
        resampled.attributes = input.attributes;
        resampled.splat_texture = input.splat_texture;
        resampled.splat_material = input.splat_material;
        resampled.has_origin = input.has_origin;
        resampled.origin = input.origin;
        for (std::size_t i = 0; i < input.positions.size(); ++i) {
            if (!used[i]) continue;
            resampled.positions.push_back(input.positions[i]);
            const double len = glm::length(acc[i]);
            resampled.normals.push_back(
                file_normals ? input.normals[i] : (len > 0.0 ? glm::vec3(acc[i] / len) : glm::vec3(0.0f)));
            if (bake) {
                // Vertex colour x base colour x texture at the vertex's uv (materials are not kept per
                // splat).
                glm::vec4 col = input.colors.empty() ? glm::vec4(1.0f) : unpack_rgba(input.colors[i]);
                if (const std::int32_t m = material_of[i]; m >= 0) {
                    const MeshMaterial& mat = input.materials[static_cast<std::size_t>(m)];
                    col *= mat.base_color;
                    if (mat.texture >= 0 && !input.uvs.empty())
                        col *= sample_texture(input.textures[static_cast<std::size_t>(mat.texture)],
                                              input.uvs[i]);
                }
                resampled.colors.push_back(pack_rgba(col.x, col.y, col.z, col.w));
            } else if (!input.colors.empty()) {
                resampled.colors.push_back(input.colors[i]);
            }
            if (!input.uvs.empty()) resampled.uvs.push_back(input.uvs[i]);
            if (texture >= 0) {
                const double w = acc_area[i] > 0.0 ? 1.0 / acc_area[i] : 0.0;
                resampled.uv_grad_u.emplace_back(w * acc_gu[i]);
                resampled.uv_grad_v.emplace_back(w * acc_gv[i]);
            }
        }
        if (texture >= 0) {
            const Image& img = input.textures[static_cast<std::size_t>(texture)];
            resampled.splat_texture.width = img.width;
            resampled.splat_texture.height = img.height;
            resampled.splat_texture.rgba8 = img.rgba8;
        }
        // Degenerate faces only: let PCA decide.
        if (std::any_of(resampled.normals.begin(), resampled.normals.end(),
                        [](const glm::vec3& n) { return glm::length(n) < 0.5f; }))
            resampled.normals.clear();
        g = &resampled;
        resampled_points = true;
    } else if (input.triangle_count() > 0) {
        auto s = sample_surface(input, mesh_splats, options.seed, options.progress);
        if (!s) return s.error();
        resampled = std::move(*s);
        g = &resampled;
        resampled_points = true;
    } else if (options.splats && options.splats != input.positions.size()) {
        if (options.splats > input.positions.size())
            return make_error(input.source + ": cannot make " + std::to_string(options.splats) +
                              " splats from " + std::to_string(input.positions.size()) +
                              " points without faces");
        // Thin evenly: the area estimate only sets the neighbourhood radius; use the bbox surface.
        glm::dvec3 lo(input.positions[0]), hi(input.positions[0]);
        for (const auto& p : input.positions) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        const glm::dvec3 e = hi - lo;
        const double area = std::max(2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) * 0.5, 1e-30);
        const auto kept = eliminate(input.positions, options.splats, area, options.progress);
        resampled.source = input.source;
        resampled.attributes = input.attributes;
        resampled.splat_texture = input.splat_texture;
        resampled.splat_material = input.splat_material;
        resampled.has_origin = input.has_origin;
        resampled.origin = input.origin;
        for (std::uint32_t i : kept) {
            resampled.positions.push_back(input.positions[i]);
            if (!input.normals.empty()) resampled.normals.push_back(input.normals[i]);
            if (!input.colors.empty()) resampled.colors.push_back(input.colors[i]);
            if (!input.uvs.empty()) resampled.uvs.push_back(input.uvs[i]);
            if (!file_grad_u.empty())
                resampled.uv_grad_u.push_back(file_grad_u[i]), resampled.uv_grad_v.push_back(file_grad_v[i]);
        }
        g = &resampled;
        resampled_points = true;
    }
    if (g->positions.empty()) return make_error(input.source + ": no points");

    SplatCloud cloud;
    cloud.origin = g->has_origin ? g->origin : choose_origin(g->positions);
    cloud.positions.resize(g->positions.size());
    for (std::size_t i = 0; i < g->positions.size(); ++i)
        cloud.positions[i] = glm::vec3(g->positions[i] - cloud.origin);
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
    cloud.texture = g->splat_texture;
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
    est.progress = options.progress;
    if (!normals_ok) cloud.normals.clear();
    estimate_splats(cloud, est);
    // The uv frame along the final axes: as stored when the stored axes were kept, else from the
    // texture-space gradients (mesh sampling, or the stored frame re-expressed).
    const std::size_t n = cloud.size();
    if (cloud.uvs.size() == n && cloud.axis_u.size() == n) {
        const std::vector<glm::vec3>* gu =
            g->uv_grad_u.size() == n ? &g->uv_grad_u
                                     : (g == &input && file_grad_u.size() == n ? &file_grad_u : nullptr);
        const std::vector<glm::vec3>* gv = gu == &g->uv_grad_u ? &g->uv_grad_v : &file_grad_v;
        if (g == &input && axes_ok && !est.radii && input.uv_axes.size() == n) {
            cloud.uv_axes = input.uv_axes;
        } else if (gu) {
            cloud.uv_axes.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                cloud.uv_axes[i] =
                    uv_frame(glm::dvec3((*gu)[i]), glm::dvec3((*gv)[i]), cloud.axis_u[i], cloud.axis_v[i]);
        }
    }
    return cloud;
}

Result<SplatCloud> import_splat_cloud(const fs::path& path, const ImportOptions& options,
                                      SplatMaterial* material) {
    // Our own single-cloud glTF/GLB files come back exactly as stored (no float re-centring).
    const std::string ext = lower_ext(path);
    const bool defaults = options.splats == 0 && !options.estimate_normals && !options.estimate_radii;
    if (defaults && (ext == ".glb" || ext == ".gltf")) {
        auto contents = read_gltf(path);
        if (!contents) return contents.error();
        const Transform identity;
        if (contents->clouds.size() == 1 && contents->other.positions.empty()) {
            const GltfCloudIn& c = contents->clouds[0];
            if (c.transform.translation == identity.translation &&
                c.transform.rotation == identity.rotation && c.transform.scale == identity.scale &&
                c.cloud.axis_u.size() == c.cloud.size() && c.cloud.normals.size() == c.cloud.size()) {
                if (material) *material = c.material;
                return c.cloud;
            }
        }
    }
    if (defaults && path.filename() == "metadata.json") {  // our own Potree 2 octree, at full detail
        auto octree = open_potree2(path);
        if (!octree) return octree.error();
        if (octree->attribute("sffd_axis_u")) return read_potree2(*octree);
    }
    auto g = read_geometry(path);
    if (!g) return g.error();
    if (material) *material = g->splat_material;
    return make_splat_cloud(*g, options);
}

}  // namespace sffd::assets
