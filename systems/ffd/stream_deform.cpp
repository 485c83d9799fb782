// Surface splats streamed through lattices (stream_deform.h); 3DGS files go to stream_deform_gaussian.cpp.
// Each chunk's columns are doubles (a lossless copy of the file): the float backends deform them relative
// to each lattice's origin (far-away scans keep their precision) and write back only the rows they changed,
// so points outside every lattice keep their exact values.
#include "systems/ffd/stream_deform.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/splat_estimation.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/stream_deform_gaussian.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

namespace sffd::ffd {

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kChunkRows = 1 << 17;  // ~131k rows: ~10 MB of double columns for 10 properties

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Vertex columns the deformation reads and writes (-1: absent).
struct VertexColumns {
    int x = -1, y = -1, z = -1;
    int n[3] = {-1, -1, -1};
    int u[3] = {-1, -1, -1}, v[3] = {-1, -1, -1};
    int radius = -1;
    int weight = -1;  // PointWeights: the deformation's per-point weight, read and written back unchanged
    bool normals() const { return n[0] >= 0 && n[1] >= 0 && n[2] >= 0; }
    bool axes() const { return u[0] >= 0 && u[1] >= 0 && u[2] >= 0 && v[0] >= 0 && v[1] >= 0 && v[2] >= 0; }
};

int scalar_property(const ply::Element& e, const char* name) {
    const int i = e.find(name);
    return i >= 0 && !e.properties[std::size_t(i)].is_list ? i : -1;
}

VertexColumns find_columns(const ply::Element& ve) {
    VertexColumns c;
    c.x = ve.find("x"), c.y = ve.find("y"), c.z = ve.find("z");
    const char* n[3] = {"nx", "ny", "nz"};
    const char* u[3] = {"axis_ux", "axis_uy", "axis_uz"};
    const char* v[3] = {"axis_vx", "axis_vy", "axis_vz"};
    for (int a = 0; a < 3; ++a)
        c.n[a] = scalar_property(ve, n[a]), c.u[a] = scalar_property(ve, u[a]),
        c.v[a] = scalar_property(ve, v[a]);
    if (!c.normals()) c.n[0] = c.n[1] = c.n[2] = -1;
    if (!c.axes()) c.u[0] = c.u[1] = c.u[2] = c.v[0] = c.v[1] = c.v[2] = -1;
    c.radius = scalar_property(ve, "radius");
    c.weight = assets::ply_weight_property(ve);
    return c;
}

// The header checks every stream makes first: the vertex element and its scalar x y z.
Result<int> vertex_element(const ply::Header& h, const std::string& path) {
    const int vi = h.find("vertex");
    if (vi < 0) return make_error(path + ": no vertex element");
    const ply::Element& ve = h.elements[std::size_t(vi)];
    const VertexColumns cols = find_columns(ve);
    if (cols.x < 0 || cols.y < 0 || cols.z < 0)
        return make_error(path + ": vertex element has no x, y, z properties");
    for (int k : {cols.x, cols.y, cols.z})
        if (ve.properties[std::size_t(k)].is_list)
            return make_error(path + ": x, y, z must be scalar properties");
    return vi;
}

// Appends float axis_u*/axis_v* properties to the vertex element (created from normals and radius).
void add_axis_properties(ply::Element& ve, VertexColumns& c) {
    const char* names[6] = {"axis_ux", "axis_uy", "axis_uz", "axis_vx", "axis_vy", "axis_vz"};
    for (int a = 0; a < 6; ++a) {
        (a < 3 ? c.u[a] : c.v[a - 3]) = int(ve.properties.size());
        ve.properties.push_back({names[a], ply::Type::float32});
    }
}

glm::dvec3 get3(const ply::Chunk& c, const int* cols, std::size_t r) {
    return {c.columns[std::size_t(cols[0])].values[r], c.columns[std::size_t(cols[1])].values[r],
            c.columns[std::size_t(cols[2])].values[r]};
}
void set3(ply::Chunk& c, const int* cols, std::size_t r, const glm::dvec3& w) {
    for (int a = 0; a < 3; ++a) c.columns[std::size_t(cols[a])].values[r] = w[a];
}

// Circular axes from the chunk's normals and its radius column (or `estimated` radii, one per vertex of
// the file, this chunk's from row `first`), in the columns add_axis_properties() made (same convention
// as import: assets::make_circular_axes).
void create_axes(ply::Chunk& c, const VertexColumns& cols, const std::vector<float>& estimated,
                 std::size_t first) {
    for (const int a : {cols.u[0], cols.u[1], cols.u[2], cols.v[0], cols.v[1], cols.v[2]})
        c.columns[std::size_t(a)].values.resize(c.rows);
    std::vector<glm::vec3> n(c.rows), u, v;
    std::vector<float> radius(c.rows);
    for (std::size_t r = 0; r < c.rows; ++r) {
        const glm::dvec3 nn = get3(c, cols.n, r);
        const double len = glm::length(nn);
        n[r] = len > 0.0 ? glm::vec3(nn / len) : glm::vec3(0, 0, 1);
        radius[r] =
            cols.radius >= 0 ? float(c.columns[std::size_t(cols.radius)].values[r]) : estimated[first + r];
    }
    assets::make_circular_axes(n, radius, u, v);
    for (std::size_t r = 0; r < c.rows; ++r)
        set3(c, cols.u, r, glm::dvec3(u[r])), set3(c, cols.v, r, glm::dvec3(v[r]));
}

// Deforms one chunk's vertex rows in place (double columns) through every lattice in order; the arrays
// are kept between chunks. Returns the deformation time in ms.
struct ChunkDeformer {
    std::span<const Lattice> lattices;
    StreamBackend backend = StreamBackend::cpu;
    GpuDeformer* gpu = nullptr;
    std::vector<glm::vec3> p, n, u, v, op, on, ou, ov;
    std::vector<float> wts;
    std::size_t inverted = 0;
    std::vector<std::size_t> inside;  // points inside each lattice (same order)
    ply::Chunk scratch;

