// splatffd deform IN.ply OUT.ply --lattice L.json [--backend cpu|gpu|reference] [--bench N] [--ascii]
//
// Streams the PLY file through the lattice in chunks (peak memory stays far below 256 MB whatever the
// file size): every element is copied in order, `vertex` rows get deformed x y z (and nx ny nz when
// present), all other properties are copied with their types. Points outside the lattice are unchanged,
// points on its faces are inside. The output is binary little-endian (or ASCII with --ascii) and atomic.
// --bench N re-runs the deformation of every chunk N more times and prints one JSON line on stdout:
// {"points":..,"backend":..,"median_ms":..,"points_per_s":..} (deformation only, no I/O).
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "runtime/assets/ply.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "systems/gaussian/gaussian_io.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/deform_gaussians.h"

namespace {

using namespace sffd;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kChunkRows = 1 << 17;  // ~131k rows: ~10 MB of double columns for 10 properties

int usage() {
    std::fprintf(stderr,
                 "usage: splatffd deform IN.ply OUT.ply --lattice L.json [--backend cpu|gpu|reference] [--bench N] [--ascii]\n");
    return 2;
}

int fail(const std::string& message) {
    std::fprintf(stderr, "splatffd deform: %s\n", message.c_str());
    return 1;
}

// Deforms one chunk's vertex rows in place (double columns). Returns the deformation time in ms.
struct ChunkDeformer {
    const Lattice& lattice;
    std::string backend;  // cpu | gpu | reference
    ffd::GpuDeformer* gpu = nullptr;
    std::vector<glm::vec3> p, n, op, on;
    std::size_t inverted = 0;

    Result<double> run(ply::Chunk& c, int ix, int iy, int iz, int inx, int iny, int inz, bool write) {
        const std::size_t rows = c.rows;
        auto& X = c.columns[std::size_t(ix)].values;
        auto& Y = c.columns[std::size_t(iy)].values;
        auto& Z = c.columns[std::size_t(iz)].values;
        const bool normals = inx >= 0 && iny >= 0 && inz >= 0;
        if (backend == "reference") {
            // Double in, double out: no float rounding at all.
            const auto t0 = Clock::now();
            std::vector<glm::dvec3> pos(rows), nrm(normals ? rows : 0);
            std::size_t inv = 0;
            for (std::size_t r = 0; r < rows; ++r) {
                const ffd::ReferencePoint rp = ffd::reference_point(lattice, {X[r], Y[r], Z[r]});
                pos[r] = rp.position;
                if (normals) {
                    const glm::dvec3 nin(c.columns[std::size_t(inx)].values[r], c.columns[std::size_t(iny)].values[r],
                                         c.columns[std::size_t(inz)].values[r]);
                    glm::dvec3 nn = nin;
                    if (rp.inside) {
                        const glm::dmat3& J = rp.jacobian;
                        nn = glm::cross(J[1], J[2]) * nin.x + glm::cross(J[2], J[0]) * nin.y + glm::cross(J[0], J[1]) * nin.z;
                        const double len = glm::length(nn);
                        if (len > 0) nn /= len;
                        inv += glm::determinant(J) < 0.0;
                    }
                    nrm[r] = nn;
                }
            }
            const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
            if (write) {
                inverted += inv;
                for (std::size_t r = 0; r < rows; ++r) {
                    X[r] = pos[r].x, Y[r] = pos[r].y, Z[r] = pos[r].z;
                    if (normals) {
                        c.columns[std::size_t(inx)].values[r] = nrm[r].x;
                        c.columns[std::size_t(iny)].values[r] = nrm[r].y;
                        c.columns[std::size_t(inz)].values[r] = nrm[r].z;
                    }
                }
            }
            return ms;
        }
        // Float paths work relative to the lattice origin (far-away scans keep their precision).
        const glm::dvec3 o = lattice.origin;
        p.resize(rows), op.resize(rows);
        n.resize(normals ? rows : 0), on.resize(normals ? rows : 0);
        for (std::size_t r = 0; r < rows; ++r) p[r] = glm::vec3(glm::dvec3(X[r], Y[r], Z[r]) - o);
        if (normals)
            for (std::size_t r = 0; r < rows; ++r)
                n[r] = glm::vec3(float(c.columns[std::size_t(inx)].values[r]), float(c.columns[std::size_t(iny)].values[r]),
                                 float(c.columns[std::size_t(inz)].values[r]));
        const ffd::PointsIn in{p.data(), normals ? n.data() : nullptr, nullptr, nullptr, rows, o};
        const ffd::PointsOut out{op.data(), normals ? on.data() : nullptr, nullptr, nullptr};
        const auto t0 = Clock::now();
        Result<ffd::DeformStats> stats = backend == "gpu" ? gpu->deform(lattice, in, out) : ffd::deform(lattice, in, out);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!stats) return stats.error();
        if (write) {
            inverted += stats->inverted;
            for (std::size_t r = 0; r < rows; ++r) {
                // Unchanged points keep their exact double coordinates.
                if (op[r] == p[r] && (!normals || on[r] == n[r])) continue;
                const glm::dvec3 w = o + glm::dvec3(op[r]);
                X[r] = w.x, Y[r] = w.y, Z[r] = w.z;
                if (normals) {
                    c.columns[std::size_t(inx)].values[r] = on[r].x;
                    c.columns[std::size_t(iny)].values[r] = on[r].y;
                    c.columns[std::size_t(inz)].values[r] = on[r].z;
                }
            }
        }
        return ms;
    }
};

