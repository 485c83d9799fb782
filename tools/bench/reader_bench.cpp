// File reading throughput (bytes_per_second: file bytes per second of wall time) of the three formats the
// editor opens most: a 1M-Gaussian degree-3 3DGS PLY (248 MB), a 4.5M-splat surface PLY and the same cloud
// as GLB (~230 MB each). Each file is written once per process to the temp folder (page cache warm, so this
// is the parser, not the disk). The 3DGS PLY runs both ways in one binary: read_gaussians() (float32 rows
// decoded in place from the mapped file) and the column path it replaced (ply::Reader's double columns,
// append_from_chunk, validate), with the same checks.
//   build/release/tools/bench/bench_reader --benchmark_min_time=0.01
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_read.h"
#include "tools/bench/bench_util.h"
#include "tools/bench/gaussian_case.h"

namespace {

using namespace sffd;
namespace fs = std::filesystem;

// Splats on a unit Fibonacci sphere with normals, colours and tangent axes (what the editor saves).
SplatCloud surface_cloud(std::size_t n) {
    SplatCloud c;
    c.positions.resize(n), c.normals.resize(n), c.axis_u.resize(n), c.axis_v.resize(n), c.colors.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p(bench::fibonacci_sphere(i, n));
        const glm::vec3 t =
            glm::normalize(glm::cross(p, std::abs(p.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
        c.positions[i] = p, c.normals[i] = p;
        c.axis_u[i] = 0.002f * t, c.axis_v[i] = 0.002f * glm::cross(p, t);
        c.colors[i] = 0xff000000u | std::uint32_t(i * 2654435761u & 0xffffffu);
    }
    return c;
}

// One generated file, written on first use (a filtered run makes only its own) and removed at exit.
struct File {
    fs::path path;
    std::string error;
    template <class Write>
    File(const char* name, Write write)
        : path(fs::temp_directory_path() / ("sffd_bench_read_" + std::to_string(getpid()) + "_" + name)) {
        if (Status s = write(path); !s) error = s.message();
    }
    ~File() {
        std::error_code ec;
        fs::remove(path, ec);
    }
};

const File& gaussian_ply() {
    static const File f("3dgs.ply", [](const fs::path& p) {
        return gaussian::write_ply(p, bench::sphere_gaussians(1000000, 3));
    });
    return f;
}
const File& surface_ply() {
    static const File f("surface.ply",
                        [](const fs::path& p) { return assets::save_splat_ply(surface_cloud(4500000), p); });
    return f;
}
const File& surface_glb() {
    static const File f("surface.glb",
                        [](const fs::path& p) { return assets::save_splat_glb(surface_cloud(4500000), p); });
    return f;
}

template <class Read>
void run(benchmark::State& state, const File& file, Read read) {
    if (!file.error.empty()) return state.SkipWithError(file.error.c_str());
    const fs::path& path = file.path;
    const double cpu0 = bench::process_cpu_s();
    for (auto _ : state)
        if (std::string why = read(path); !why.empty()) return state.SkipWithError(why.c_str());
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(fs::file_size(path)));
    state.counters["process_cpu_ms_per_read"] =
        1e3 * (bench::process_cpu_s() - cpu0) / double(state.iterations());
}

// Arg 0: read_gaussians(); 1: the column path (what read_ply did before the float32 path).
void BM_Read3dgsPly(benchmark::State& state) {
    const bool columns = state.range(0) != 0;
    state.SetLabel(columns ? "ply::Reader columns" : "read_gaussians");
    run(state, gaussian_ply(), [&](const fs::path& p) -> std::string {
        if (!columns) {
            auto g = gaussian::read_gaussians(p);
            return g ? std::string() : g.message();
        }
        auto reader = ply::Reader::open(p);
        if (!reader) return reader.message();
        const ply::Element& ve = reader->header().elements[std::size_t(reader->header().find("vertex"))];
        auto layout = gaussian::ply_layout(ve, p.string());
        if (!layout) return layout.message();
        GaussianCloud g;
        g.sh_degree = layout->degree;
        ply::Chunk chunk;
        for (std::uint64_t row = 0;;) {
            auto rows = reader->read_rows(1 << 16, chunk);
            if (!rows) return rows.message();
            if (*rows == 0) break;
            if (auto s = gaussian::append_from_chunk(chunk, *layout, row, p.string(), g); !s)
                return s.message();
            row += *rows;
        }
        auto s = gaussian::validate(g, p.string());
        return s ? std::string() : s.message();
    });
}
BENCHMARK(BM_Read3dgsPly)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadSurfacePly(benchmark::State& state) {
    run(state, surface_ply(), [](const fs::path& p) -> std::string {
        auto g = assets::read_ply_geometry(p);
        return g ? std::string() : g.message();
    });
}
BENCHMARK(BM_ReadSurfacePly)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadSurfaceGlb(benchmark::State& state) {
    run(state, surface_glb(), [](const fs::path& p) -> std::string {
        auto g = assets::read_gltf(p);
        return g ? std::string() : g.message();
    });
}
BENCHMARK(BM_ReadSurfaceGlb)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
