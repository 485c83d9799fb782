#include "systems/profiling/profiler.h"

#include <algorithm>
#include <cassert>
#include <limits>

#include "runtime/gfx/gl.h"
#include "systems/profiling/overlay.h"
#include "runtime/app/pass_timer.h"

namespace sffd::profiling {

namespace {
constexpr std::size_t not_kept = std::numeric_limits<std::size_t>::max();
// Bound on outstanding queries: past this the oldest are waited for (only if the GPU is far behind).
constexpr std::size_t max_pending = 4096;
constexpr float overlay_alpha = 0.05f;

void pass_begin_hook(void* owner, const char* name) { static_cast<Profiler*>(owner)->pass_begin(name); }
void pass_end_hook(void* owner, const char* name) { static_cast<Profiler*>(owner)->pass_end(name); }

float ema(float avg, float value, bool first) { return first ? value : avg + overlay_alpha * (value - avg); }
}  // namespace

const char* gpu_timing_name(GpuTiming timing) {
    switch (timing) {
        case GpuTiming::none: return "none";
        case GpuTiming::queries: return "queries";
        case GpuTiming::sync: return "sync";
    }
    return "?";
}

Profiler::Profiler(ProfilerSettings settings)
    : m_settings(settings), m_t0(std::chrono::steady_clock::now()) {}

Profiler::~Profiler() {
    for (GLsync f : m_frame_fences) glDeleteSync(f);
    if (!m_query_names.empty())
        glDeleteQueries(static_cast<GLsizei>(m_query_names.size()), m_query_names.data());
}

double Profiler::now_ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m_t0).count();
}

std::uint32_t Profiler::intern(std::string_view name) {
    // Fast path, no allocation: names usually come from stable storage (Schedule entries, literals), so
    // the pointer finds the id; the content check guards against reused addresses.
    if (auto it = m_pass_ids.find(name.data());
        it != m_pass_ids.end() && m_names[it->second].size() == name.size() && m_names[it->second] == name)
        return it->second;
    std::string key(name);
    std::uint32_t id = 0;
    if (auto it = m_name_ids.find(key); it != m_name_ids.end()) {
        id = it->second;
    } else {
        id = static_cast<std::uint32_t>(m_names.size());
        m_names.push_back(key);
        m_name_ids.emplace(std::move(key), id);
    }
    m_pass_ids[name.data()] = id;
    return id;
}

std::uint32_t Profiler::intern_pass(const char* name) { return intern(name); }

FrameRecord& Profiler::current() { return m_settings.keep_frames ? m_frames.back() : m_scratch; }

void Profiler::attach(Schedule& schedule, ecs::Registry& registry) {
    m_registry = &registry;
    FrameObserver o;
    o.frame_begin = [this](const FrameContext& c) { on_frame_begin(c); };
    o.frame_end = [this](const FrameContext& c) { on_frame_end(c); };
    o.phase_begin = [this](Phase p) { on_phase_begin(p); };
    o.phase_end = [this](Phase p) { on_phase_end(p); };
    o.system_begin = [this](Phase p, std::string_view s) { on_system_begin(p, s); };
    o.system_end = [this](Phase p, std::string_view s) { on_system_end(p, s); };
    schedule.set_observer(std::move(o));
    registry.set_resource<PassTimer>(PassTimer{this, &pass_begin_hook, &pass_end_hook});
    auto& overlay = registry.set_resource<ProfileOverlay>();
    overlay.gpu_method = gpu_timing_name(m_settings.gpu);
}

void Profiler::detach(Schedule& schedule, ecs::Registry& registry) {
    schedule.set_observer({});
    registry.erase_resource<PassTimer>();
    m_registry = nullptr;
}

void Profiler::on_frame_begin(const FrameContext& ctx) {
    if (m_settings.gpu == GpuTiming::queries) pace_frames(), poll_queries(false);
    if (m_settings.gpu == GpuTiming::sync) glFinish();  // the previous frame's GL work is not ours
    m_frame_no = ctx.frame;
    if (m_settings.keep_frames) m_frames.emplace_back();
    FrameRecord& r = current();
    r.frame = ctx.frame;
    r.scopes.clear();
    r.begin_ms = now_ms();
    m_in_frame = true;
}

void Profiler::on_frame_end(const FrameContext&) {
    FrameRecord& r = current();
    r.total_ms = now_ms() - r.begin_ms;
    if (m_settings.gpu == GpuTiming::queries && m_settings.max_frames_in_flight > 0)
        if (GLsync f = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0)) m_frame_fences.push_back(f);
    m_in_frame = false;
    update_overlay(r);
}

