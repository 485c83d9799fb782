// `splatffd profile --paper`: the seed paper's table (section IV): sphere and face, 11^3 control points,
// four cases; the paper's naive CPU algorithm against ffd_system's CPU and GPU paths and paper mode.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/gfx/gl.h"
#include "runtime/gfx/render_target.h"
#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/paper_mode.h"
#include "systems/residency/residency_system.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/profile_run.h"
#include "tools/splatffd/progress.h"

namespace sffd::profile_cmd {

using namespace profiling;

namespace {

struct PaperRow {
    std::string object, method;
    std::size_t points = 0;
    std::vector<double> case_ms;  // per case: median ms per frame (-1: not available)
    std::string note;
};

}  // namespace

int run_paper(const Options& o) {
    std::printf(
        "The seed paper's experiment (section IV): 11x11x11 = 1331 control points, Bernstein basis,\n"
        "positions + normals deformed every frame; time per frame = deformation only.\n"
        "Paper (Pentium Dual-Core 2.7 GHz, GeForce 9500 GT): CPU %.2f FPS (~%.0f s/frame), "
        "GPU vertex shader up to %.0f FPS (~%.0f ms), x%.0f.\n\n",
        paper_cpu_fps, 1.0 / paper_cpu_fps, paper_gpu_fps, 1000.0 / paper_gpu_fps, paper_speedup);
    std::vector<PaperRow> rows;
    // The naive algorithm runs about a minute per case: a percentage on a terminal (quiet in logs).
    cli::ProgressPrinter progress("profile --paper", cli::ProgressPrinter::mode_for(false));
    for (const char* object : {"sphere", "face"}) {
        ecs::Registry registry;
        bool synthetic = false;
        if (Status st = load(registry, object, &synthetic); !st) {
            cli::command_error("profile", st.message());
            return 1;
        }
        // The largest cloud of the scene is the paper's object.
        const SplatCloud* cloud = nullptr;
        for (auto [e, c] : registry.view<const SplatCloud>()) {
            (void)e;
            if (!cloud || c.size() > cloud->size()) cloud = &c;
        }
        if (!cloud) {
            cli::command_error("profile", std::string(object) + ": no point cloud in the scene");
            return 1;
        }
        const std::string label = std::string(object) + (synthetic ? " (synthetic stand-in)" : "");
        Lattice lattice = paper_lattice(*cloud, 10);
        std::vector<glm::vec3> pos, nrm;

        PaperRow naive{label, "paper CPU naive, wall (1 thread)", cloud->size(), {}, ""};
        PaperRow naive_cpu{label, "paper CPU naive, thread CPU time", cloud->size(), {}, ""};
        const std::string naive_step = std::string(object) + ": naive paper CPU";
        for (const auto& pc : paper_cases) {
            progress.report(naive_step, double(&pc - paper_cases) / double(std::size(paper_cases)));
            std::vector<double> ms, cpu;
            for (int f = 0; f < o.naive_frames; ++f) {
                apply_paper_case(lattice, pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                const auto t0 = std::chrono::steady_clock::now();
                const double c0 = thread_cpu_ms();
                paper_ffd_naive(lattice, *cloud, pos, nrm);
                cpu.push_back(thread_cpu_ms() - c0);
                ms.push_back(
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            }
            naive.case_ms.push_back(ms.empty() ? -1.0 : median(ms));
            naive_cpu.case_ms.push_back(cpu.empty() ? -1.0 : median(cpu));
            if (ms.empty()) {
                naive.note = naive_cpu.note = "skipped (--naive-frames 0)";
                continue;
            }
            std::printf("  %-8s %-15s naive  wall %10.1f ms  thread CPU %10.1f ms\n", object, pc.name,
                        naive.case_ms.back(), naive_cpu.case_ms.back());
            std::fflush(stdout);
        }
        progress.report(naive_step, 1.0);
        rows.push_back(naive);
        rows.push_back(naive_cpu);

        // Ours on the CPU: ffd_system's CPU path (FfdSettings::force_cpu), positions + normals as in the
        // paper (the cloud's splat axes are left out of this registry's copy).
        PaperRow fast{label, "ours CPU (ffd_system CPU path)", cloud->size(), {}, ""};
        {
            ecs::Registry creg;
            const ecs::Entity ce = creg.create();
            SplatCloud pn;
            pn.origin = cloud->origin, pn.positions = cloud->positions, pn.normals = cloud->normals;
            creg.emplace<SplatCloud>(ce, std::move(pn));
            const ecs::Entity le = creg.create();
            creg.emplace<Lattice>(le, lattice);
            creg.emplace<Deformers>(ce, Deformers{{le}});
            creg.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
            for (const auto& pc : paper_cases) {
                std::vector<double> ms;
                for (int f = 0; f < std::max(3, o.frames / 4) + 2; ++f) {
                    apply_paper_case(creg.patch<Lattice>(le), pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                    const auto t0 = std::chrono::steady_clock::now();
                    ffd_system(creg, {});
                    const double t =
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                            .count();
                    if (!creg.get<DeformedSplats>(ce).cpu_valid) {
                        cli::command_error("profile", "--paper: ffd_system did not deform on the CPU");
                        return 1;
                    }
                    if (f >= 2) ms.push_back(t);  // two warm-up frames
                }
                fast.case_ms.push_back(median(ms));
            }
        }
        rows.push_back(fast);
        {
            // GPU rows, timed with glFinish + CPU clock (llvmpipe's timer queries are not trustworthy):
            //   compute          the skinning-style compute pass alone (deform once per change);
            //   compute + draw   that pass then the same point sprites drawn from the deformed buffer;
            //   paper mode       the paper's design: deformation in the vertex shader of the point draw.
            // Draws go to an offscreen 1024x768 target, camera framing the cloud; 2-pixel point sprites.
            PaperRow gpu{label, "ours GPU compute (deform only)", cloud->size(), {}, ""};
            PaperRow gpu_draw{label, "ours GPU compute + point draw", cloud->size(), {}, ""};
            PaperRow paper_mode{label, "paper mode: vertex-shader deform + draw", cloud->size(), {}, ""};
            auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 64, .debug = false});
            if (!ctx) {
                gpu.case_ms = gpu_draw.case_ms = paper_mode.case_ms = {-1, -1, -1, -1};
                gpu.note = gpu_draw.note = paper_mode.note = ctx.message();
            } else {
                // ffd_system's compute path (FfdSettings::force_gpu) on the uploaded rest splats.
                auto greg = std::make_unique<ecs::Registry>();  // dies before the context
                const ecs::Entity ce = greg->create();
                greg->emplace<SplatCloud>(ce, *cloud);
                const ecs::Entity le = greg->create();
                greg->emplace<Lattice>(le, lattice);
                greg->emplace<Deformers>(ce, Deformers{{le}});
                greg->set_resource<FfdSettings>(FfdSettings{.force_gpu = true});
                residency_system(*greg, {});  // the rest splats the compute path reads
                auto deform = [&]() -> Status {
                    ffd_system(*greg, {});
                    if (!ffd::output_on_gpu(*greg, ce))
                        return make_error("profile --paper: ffd_system did not deform on the GPU");
                    return {};
                };
                const int frames = std::max(3, o.frames / 8) + 2;
                auto time_frames = [&](const PaperCase& pc, auto&& body) -> Result<double> {
                    std::vector<double> ms;
                    for (int f = 0; f < frames; ++f) {
                        apply_paper_case(greg->patch<Lattice>(le), pc, 0.5 + 0.5 * std::sin(0.7 * (f + 1)));
                        glFinish();
                        const auto t0 = std::chrono::steady_clock::now();
                        if (Status st = body(); !st) return st.error();
                        glFinish();
                        const double t =
                            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                                .count();
                        if (f >= 2) ms.push_back(t);  // two warm-up frames
                    }
                    return median(ms);
                };
                for (const auto& pc : paper_cases) {
                    auto t = time_frames(pc, deform);
                    if (!t) {
                        cli::command_error("profile", t.message());
                        return 1;
                    }
                    gpu.case_ms.push_back(*t);
                }
                auto target = gfx::RenderTarget::create({.label = "profile.paper",
                                                         .width = 1024,
                                                         .height = 768,
                                                         .color = {{"color", gfx::ColorFormat::rgba8}}});
                auto paper = ffd::PaperModeRenderer::create();
                if (!target || !paper) {
                    cli::command_error("profile", !target ? target.message() : paper.message());
                    return 1;
                }
                glm::dvec3 lo = lattice.origin,
                           hi = lattice.origin + lattice.axes[0] + lattice.axes[1] + lattice.axes[2];
                const glm::dvec3 centre = 0.5 * (lo + hi) - cloud->origin;
                const float radius = static_cast<float>(0.5 * glm::length(hi - lo));
                const glm::mat4 view_proj =
                    glm::perspective(glm::radians(45.0f), 1024.0f / 768.0f, 0.01f * radius, 10.0f * radius) *
                    glm::lookAt(glm::vec3(centre) + glm::vec3(0, 0, 2.8f * radius), glm::vec3(centre),
                                glm::vec3(0, 1, 0));
                const float black[4] = {0, 0, 0, 0};
                const gfx::GpuSplats& buffers = greg->resource<gfx::GpuSplatStore>().clouds.at(ce);
                for (const auto& pc : paper_cases) {
                    auto t = time_frames(pc, [&]() -> Status {
                        if (Status s1 = deform(); !s1) return s1;
                        target->bind();
                        target->clear_color("color", black);
                        target->clear_depth();
                        paper->draw_deformed(buffers.deformed.id(), buffers.count, view_proj, 2.0f);
                        return {};
                    });
                    if (!t) {
                        cli::command_error("profile", t.message());
                        return 1;
                    }
                    gpu_draw.case_ms.push_back(*t);
                    auto tp = time_frames(pc, [&]() -> Status {
                        target->bind();
                        target->clear_color("color", black);
                        target->clear_depth();
                        return paper->draw(greg->get<Lattice>(le), greg->version<Lattice>(le), cloud->origin,
                                           buffers.rest.id(), buffers.count, view_proj, 2.0f);
                    });
                    if (!tp) {
                        cli::command_error("profile", tp.message());
                        return 1;
                    }
                    paper_mode.case_ms.push_back(*tp);
                }
                paper = make_error("done");  // GL objects go while the context is current
                target = make_error("done");
                ffd_release_gpu(*greg);
                greg.reset();
            }
            rows.push_back(gpu);
            rows.push_back(gpu_draw);
            rows.push_back(paper_mode);
        }
    }

    const MachineInfo m = machine_info(false);
    std::printf("\nmachine: %s, %u cores, %s\n", m.cpu.c_str(), m.cores, m.os.c_str());
    std::printf("%-30s %-42s", "object (splats)", "method");
    for (const auto& pc : paper_cases) std::printf(" %15s", pc.name);
    std::printf(" %10s %9s\n", "FPS", "speed-up");
    for (const auto& r : rows) {
        const std::string obj = r.object + " (" + std::to_string(r.points) + ")";
        std::printf("%-30s %-42s", obj.c_str(), r.method.c_str());
        double sum = 0;
        int n = 0;
        for (double ms : r.case_ms) {
            if (ms < 0) std::printf(" %15s", "-");
            else std::printf(" %12.2f ms", ms), sum += ms, ++n;
        }
        // Speed-up against the naive algorithm's thread CPU time (what its wall time is on an idle core), on
        // the mean over the four cases; the other rows are wall times, so under load the ratio is
        // conservative.
        double naive_mean = 0;
        for (const auto& q : rows)
            if (q.object == r.object && q.method.rfind("paper CPU naive, thread CPU", 0) == 0) {
                for (double ms : q.case_ms) naive_mean += ms < 0 ? -1e300 : ms / 4.0;
            }
        if (n > 0) {
            const double mean = sum / n;
            const double ratio = naive_mean / mean;
            if (naive_mean > 0)
                std::printf(ratio < 10 ? " %10.2f %8.2fx" : " %10.2f %8.0fx", 1000.0 / mean, ratio);
            else std::printf(" %10.2f %9s", 1000.0 / mean, "-");
        } else {
            std::printf(" %10s %9s  %s", "-", "-", r.note.c_str());
        }
        std::printf("\n");
    }
    std::printf("%-30s %-42s %63s %10.2f %8s\n", "paper (59,650 / 40,880)", "paper CPU", "", paper_cpu_fps,
                "1x");
    std::printf("%-30s %-42s %63s %10.2f %8.0fx\n", "paper (59,650 / 40,880)", "paper GPU (vertex shader)",
                "", paper_gpu_fps, paper_speedup);
    return 0;
}

}  // namespace sffd::profile_cmd