int run_deform(sffd::cli::Args args) {
    std::vector<std::string> pos;
    std::string lattice_path, backend = "cpu";
    int bench = 0;
    bool ascii = false;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto next = [&]() -> std::optional<std::string> {
            if (i + 1 >= args.size()) return std::nullopt;
            return args[++i];
        };
        if (a == "--help" || a == "-h") return usage();
        if (a == "--lattice") {
            auto v = next();
            if (!v) return usage();
            lattice_path = *v;
        } else if (a == "--backend") {
            auto v = next();
            if (!v || (*v != "cpu" && *v != "gpu" && *v != "reference")) return usage();
            backend = *v;
        } else if (a == "--bench") {
            auto v = next();
            if (!v) return usage();
            try {
                bench = std::stoi(*v);
            } catch (...) {
                return usage();
            }
            if (bench < 0) return usage();
        } else if (a == "--ascii") {
            ascii = true;
        } else if (!a.empty() && a[0] == '-') {
            return usage();
        } else {
            pos.push_back(a);
        }
    }
    if (pos.size() != 2 || lattice_path.empty()) return usage();
    // The output is always PLY: another extension would put PLY bytes under a misleading name.
    {
        std::string ext = std::filesystem::path(pos[1]).extension().string();
        for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        if (ext != ".ply")
            return fail(pos[1] + ": deform writes PLY files; name the output *.ply (got '" + ext + "'; use `splatffd convert` for other formats)");
    }
    // Writing over the input while streaming it would destroy the input on success.
    {
        std::error_code ec;
        const bool same = std::filesystem::equivalent(pos[0], pos[1], ec) ||
                          std::filesystem::weakly_canonical(pos[0], ec) == std::filesystem::weakly_canonical(pos[1], ec);
        if (same) return fail(pos[1] + ": output is the input file; choose another output name");
    }

    auto lattice = ffd::load_lattice(lattice_path);
    if (!lattice) return fail(lattice.message());
    auto reader = ply::Reader::open(pos[0]);
    if (!reader) return fail(reader.message());
    const ply::Header& in_header = reader->header();
    const int vi = in_header.find("vertex");
    if (vi < 0) return fail(pos[0] + ": no vertex element");
    const ply::Element& ve = in_header.elements[std::size_t(vi)];
    const int ix = ve.find("x"), iy = ve.find("y"), iz = ve.find("z");
    if (ix < 0 || iy < 0 || iz < 0) return fail(pos[0] + ": vertex element has no x, y, z properties");
    // 3D Gaussian splats (3DGS PLY): covariances and SH follow the lattice too (tools/splatffd/deform_gaussians.cpp).
    if (gaussian::is_gaussian_element(ve))
        return cli::deform_gaussian_ply(pos[0], pos[1], *lattice, lattice_path, backend, bench, ascii);
    for (int k : {ix, iy, iz})
        if (ve.properties[std::size_t(k)].is_list) return fail(pos[0] + ": x, y, z must be scalar properties");
    int inx = ve.find("nx"), iny = ve.find("ny"), inz = ve.find("nz");
    if (inx < 0 || iny < 0 || inz < 0 || ve.properties[std::size_t(inx)].is_list) inx = iny = inz = -1;

    std::optional<ffd::GpuDeformer> gpu;
    if (backend == "gpu") {
        auto g = ffd::GpuDeformer::create_headless();
        if (!g) return fail(g.message());
        gpu.emplace(std::move(*g));
    }

    ply::Header out_header = in_header;
    out_header.format = ascii ? ply::Format::ascii : ply::Format::binary_little_endian;
    auto writer = ply::Writer::create(pos[1], out_header);
    if (!writer) return fail(writer.message());

    ChunkDeformer deformer{*lattice, backend, gpu ? &*gpu : nullptr, {}, {}, {}, {}, 0};
    std::vector<double> rep_ms(std::size_t(bench), 0.0);
    double first_ms = 0.0;
    std::size_t points = 0;
    const auto t_start = Clock::now();
    ply::Chunk chunk;
    for (const ply::Element& e : in_header.elements) {
        if (auto s = reader->seek_element(e.name); !s) return fail(s.message());
        while (true) {
            auto rows = reader->read_rows(kChunkRows, chunk);
            if (!rows) return fail(rows.message());
            if (*rows == 0) break;
            if (e.name == "vertex") {
                for (int r = 0; r < bench; ++r) {  // timing runs first (the chunk is still the input)
                    auto ms = deformer.run(chunk, ix, iy, iz, inx, iny, inz, false);
                    if (!ms) return fail(lattice_path + ": " + ms.message());
                    rep_ms[std::size_t(r)] += *ms;
                }
                auto ms = deformer.run(chunk, ix, iy, iz, inx, iny, inz, true);
                if (!ms) return fail(lattice_path + ": " + ms.message());
                // Outputs must be finite: a lattice that overflows must fail the run, not write inf.
                for (std::size_t r = 0; r < *rows; ++r)
                    for (int k : {ix, iy, iz, inx, iny, inz})
                        if (k >= 0 && !std::isfinite(chunk.columns[std::size_t(k)].values[r]))
                            return fail(lattice_path + ": deformed point " + std::to_string(points + r) + " of " + pos[0] +
                                        " is not finite; nothing was written to " + pos[1]);
                first_ms += *ms;
                points += *rows;
            }
            if (auto s = writer->write_rows(chunk); !s) return fail(s.message());
        }
    }
    if (auto s = writer->finish(); !s) return fail(s.message());
    const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    std::fprintf(stderr, "splatffd deform: %zu points (%s backend), deformation %.1f ms (%.3g points/s), total with I/O %.2f s (%.3g points/s), %zu inverted\n",
                 points, backend.c_str(), first_ms, first_ms > 0 ? double(points) / (first_ms * 1e-3) : 0.0, total_s,
                 total_s > 0 ? double(points) / total_s : 0.0, deformer.inverted);
    if (bench > 0) {
        std::sort(rep_ms.begin(), rep_ms.end());
        const double median = rep_ms.size() % 2 ? rep_ms[rep_ms.size() / 2]
                                                : 0.5 * (rep_ms[rep_ms.size() / 2 - 1] + rep_ms[rep_ms.size() / 2]);
        std::printf("{\"points\":%zu,\"backend\":\"%s\",\"median_ms\":%.4f,\"min_ms\":%.4f,\"runs\":%d,\"points_per_s\":%.4g}\n",
                    points, backend.c_str(), median, rep_ms.front(), bench, median > 0 ? double(points) / (median * 1e-3) : 0.0);
    }
    return 0;
}

}  // namespace

SFFD_COMMAND(deform, "deform a PLY file with a lattice (streaming; --backend cpu|gpu|reference, --bench N)", run_deform);
