// The temporary-file registry behind installTempFileSignalCleanup(). A signal handler may only use
// async-signal-safe calls (POSIX.1 signal-safety(7)): it reads slots through lock-free atomics and
// calls unlink(), sigaction() and raise(), nothing that allocates or locks.
#include "lodbake/core/temp_files.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>

#include <unistd.h>

namespace lodbake {

namespace {

constexpr size_t kMaxPathBytes = 4096;

// state: 0 free, 1 being filled or emptied (handler skips it), 2 holds a path to remove.
struct Slot {
    std::atomic<int> state{0};
    char path[kMaxPathBytes];
};

Slot g_slots[kMaxTempFiles];

static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP};

extern "C" void cleanupAndReraise(int sig) {
    const int saved_errno = errno;
    for (Slot& slot : g_slots)
        if (slot.state.load(std::memory_order_acquire) == 2) ::unlink(slot.path);
    struct sigaction dfl;
    std::memset(&dfl, 0, sizeof(dfl));
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    ::sigaction(sig, &dfl, nullptr);
    errno = saved_errno;
    // The signal is blocked while its handler runs; raise() delivers it on return from the handler
    // at the latest, now with the default action, so the process dies by it.
    ::raise(sig);
}

} // namespace

int registerTempFile(const std::string& path) {
    if (path.size() + 1 > kMaxPathBytes) return -1;
    for (int i = 0; i < kMaxTempFiles; ++i) {
        int expected = 0;
        if (!g_slots[i].state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
        std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
        g_slots[i].state.store(2, std::memory_order_release);
        return i;
    }
    return -1;
}

void unregisterTempFile(int slot) {
    if (slot < 0 || slot >= kMaxTempFiles) return;
    g_slots[slot].state.store(0, std::memory_order_release);
}

void installTempFileSignalCleanup() {
    for (int sig : kCleanupSignals) {
        // A signal the parent ignores (nohup, a background job) stays ignored.
        struct sigaction old;
        if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        struct sigaction action;
        std::memset(&action, 0, sizeof(action));
        action.sa_handler = cleanupAndReraise;
        sigemptyset(&action.sa_mask);
        // Block the other cleanup signals during the handler so two of them never interleave.
        for (int other : kCleanupSignals) sigaddset(&action.sa_mask, other);
        ::sigaction(sig, &action, nullptr);
    }
}

} // namespace lodbake
