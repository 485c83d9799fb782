#include "runtime/assets/formats/archive/mapping_guard.h"

#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <utility>

namespace sffd::assets {

namespace {

constexpr int kSlots = 64;

// Lock-free for the handler: a slot is in use while `end` is non-zero; begin is written before end.
struct Slot {
    std::atomic<std::uintptr_t> begin{0}, end{0};
    std::atomic<bool> hit{false};
};
Slot g_slots[kSlots];
std::atomic<bool> g_claim[kSlots];  // slot ownership, taken by registration only
struct sigaction g_previous {};
std::uintptr_t g_page = 4096;  // set before the handler is installed (sysconf is not for signal handlers)

void on_sigbus(int sig, siginfo_t* info, void* context) {
    const auto addr = reinterpret_cast<std::uintptr_t>(info->si_addr);
    for (Slot& s : g_slots) {
        const std::uintptr_t end = s.end.load(std::memory_order_acquire);
        if (end == 0 || addr < s.begin.load(std::memory_order_relaxed) || addr >= end) continue;
        // mmap is a plain system call (async-signal-safe in practice on Linux, as sigaction's users rely
        // on): the page becomes private zeros and the faulting load is retried against it.
        void* at = reinterpret_cast<void*>(addr / g_page * g_page);
        if (::mmap(at, g_page, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0) != MAP_FAILED) {
            s.hit.store(true, std::memory_order_release);
            return;
        }
        break;
    }
    // Not ours (or the page could not be replaced): what would have happened without this handler.
    if (g_previous.sa_flags & SA_SIGINFO) {
        if (g_previous.sa_sigaction) return g_previous.sa_sigaction(sig, info, context);
    } else if (g_previous.sa_handler != SIG_DFL && g_previous.sa_handler != SIG_IGN) {
        return g_previous.sa_handler(sig);
    }
    ::signal(SIGBUS, SIG_DFL);  // the faulting access runs again and ends the process with SIGBUS
}

void install_once() {
    static std::once_flag once;
    std::call_once(once, [] {
        g_page = std::uintptr_t(::sysconf(_SC_PAGESIZE));
        struct sigaction sa {};
        sa.sa_sigaction = on_sigbus;
        sa.sa_flags = SA_SIGINFO;
        sigemptyset(&sa.sa_mask);
        ::sigaction(SIGBUS, &sa, &g_previous);
    });
}

}  // namespace

MappingGuard::MappingGuard(const void* base, std::size_t size) {
    if (!base || size == 0) return;
    install_once();
    for (int i = 0; i < kSlots; ++i) {
        bool free = false;
        if (!g_claim[i].compare_exchange_strong(free, true)) continue;
        Slot& s = g_slots[i];
        s.hit.store(false, std::memory_order_relaxed);
        s.begin.store(reinterpret_cast<std::uintptr_t>(base), std::memory_order_relaxed);
        s.end.store(reinterpret_cast<std::uintptr_t>(base) + size, std::memory_order_release);
        m_slot = i;
        return;
    }
}

MappingGuard::MappingGuard(MappingGuard&& o) noexcept : m_slot(std::exchange(o.m_slot, -1)) {}

MappingGuard& MappingGuard::operator=(MappingGuard&& o) noexcept {
    if (this != &o) {
        release();
        m_slot = std::exchange(o.m_slot, -1);
    }
    return *this;
}

MappingGuard::~MappingGuard() { release(); }

bool MappingGuard::changed() const {
    return m_slot >= 0 && g_slots[m_slot].hit.load(std::memory_order_acquire);
}

void MappingGuard::release() {
    if (m_slot < 0) return;
    g_slots[m_slot].end.store(0, std::memory_order_release);
    g_claim[m_slot].store(false, std::memory_order_release);
    m_slot = -1;
}

}  // namespace sffd::assets