// Outside every timed scope: the wait a swap chain would have put into present.
void Profiler::pace_frames() {
    const std::size_t max = std::size_t(std::max(m_settings.max_frames_in_flight, 0));
    while (max > 0 && m_frame_fences.size() >= max) {
        GLsync oldest = m_frame_fences.front();
        // The flush bit makes sure the fence reaches the GPU; loop over timeouts (1 s each).
        while (glClientWaitSync(oldest, GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000) == GL_TIMEOUT_EXPIRED) {
        }
        glDeleteSync(oldest);
        m_frame_fences.erase(m_frame_fences.begin());
    }
}

void Profiler::on_phase_begin(Phase phase) {
    m_phase = phase;
    FrameRecord& r = current();
    m_phase_sample = r.scopes.size();
    ScopeSample s;
    s.name = intern(phase_name(phase));
    s.kind = ScopeKind::phase;
    s.phase = phase;
    s.begin_ms = now_ms();
    r.scopes.push_back(s);
}

void Profiler::on_phase_end(Phase) {
    ScopeSample& s = current().scopes[m_phase_sample];
    s.cpu_ms = now_ms() - s.begin_ms;
}

void Profiler::on_system_begin(Phase phase, std::string_view system) {
    if (m_settings.gpu == GpuTiming::sync) glFinish();
    FrameRecord& r = current();
    m_system_sample = r.scopes.size();
    m_system = intern(system);
    ScopeSample s;
    s.name = m_system;
    s.kind = ScopeKind::system;
    s.phase = phase;
    s.begin_ms = now_ms();
    r.scopes.push_back(s);
}

void Profiler::on_system_end(Phase, std::string_view) {
    // sync: the system's own GL work counts towards its time, not the next system's.
    if (m_settings.gpu == GpuTiming::sync) glFinish();
    ScopeSample& s = current().scopes[m_system_sample];
    s.cpu_ms = now_ms() - s.begin_ms;
    m_system = no_name;
}

std::uint32_t Profiler::acquire_query() {
    if (!m_free_queries.empty()) {
        const std::uint32_t q = m_free_queries.back();
        m_free_queries.pop_back();
        return q;
    }
    GLuint id = 0;
    glCreateQueries(GL_TIMESTAMP, 1, &id);
    static constexpr char label[] = "profiling.timestamp";
    glObjectLabel(GL_QUERY, id, static_cast<GLsizei>(sizeof(label) - 1), label);
    m_query_names.push_back(id);
    return static_cast<std::uint32_t>(m_query_names.size() - 1);
}

void Profiler::pass_begin(const char* name) {
    // Passes issued outside a frame (set-up code) still get a record of their own.
    if (!m_in_frame && m_settings.keep_frames && m_frames.empty()) m_frames.emplace_back();
    FrameRecord& r = current();
    OpenPass open;
    open.sample = r.scopes.size();
    ScopeSample s;
    s.name = intern_pass(name);
    s.system = m_system;
    s.kind = ScopeKind::pass;
    s.phase = m_phase;
    s.depth = static_cast<std::uint16_t>(m_open.size());
    if (m_settings.gpu == GpuTiming::sync) glFinish();
    if (m_settings.gpu == GpuTiming::queries) {
        open.q_begin = acquire_query();
        glQueryCounter(m_query_names[open.q_begin], GL_TIMESTAMP);
    }
    s.begin_ms = now_ms();
    r.scopes.push_back(s);
    m_open.push_back(open);
}

void Profiler::pass_end(const char*) {
    assert(!m_open.empty() && "pass_end(): no open pass");
    if (m_open.empty()) return;
    const OpenPass open = m_open.back();
    m_open.pop_back();
    FrameRecord& r = current();
    ScopeSample& s = r.scopes[open.sample];
    if (m_settings.gpu == GpuTiming::sync) {
        glFinish();
        s.cpu_ms = now_ms() - s.begin_ms;
        s.gpu_ms = s.cpu_ms;  // GPU work of this pass, bracketed by two glFinish calls
        return;
    }
    s.cpu_ms = now_ms() - s.begin_ms;
    if (m_settings.gpu == GpuTiming::queries) {
        Pending p;
        p.frame = m_frame_no;
        p.record = m_settings.keep_frames ? m_frames.size() - 1 : not_kept;
        p.sample = open.sample;
        p.name = s.name;
        p.q_begin = open.q_begin;
        p.q_end = acquire_query();
        glQueryCounter(m_query_names[p.q_end], GL_TIMESTAMP);
        m_pending.push_back(p);
        if (m_pending.size() > max_pending) poll_queries(true);
    }
}

