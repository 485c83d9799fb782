#include "runtime/app/frame_loop.h"

#include <cstdlib>

namespace sffd {

const char* phase_name(Phase phase) {
    switch (phase) {
        case Phase::input: return "input";
        case Phase::animation: return "animation";
        case Phase::residency: return "residency";
        case Phase::deformation: return "deformation";
        case Phase::picking: return "picking";
        case Phase::rendering: return "rendering";
        case Phase::present: return "present";
    }
    return "?";
}

namespace {
// With SFFD_ACCESS_WARN=1 (each violation printed once, not fatal) a system without a declaration is
// checked as one that declares nothing: the run lists every type it touches, to write its declaration.
bool listing_undeclared() {
    static const bool on = [] {
        const char* v = std::getenv("SFFD_ACCESS_WARN");
        return v && *v && *v != '0';
    }();
    return on;
}
const ecs::Access& nothing_declared() {
    static const ecs::Access none = ecs::no_access();
    return none;
}
}  // namespace

void Schedule::add(Phase phase, std::string name, SystemFn fn, ecs::Access access) {
    m_phases[static_cast<std::size_t>(phase)].push_back({std::move(name), std::move(fn), std::move(access)});
}

void Schedule::run_frame(ecs::Registry& registry, const FrameContext& frame) const {
    if (m_observer.frame_begin) m_observer.frame_begin(frame);
    for (std::size_t p = 0; p < phase_count; ++p) {
        const auto phase = static_cast<Phase>(p);
        if (m_observer.phase_begin) m_observer.phase_begin(phase);
        for (const Entry& system : m_phases[p]) {
            if (m_observer.system_begin) m_observer.system_begin(phase, system.name);
            {
                const ecs::ActiveAccess active{system.name, listing_undeclared() && !system.access.declared()
                                                                ? &nothing_declared()
                                                                : &system.access};
                const ecs::AccessScope scope(registry, active);
                system.fn(registry, frame);
            }
            if (m_observer.system_end) m_observer.system_end(phase, system.name);
        }
        registry.flush();
        if (m_observer.phase_end) m_observer.phase_end(phase);
    }
    if (m_observer.frame_end) m_observer.frame_end(frame);
}

}  // namespace sffd
