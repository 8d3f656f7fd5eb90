// Nothing is left behind when a run is interrupted. Temporaries (a file being written, a
// staging directory) register themselves while they exist; `InstallInterruptCleanup()`
// (the binary's main, before any other thread starts) blocks SIGINT, SIGTERM and SIGHUP in
// every thread and leaves them to one watcher thread, which removes what is registered
// and exits with 128 + the signal number (naming any output already moved into place
// complete before the signal: NoteCommittedOutput). A watcher thread rather than a signal handler:
// removing a directory tree is not async-signal-safe, and the watcher can wait for a
// commit in progress (InterruptCleanupCriticalSection) instead of tearing it in half.
//
// A process killed by SIGKILL (or a power cut) cannot clean up: the next run that writes
// into the same directory removes temporaries whose process no longer exists
// (RemoveStaleTemporaries; AtomicOutput and the staged output directory call it).
#pragma once
#include <string>

namespace skycal {

// Registers `path` (file or directory) for removal on interruption while alive. It does
// not remove anything itself: the owner removes or commits, then the guard unregisters.
class TemporaryGuard {
 public:
  explicit TemporaryGuard(std::string path);
  ~TemporaryGuard();
  TemporaryGuard(const TemporaryGuard&) = delete;
  TemporaryGuard& operator=(const TemporaryGuard&) = delete;

 private:
  std::string path_;
};

// While alive, the watcher waits before cleaning up: wrap sequences of renames that must
// not stop half-way (replacing an output directory).
class InterruptCleanupCriticalSection {
 public:
  InterruptCleanupCriticalSection();
  ~InterruptCleanupCriticalSection();
  InterruptCleanupCriticalSection(const InterruptCleanupCriticalSection&) = delete;
  InterruptCleanupCriticalSection& operator=(const InterruptCleanupCriticalSection&) = delete;
};

// Records that `path` (a file or directory) was just moved into place complete: an
// interrupt after this leaves it (it is not partial) and the watcher's message names it,
// so that "interrupted" never hides a finished output. Call it in the same critical
// section as the move.
void NoteCommittedOutput(const std::string& path);

// Call once, from main, before other threads exist. Also ignores SIGPIPE so that writes to
// a closed pipe fail with EPIPE (and the verb reports it) instead of killing the process
// with its temporaries in place.
void InstallInterruptCleanup();

// The temporary names this project uses: ".NAME.tmp-PID", ".NAME.tmp-PID-N" (files and
// staging directories) and ".NAME.old-PID" (a replaced output directory on its way out).
// Returns the PID, or -1 if `name` is not such a name.
long TemporaryOwnerPid(const std::string& name);

// Removes the entries of `dir` with a temporary name whose owning process no longer
// exists on this machine. Returns how many were removed. Never throws.
int RemoveStaleTemporaries(const std::string& dir);

}  // namespace skycal
