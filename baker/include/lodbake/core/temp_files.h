#pragma once
// In-flight temporary files, so that a process killed by SIGINT/SIGTERM/SIGHUP removes them before
// it dies: AtomicFileWriter registers every temporary it creates and unregisters it once renamed
// into place or discarded. A build system that interrupts a bake then finds neither the output nor
// any temporary next to it.

#include <string>

namespace lodbake {

/// Records `path` as an in-flight temporary. Returns a slot id for unregisterTempFile, or -1 when
/// the fixed-size registry (kMaxTempFiles entries, each path < 4096 bytes) is full: the file is then
/// not removed on a signal. Thread-safe and lock-free.
int registerTempFile(const std::string& path);

/// Forgets slot `slot` (from registerTempFile; -1 is ignored).
void unregisterTempFile(int slot);

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that unlink every registered temporary (only
/// async-signal-safe calls), restore the default action and re-raise the signal, so the parent
/// sees the process die by that signal. Call once from main-line code (the CLI), never from a library.
void installTempFileSignalCleanup();

/// Number of registry slots.
constexpr int kMaxTempFiles = 256;

} // namespace lodbake