    Result<double> run(ply::Chunk& c, const VertexColumns& cols, bool write) {
        ply::Chunk* target = &c;
        if (!write) {  // timing run: deform a copy, the chunk stays the input
            scratch = c;
            target = &scratch;
        }
        double ms = 0.0;
        for (std::size_t i = 0; i < lattices.size(); ++i) {
            auto t = backend == StreamBackend::reference
                         ? run_reference(lattices[i], *target, cols, write, inside[i])
                         : run_float(lattices[i], *target, cols, write, inside[i]);
            if (!t) return t.error();
            ms += *t;
        }
        return ms;
    }

    // Double in, double out: no float rounding at all (the reference backend's per-point evaluation).
    Result<double> run_reference(const Lattice& lattice, ply::Chunk& c, const VertexColumns& cols, bool count,
                                 std::size_t& inside_count) {
        if (Status s = validate(lattice); !s) return s.error();
        const int xyz[3] = {cols.x, cols.y, cols.z};
        const bool normals = cols.normals(), axes = cols.axes();
        const auto t0 = Clock::now();
        std::size_t inv = 0;
        for (std::size_t r = 0; r < c.rows; ++r) {
            const double w = cols.weight >= 0 ? c.columns[std::size_t(cols.weight)].values[r] : 1.0;
            const ReferencePoint rp = reference_point(lattice, get3(c, xyz, r), w);
            if (!rp.inside) continue;
            inside_count += count;
            if (!(w > 0.0)) continue;  // weight 0: unchanged
            set3(c, xyz, r, rp.position);
            const glm::dmat3& J = rp.jacobian;
            if (normals) set3(c, cols.n, r, deformed_normal(J, get3(c, cols.n, r)));
            if (axes) set3(c, cols.u, r, J * get3(c, cols.u, r)), set3(c, cols.v, r, J * get3(c, cols.v, r));
            inv += glm::determinant(J) < 0.0;
        }
        if (count) inverted += inv;
        return ms_since(t0);
    }