void Profiler::deliver_gpu(const Pending& p, double gpu_ms) {
    if (p.record != not_kept && p.record < m_frames.size() && p.sample < m_frames[p.record].scopes.size())
        m_frames[p.record].scopes[p.sample].gpu_ms = gpu_ms;
    if (!m_registry) return;
    auto* overlay = m_registry->try_resource<ProfileOverlay>();
    if (!overlay) return;
    if (auto it = m_overlay_pass_rows.find(p.name); it != m_overlay_pass_rows.end()) {
        auto& e = overlay->passes[it->second];
        const bool first = e.gpu_avg_ms < 0.0f;
        e.gpu_last_ms = static_cast<float>(gpu_ms);
        e.gpu_avg_ms = ema(e.gpu_avg_ms, e.gpu_last_ms, first);
    }
}

// Reads back every pending pair whose frame is old enough and whose result is available. With `wait`,
// reads everything (blocking), oldest first.
void Profiler::poll_queries(bool wait) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < m_pending.size(); ++i) {
        const Pending& p = m_pending[i];
        bool ready = wait;
        if (!ready && p.frame + static_cast<std::uint64_t>(m_settings.query_latency) <= m_frame_no) {
            GLint available = 0;
            glGetQueryObjectiv(m_query_names[p.q_end], GL_QUERY_RESULT_AVAILABLE, &available);
            ready = available != 0;
        }
        if (!ready) {
            m_pending[kept++] = p;
            continue;
        }
        GLuint64 t_begin = 0, t_end = 0;
        glGetQueryObjectui64v(m_query_names[p.q_begin], GL_QUERY_RESULT, &t_begin);
        glGetQueryObjectui64v(m_query_names[p.q_end], GL_QUERY_RESULT, &t_end);
        const double ms = t_end >= t_begin ? static_cast<double>(t_end - t_begin) * 1e-6 : 0.0;
        deliver_gpu(p, ms);
        m_free_queries.push_back(p.q_begin);
        m_free_queries.push_back(p.q_end);
    }
    m_pending.resize(kept);
}

void Profiler::resolve_all() {
    if (m_settings.gpu == GpuTiming::queries && !m_pending.empty()) {
        glFinish();
        poll_queries(true);
    }
}

void Profiler::clear() {
    resolve_all();
    m_frames.clear();
}

void Profiler::update_overlay(const FrameRecord& record) {
    if (!m_registry) return;
    auto* overlay = m_registry->try_resource<ProfileOverlay>();
    if (!overlay) return;
    auto& o = *overlay;
    o.frame_last_ms = static_cast<float>(record.total_ms);
    o.frame_ms[o.head] = o.frame_last_ms;
    o.head = (o.head + 1) % ProfileOverlay::history;
    o.count = std::min(o.count + 1, ProfileOverlay::history);
    float sum = 0.0f, mx = 0.0f;
    for (std::size_t i = 0; i < o.count; ++i) {
        sum += o.frame_ms[i];
        mx = std::max(mx, o.frame_ms[i]);
    }
    o.frame_avg_ms = sum / static_cast<float>(o.count);
    o.max_ms = mx;

    // A system or pass may run several times a frame (passes per cloud): sum its time per frame.
    std::unordered_map<std::uint64_t, std::pair<double, double>> per_name;  // (kind, name) -> cpu, gpu
    for (const ScopeSample& s : record.scopes) {
        if (s.kind == ScopeKind::phase) continue;
        auto& rows = s.kind == ScopeKind::system ? m_overlay_system_rows : m_overlay_pass_rows;
        auto& list = s.kind == ScopeKind::system ? o.systems : o.passes;
        if (!rows.count(s.name)) {
            rows.emplace(s.name, list.size());
            ProfileOverlay::Entry e;
            e.name = m_names[s.name];
            e.phase = phase_name(s.phase);
            e.avg_ms = -1.0f;
            list.push_back(std::move(e));
        }
        auto& acc = per_name[(std::uint64_t(s.kind) << 32) | s.name];
        acc.first += s.cpu_ms;
        if (s.gpu_ms >= 0.0) acc.second += s.gpu_ms;
    }
    for (const auto& [key, t] : per_name) {
        const auto id = static_cast<std::uint32_t>(key & 0xffffffffu);
        const bool is_system = (key >> 32) == std::uint64_t(ScopeKind::system);
        auto& e = is_system ? o.systems[m_overlay_system_rows[id]] : o.passes[m_overlay_pass_rows[id]];
        const bool first = e.avg_ms < 0.0f;
        e.last_ms = static_cast<float>(t.first);
        e.avg_ms = ema(e.avg_ms, e.last_ms, first);
        if (m_settings.gpu == GpuTiming::sync) {
            e.gpu_last_ms = static_cast<float>(t.second);
            e.gpu_avg_ms = ema(e.gpu_avg_ms, e.gpu_last_ms, e.gpu_avg_ms < 0.0f);
        }
    }
}

}  // namespace sffd::profiling
