#include "skycal/core/interrupt_cleanup.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace skycal {
namespace fs = std::filesystem;
namespace {

// Recursive: a critical section may register or unregister temporaries inside it. These
// three are never destroyed: the watcher may still be using them while the main thread
// runs the static destructors of a normal exit (a signal just after the last commit).
std::recursive_mutex& RegistryMutex() {
  static auto* m = new std::recursive_mutex;
  return *m;
}

std::multiset<std::string>& Registry() {
  static auto* paths = new std::multiset<std::string>;
  return *paths;
}

std::vector<std::string>& Committed() {
  static auto* paths = new std::vector<std::string>;
  return *paths;
}

sigset_t InterruptSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  return set;
}

const char* SignalName(int sig) {
  switch (sig) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    default: return "signal";
  }
}

void WatchForInterrupts() {
  const sigset_t set = InterruptSignals();
  int sig = 0;
  while (sigwait(&set, &sig) != 0) {
  }
  // Holding the lock until exit: no commit starts or finishes half-way after this point.
  RegistryMutex().lock();
  int removed = 0;
  for (const std::string& p : Registry()) {
    std::error_code ec;
    removed += fs::remove_all(p, ec) > 0 ? 1 : 0;
  }
  if (Committed().empty()) {
    std::fprintf(stderr, "skycal: interrupted by %s: removed %d temporary output%s, nothing else was written\n",
                 SignalName(sig), removed, removed == 1 ? "" : "s");
  } else {
    std::string done;
    for (const std::string& p : Committed()) done += (done.empty() ? "" : ", ") + p;
    std::fprintf(stderr, "skycal: interrupted by %s: removed %d temporary output%s; already complete before it: %s\n",
                 SignalName(sig), removed, removed == 1 ? "" : "s", done.c_str());
  }
  std::fflush(stderr);
  _exit(128 + sig);
}

}  // namespace

TemporaryGuard::TemporaryGuard(std::string path) : path_(std::move(path)) {
  std::lock_guard<std::recursive_mutex> lock(RegistryMutex());
  Registry().insert(path_);
}

TemporaryGuard::~TemporaryGuard() {
  std::lock_guard<std::recursive_mutex> lock(RegistryMutex());
  auto it = Registry().find(path_);
  if (it != Registry().end()) Registry().erase(it);
}

void NoteCommittedOutput(const std::string& path) {
  std::lock_guard<std::recursive_mutex> lock(RegistryMutex());
  Committed().push_back(path);
}

InterruptCleanupCriticalSection::InterruptCleanupCriticalSection() { RegistryMutex().lock(); }
InterruptCleanupCriticalSection::~InterruptCleanupCriticalSection() { RegistryMutex().unlock(); }

void InstallInterruptCleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    ::signal(SIGPIPE, SIG_IGN);
    const sigset_t set = InterruptSignals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);  // inherited by every thread started later
    std::thread(WatchForInterrupts).detach();
  });
}

long TemporaryOwnerPid(const std::string& name) {
  if (name.size() < 2 || name[0] != '.') return -1;
  for (const char* tag : {".tmp-", ".old-"}) {
    const size_t at = name.rfind(tag);
    if (at == std::string::npos || at == 0) continue;
    size_t i = at + 5;
    long pid = 0;
    size_t digits = 0;
    while (i < name.size() && name[i] >= '0' && name[i] <= '9' && digits < 10) pid = pid * 10 + (name[i++] - '0'), ++digits;
    if (digits == 0) continue;
    // bench's scratch beside its staging directory: "..NAME.tmp-PID-scratch".
    if (name.compare(i, std::string::npos, "-scratch") == 0) return pid > 0 ? pid : -1;
    if (i < name.size()) {  // an optional "-N" counter, then the end
      if (name[i] != '-' || i + 1 == name.size()) continue;
      size_t j = i + 1;
      while (j < name.size() && name[j] >= '0' && name[j] <= '9') ++j;
      if (j != name.size()) continue;
    }
    return pid > 0 ? pid : -1;
  }
  return -1;
}

int RemoveStaleTemporaries(const std::string& dir) {
  std::error_code ec;
  int removed = 0;
  fs::directory_iterator it(dir.empty() ? "." : dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const long pid = TemporaryOwnerPid(it->path().filename().string());
    if (pid <= 0 || pid == static_cast<long>(::getpid())) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to judge)
    std::error_code rec;
    if (fs::remove_all(it->path(), rec) > 0) ++removed;
  }
  return removed;
}

}  // namespace skycal