    // The in-engine float kernels (ffd::deform, Backend::automatic) or the GPU compute deformer.
    Result<double> run_float(const Lattice& lattice, ply::Chunk& c, const VertexColumns& cols, bool count,
                             std::size_t& inside_count) {
        const std::size_t rows = c.rows;
        const int xyz[3] = {cols.x, cols.y, cols.z};
        const bool normals = cols.normals(), axes = cols.axes();
        const glm::dvec3 o = lattice.origin;
        auto size = [rows](std::vector<glm::vec3>& a, bool used) { a.resize(used ? rows : 0); };
        size(p, true), size(op, true), size(n, normals), size(on, normals);
        size(u, axes), size(v, axes), size(ou, axes), size(ov, axes);
        wts.resize(cols.weight >= 0 ? rows : 0);
        for (std::size_t r = 0; r < rows; ++r) {
            if (cols.weight >= 0) wts[r] = float(c.columns[std::size_t(cols.weight)].values[r]);
            p[r] = glm::vec3(get3(c, xyz, r) - o);
            if (normals) n[r] = glm::vec3(get3(c, cols.n, r));
            if (axes) u[r] = glm::vec3(get3(c, cols.u, r)), v[r] = glm::vec3(get3(c, cols.v, r));
        }
        PointsIn in{p.data(),
                    normals ? n.data() : nullptr,
                    axes ? u.data() : nullptr,
                    axes ? v.data() : nullptr,
                    rows,
                    o};
        in.weights = cols.weight >= 0 ? wts.data() : nullptr;
        const PointsOut out{op.data(), normals ? on.data() : nullptr, axes ? ou.data() : nullptr,
                            axes ? ov.data() : nullptr};
        const auto t0 = Clock::now();
        Result<DeformStats> stats =
            backend == StreamBackend::gpu ? gpu->deform(lattice, in, out) : deform(lattice, in, out);
        const double ms = ms_since(t0);
        if (!stats) return stats.error();
        if (count) inverted += stats->inverted, inside_count += stats->inside;
        for (std::size_t r = 0; r < rows; ++r) {
            // Unchanged points keep their exact double values.
            if (op[r] == p[r] && (!normals || on[r] == n[r]) && (!axes || (ou[r] == u[r] && ov[r] == v[r])))
                continue;
            set3(c, xyz, r, o + glm::dvec3(op[r]));
            if (normals) set3(c, cols.n, r, glm::dvec3(on[r]));
            if (axes) set3(c, cols.u, r, glm::dvec3(ou[r])), set3(c, cols.v, r, glm::dvec3(ov[r]));
        }
        return ms;
    }
};

// Outputs must be finite: a lattice that overflows fails the run instead of writing inf (index of the
// first bad row, or -1).
long first_non_finite_row(const ply::Chunk& c, const VertexColumns& cols) {
    for (std::size_t r = 0; r < c.rows; ++r)
        for (int k : {cols.x, cols.y, cols.z, cols.n[0], cols.n[1], cols.n[2], cols.u[0], cols.u[1],
                      cols.u[2], cols.v[0], cols.v[1], cols.v[2]})
            if (k >= 0 && !std::isfinite(c.columns[std::size_t(k)].values[r])) return static_cast<long>(r);
    return -1;
}

Result<StreamDeformResult> stream_surface(const StreamDeformRequest& req, ply::Reader& reader, int vi,
                                          const StreamProgress& progress) {
    const std::string& in_path = req.input;
    const ply::Header& in_header = reader.header();
    const ply::Element& ve = in_header.elements[std::size_t(vi)];
    VertexColumns cols = find_columns(ve);
    const std::size_t chunk_rows = req.chunk_rows > 0 ? req.chunk_rows : kChunkRows;
    StreamDeformResult result;
    result.normals = cols.normals();

    // Normals but neither axes nor a radius: radii from neighbour spacing, exactly as import estimates
    // them (6th nearest neighbour, clamped to 4x the median). Needs every position in memory (~60 bytes
    // per point: positions and a 6-neighbour table), unlike the rest of the stream: done only up to
    // estimate_max_points (~300 MB at 4M) unless estimate_always.
    std::vector<float> estimated_radii;
    const bool wants_estimate = !cols.axes() && cols.normals() && cols.radius < 0;
    const bool estimate = wants_estimate && (req.estimate_always || ve.count <= req.estimate_max_points);
    if (estimate) {
        std::vector<glm::vec3> read;
        if (req.positions.empty()) {
            glm::dvec3 unused(0.0);
            auto pts = read_ply_positions(in_path, unused);
            if (!pts) return pts.error();
            read = std::move(*pts);
        }
        const std::vector<glm::vec3>& pts = req.positions.empty() ? read : req.positions;
        if (pts.size() >= 2)
            estimated_radii = assets::estimate_radii(assets::find_neighbours(pts, 6), 6, 1.0f);
    }

    std::optional<GpuDeformer> gpu;
    if (req.backend == StreamBackend::gpu) {
        auto g = GpuDeformer::create_headless();
        if (!g) return g.error();
        gpu.emplace(std::move(*g));
        result.set_up_ms = set_up_gpu_programs(*gpu, req.lattices, cols.weight >= 0);
    }

    ply::Header out_header = in_header;
    out_header.format = req.ascii ? ply::Format::ascii : ply::Format::binary_little_endian;
    const bool create = !cols.axes() && cols.normals() && (cols.radius >= 0 || !estimated_radii.empty());
    if (create) add_axis_properties(out_header.elements[std::size_t(vi)], cols);
    result.axes = cols.axes()      ? (!create    ? StreamAxes::deformed
                                      : estimate ? StreamAxes::from_estimate
                                                 : StreamAxes::from_radius)
                  : wants_estimate ? StreamAxes::absent_too_many
                                   : StreamAxes::absent_no_normals;
    auto writer = ply::Writer::create(req.output, out_header);
    if (!writer) return writer.error();

    ChunkDeformer deformer;
    deformer.lattices = req.lattices;
    deformer.backend = req.backend;
    deformer.gpu = gpu ? &*gpu : nullptr;
    deformer.inside.assign(req.lattices.size(), 0);
    result.timing_ms.assign(std::size_t(std::max(req.timing_runs, 0)), 0.0);
    const std::string& label = req.lattice_label.empty() ? in_path : req.lattice_label;
    std::uint64_t points = 0;
    const auto t_start = Clock::now();
    ply::Chunk chunk;
    for (const ply::Element& e : in_header.elements) {
        if (auto s = reader.seek_element(e.name); !s) return s.error();
        while (true) {
            auto rows = reader.read_rows(chunk_rows, chunk);
            if (!rows) return rows.error();
            if (*rows == 0) break;
            if (e.name == "vertex") {
                if (create) {
                    chunk.element = out_header.elements[std::size_t(vi)];
                    chunk.columns.resize(chunk.element.properties.size());
                    create_axes(chunk, cols, estimated_radii, std::size_t(points));
                }
                if (cols.weight >= 0)
                    if (Status s = assets::check_ply_weights(chunk.columns[std::size_t(cols.weight)].values,
                                                             chunk.rows, points, in_path);
                        !s)
                        return s.error();
                for (std::size_t r = 0; r < result.timing_ms.size(); ++r) {  // timing runs first, on a copy
                    auto ms = deformer.run(chunk, cols, false);
                    if (!ms) return make_error(label + ": " + ms.message());
                    result.timing_ms[r] += *ms;
                }
                auto ms = deformer.run(chunk, cols, true);
                if (!ms) return make_error(label + ": " + ms.message());
                if (const long bad = first_non_finite_row(chunk, cols); bad >= 0)
                    return make_error(label + ": deformed point " +
                                      std::to_string(points + std::uint64_t(bad)) + " of " + in_path +
                                      " is not finite; nothing was written to " + req.output);
                result.deform_ms += *ms;
                points += *rows;
                if (progress) progress(points, ve.count);
            }
            if (auto s = writer->write_rows(chunk); !s) return s.error();
        }
    }
    if (auto s = writer->finish(); !s) return s.error();
    result.total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    result.points = points;
    result.inverted = deformer.inverted;
    result.inside = std::move(deformer.inside);
    return result;
}

}  // namespace

