// Streaming deformation of a PLY file through lattices, in bounded memory (what `splatffd deform` runs on
// PLY in, PLY out; a 100M-point scan streams in ~32 MB).
//
//   auto input = ffd::inspect_stream_input("scan.ply");       // kind and count; "scan.ply: problem"
//   ffd::StreamDeformRequest req{.input = "scan.ply", .output = "out.ply", .lattices = chain};
//   auto done = ffd::stream_deform(req, [](std::uint64_t rows, std::uint64_t of) { ... });
//   if (!done) return done.error();                           // names the file and the problem
//
// Every element is copied in file order, chunk by chunk (chunk_rows rows at a time; the output does not
// depend on it). Surface splats: `vertex` rows get x y z, nx ny nz and the splat axes axis_u* axis_v*
// deformed through each lattice in order by the in-engine CPU kernels (ffd::deform: the fast and sparse
// float kernels with run-time SIMD dispatch), the GPU compute deformer, or the double-precision reference
// (ffd::reference_point, double in and out); a file with normals but no axes gets circular axes appended
// as float properties first (assets::make_circular_axes), from its `radius`, or from radii estimated from
// neighbour spacing as import does (this holds every position in memory, so only up to
// estimate_max_points unless estimate_always). 3DGS files (the vertex element gaussian::is_gaussian_element
// accepts) go through gaussian::deform (centres, Σ' = J Σ Jᵀ, SH rotated by the polar rotation of J) or
// its GPU deformer, one lattice. Points outside a lattice keep their exact values; every other property
// keeps its type. The output is written to a temporary and renamed on success (ply::Writer): on any error
// OUT is not created and an old OUT is untouched.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

enum class StreamBackend : std::uint8_t { cpu, gpu, reference };
const char* stream_backend_name(StreamBackend b);  // "cpu" "gpu" "reference"

enum class StreamKind : std::uint8_t { surface, gaussians };

// What the input's header says (the checks stream_deform() makes first, with the same messages).
struct StreamInput {
    StreamKind kind = StreamKind::surface;
    std::uint64_t points = 0;  // rows of the vertex element
};
Result<StreamInput> inspect_stream_input(const std::string& path);

// x y z of a PLY's vertices relative to the first one (`origin`), read in chunks: for fitting a lattice
// to a file that is then streamed (pass them on as StreamDeformRequest::positions).
Result<std::vector<glm::vec3>> read_ply_positions(const std::string& path, glm::dvec3& origin);

struct StreamDeformRequest {
    std::string input, output;          // both PLY; output is written atomically
    std::span<const Lattice> lattices;  // applied in order (3DGS input: exactly one)
    StreamBackend backend = StreamBackend::cpu;
    int timing_runs = 0;  // re-run each chunk's deformation this often on a copy (timings only)
    bool ascii = false;   // ASCII PLY out (default binary little endian)
    // Radii from neighbour spacing for a surface file with normals but no axes and no radius.
    bool estimate_always = false;
    std::uint64_t estimate_max_points = 4'000'000;
    // The input's positions when the caller has read them already (read_ply_positions): saves a pass.
    std::vector<glm::vec3> positions;
    std::string lattice_label;   // prefixes deformation errors (default: input)
    std::size_t chunk_rows = 0;  // 0: 131072 rows (surface), 65536 (Gaussians)
};

// Where the written splat axes come from (surface input).
enum class StreamAxes : std::uint8_t {
    deformed,           // the input had them
    from_radius,        // created from normals and the radius property
    from_estimate,      // created from normals and radii estimated from neighbour spacing
    absent_too_many,    // normals only, more points than estimate_max_points
    absent_no_normals,  // no normals in the input
};

struct StreamDeformResult {
    StreamKind kind = StreamKind::surface;
    std::uint64_t points = 0;
    bool normals = false;  // surface: the input has nx ny nz
    StreamAxes axes = StreamAxes::absent_no_normals;
    std::size_t inverted = 0;
    std::vector<std::size_t> inside;  // points inside each lattice, in order
    double deform_ms = 0.0;           // deformation only (no I/O, no GPU set-up)
    double set_up_ms = -1.0;          // GPU program set-up (shader compilation, first dispatch); < 0: none
    std::vector<double> timing_ms;    // per timing run, summed over the chunks
    double total_s = 0.0;             // with I/O
    // Gaussians only.
    int sh_degree = 0;
    std::size_t degenerate = 0, not_finite = 0;  // not finite on the GPU: written transparent
    double read_ms = 0.0;                        // parse + convert of the input
};

class GpuDeformer;
// The GPU's programs are specialised per lattice shape and compiled at their first dispatch (seconds with a
// cold shader cache): one point through each lattice before the timed work, so the deformation time is the
// deformation's. Returns its milliseconds (the in-memory `deform` path uses it too). `weighted`: the
// programs of clouds with per-point weights (FFD_WEIGHTS), which are others.
double set_up_gpu_programs(GpuDeformer& gpu, std::span<const Lattice> lattices, bool weighted = false);

// A PLY vertex property `weight` (PointWeights, runtime/scene/point_columns.h) is the deformation's
// per-point weight: X + w D, J_w = I + w (J − I) (surface splats and 3DGS rows alike), and is written back
// unchanged. A weight that is NaN or outside [0, 1] fails the run before anything is written:
// "IN: vertex i: weight w is not in [0, 1]". The property and its check are assets' one reader of the
// column (runtime/assets/formats/surface/ply_weights.h), which render, view, convert and info use too.

// Called after each vertex chunk with the vertex rows done so far and the element's count.
using StreamProgress = std::function<void(std::uint64_t done, std::uint64_t total)>;

// Errors read "file: problem" (a lattice problem "lattice_label: lattice: problem"; a deformed point that
// is not finite fails the run, "lattice_label: deformed point i of IN is not finite; nothing was written
// to OUT").
Result<StreamDeformResult> stream_deform(const StreamDeformRequest& request,
                                         const StreamProgress& progress = {});

}  // namespace sffd::ffd
