// The GPU deformers' control-point kernel choice (ffd::detail::choose_kernel) at the implementations'
// limits, without a GL context: shared memory must hold the lattice's xyz and the deform shaders' own
// shared words, or the program fails to link on the implementation whose limit the points fill exactly.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "runtime/core/paths.h"
#include "systems/ffd/gpu_kernel.h"
#include "systems/ffd/lattice.h"

namespace {

using namespace sffd;
using ffd::GpuBernsteinKernel;
using ffd::detail::choose_kernel;

Lattice lattice(glm::ivec3 divisions, LatticeBasis basis = LatticeBasis::bernstein) {
    return make_lattice({0, 0, 0}, {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}, divisions,
                        basis);
}

constexpr std::size_t kNvidiaShared = 49152, kNvidiaUbo = 65536;  // NVIDIA's limits (H100, H200)
constexpr std::size_t kGlMinShared = 32768, kGlMinUbo = 16384;    // GL 4.5's minimum maxima

TEST(KernelChoice, SharedMemoryKeepsRoomForTheShadersOwnWords) {
    // 16^3 points: 49,152 bytes of xyz, exactly NVIDIA's limit: with the shaders' counters beside them the
    // shared program would not link, so they go to the UBO (65,536 bytes, which they fit).
    auto c =
        choose_kernel(lattice({15, 15, 15}), GpuBernsteinKernel::automatic, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_FALSE(c.shared);
    EXPECT_TRUE(c.ubo);
    // 15^3 points (40,500 bytes) fit with room to spare.
    c = choose_kernel(lattice({14, 14, 14}), GpuBernsteinKernel::automatic, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_TRUE(c.shared);
    EXPECT_FALSE(c.ubo);
    // At GL's minimum, 13 x 14 x 15 points (32,760 bytes) do not fit even when asked (they did before the
    // room was kept); 12 x 15 x 15 (32,400 bytes) do.
    c = choose_kernel(lattice({12, 13, 14}), GpuBernsteinKernel::shared, false, kGlMinShared, kGlMinUbo);
    EXPECT_FALSE(c.shared);
    EXPECT_FALSE(c.ubo);  // 43,680 bytes: past the minimum UBO too, so the SSBO
    EXPECT_FALSE(c.runs);
    c = choose_kernel(lattice({11, 14, 14}), GpuBernsteinKernel::shared, false, kGlMinShared, kGlMinUbo);
    EXPECT_TRUE(c.shared);
}

TEST(KernelChoice, EachKernelWhereItIsChosen) {
    const Lattice paper = lattice({10, 10, 10}), spline = lattice({10, 10, 10}, LatticeBasis::bspline);
    // Bernstein: shared memory on hardware, the UBO on a software rasterizer (its barrier() is costly).
    auto c = choose_kernel(paper, GpuBernsteinKernel::automatic, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_TRUE(c.shared && !c.ubo && !c.runs);
    c = choose_kernel(paper, GpuBernsteinKernel::automatic, true, kGlMinShared, kNvidiaUbo);
    EXPECT_TRUE(!c.shared && c.ubo && !c.runs);
    c = choose_kernel(paper, GpuBernsteinKernel::direct, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_TRUE(!c.shared && c.ubo && !c.runs);  // direct Bernstein reads its points from a UBO that fits
    // B-spline: packed runs by default, shared only when asked (its 13^3-point grid, 26,364 bytes, fits).
    c = choose_kernel(spline, GpuBernsteinKernel::automatic, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_TRUE(!c.shared && !c.ubo && c.runs);
    c = choose_kernel(spline, GpuBernsteinKernel::shared, false, kGlMinShared, kGlMinUbo);
    EXPECT_TRUE(c.shared && !c.ubo && !c.runs);
    c = choose_kernel(spline, GpuBernsteinKernel::direct, false, kNvidiaShared, kNvidiaUbo);
    EXPECT_TRUE(!c.shared && !c.ubo && !c.runs);
}

// The room kept for the shaders' own shared words covers what they declare beside the control points
// (declarations `shared uint|int|float a, b[N];` on one line; the control points' array is in ffd_common).
TEST(KernelChoice, TheDeformShadersOwnSharedWordsFitTheRoomKept) {
    for (const char* file : {"ffd/deform.comp", "gaussian/deform.comp"}) {
        std::ifstream in(paths::shader_dir() / file);
        ASSERT_TRUE(in) << file;
        std::size_t bytes = 0, declarations = 0;
        for (std::string line; std::getline(in, line);) {
            std::istringstream words(line);
            std::string keyword, type;
            if (!(words >> keyword >> type) || keyword != "shared") continue;
            ASSERT_TRUE(type == "uint" || type == "int" || type == "float") << file << ": " << line;
            ++declarations;
            std::string names;
            std::getline(words, names, ';');
            std::istringstream list(names);
            for (std::string one; std::getline(list, one, ',');) {
                const auto open = one.find('[');
                bytes += 4 * (open == std::string::npos ? 1 : std::stoul(one.substr(open + 1)));
            }
        }
        EXPECT_GT(declarations, 0u) << file;  // both count per work group in shared memory
        EXPECT_LE(bytes, ffd::detail::kDeformShaderSharedBytes) << file;
    }
}

}  // namespace