const char* stream_backend_name(StreamBackend b) {
    switch (b) {
        case StreamBackend::cpu: return "cpu";
        case StreamBackend::gpu: return "gpu";
        case StreamBackend::reference: return "reference";
    }
    return "?";
}

double set_up_gpu_programs(GpuDeformer& gpu, std::span<const Lattice> lattices, bool weighted) {
    const auto t0 = Clock::now();
    for (const Lattice& l : lattices) {
        glm::vec3 p(0.0f), n(0.0f, 0.0f, 1.0f), u(0.0f), v(0.0f);
        const float w = 1.0f;
        PointsIn in{&p, &n, &u, &v, 1, l.origin};
        in.weights = weighted ? &w : nullptr;  // the weighted programs (FFD_WEIGHTS) are others
        (void)gpu.deform(l, in, PointsOut{&p, &n, &u, &v});
    }
    return ms_since(t0);
}

Result<StreamInput> inspect_stream_input(const std::string& path) {
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    auto vi = vertex_element(reader->header(), path);
    if (!vi) return vi.error();
    const ply::Element& ve = reader->header().elements[std::size_t(*vi)];
    return StreamInput{gaussian::is_gaussian_element(ve) ? StreamKind::gaussians : StreamKind::surface,
                       ve.count};
}

Result<std::vector<glm::vec3>> read_ply_positions(const std::string& path, glm::dvec3& origin) {
    auto reader = ply::Reader::open(path);
    if (!reader) return reader.error();
    auto vi = vertex_element(reader->header(), path);
    if (!vi) return vi.error();
    const ply::Element& ve = reader->header().elements[std::size_t(*vi)];
    const int xyz[3] = {ve.find("x"), ve.find("y"), ve.find("z")};
    if (auto s = reader->seek_element("vertex"); !s) return s.error();
    std::vector<glm::vec3> out;
    ply::Chunk chunk;
    while (true) {
        auto rows = reader->read_rows(kChunkRows, chunk);
        if (!rows) return rows.error();
        if (*rows == 0) break;
        for (std::size_t r = 0; r < *rows; ++r) {
            const glm::dvec3 w = get3(chunk, xyz, r);
            if (out.empty()) origin = w;
            out.push_back(glm::vec3(w - origin));
        }
    }
    return out;
}

Result<StreamDeformResult> stream_deform(const StreamDeformRequest& req, const StreamProgress& progress) {
    auto reader = ply::Reader::open(req.input);
    if (!reader) return reader.error();
    auto vi = vertex_element(reader->header(), req.input);
    if (!vi) return vi.error();
    if (gaussian::is_gaussian_element(reader->header().elements[std::size_t(*vi)])) {
        if (req.lattices.size() != 1)
            return make_error(req.input + ": 3D Gaussian files are deformed by one lattice at a time (got " +
                              std::to_string(req.lattices.size()) + ")");
        return detail::stream_gaussians(req, *reader, progress);
    }
    return stream_surface(req, *reader, *vi, progress);
}

}  // namespace sffd::ffd
