#include "batch_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "skycal/core/error.h"
#include <iostream>

extern char** environ;

namespace skycal::batch {

void BatchLog(const std::string& message) { std::cerr << "[batch] " << message << std::endl; }
namespace fs = std::filesystem;

std::string DescribeWaitStatus(int status) {
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
}

// Starts `args` (args[0] a path) with stdout and stderr appended to `log` (or, with an
// empty log, a pipe returned in *out_fd). Throws naming what failed.
pid_t Spawn(const std::vector<std::string>& args, const std::string& log, int* out_fd) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  int pipe_fds[2] = {-1, -1};
  if (log.empty()) {
    if (::pipe(pipe_fds) != 0) throw Error("cannot create a pipe for " + args[0]);
    posix_spawn_file_actions_adddup2(&fa, pipe_fds[1], 1);
    posix_spawn_file_actions_addclose(&fa, pipe_fds[0]);
    posix_spawn_file_actions_addclose(&fa, pipe_fds[1]);
  } else {
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
  }
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0].c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (log.empty()) ::close(pipe_fds[1]);
  if (rc != 0) {
    if (log.empty()) ::close(pipe_fds[0]);
    throw Error("cannot start " + args[0] + " (" + std::strerror(rc) + ")");
  }
  if (out_fd) *out_fd = pipe_fds[0];
  return pid;
}


Captured RunCapture(const std::vector<std::string>& args) {
  int fd = -1;
  const pid_t pid = Spawn(args, "", &fd);
  Captured c;
  char buf[4096];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) c.out.append(buf, static_cast<size_t>(n));
  ::close(fd);
  ::waitpid(pid, &c.status, 0);
  return c;
}

// `name` on $PATH, else empty.
std::string FindOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream ss(path ? path : "");
  for (std::string dir; std::getline(ss, dir, ':');) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / name;
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

std::string LogPath(const std::string& out_dir, const std::string& name) {
  return (fs::path(out_dir) / "logs" / name).string();
}

ProgressPrinter::ProgressPrinter(int done_at_start) : at_start_(done_at_start), t0_(Clock::now()), last_print_(t0_) {}

void ProgressPrinter::Update(const BatchProgress& p, const std::string& what) {
  const auto now = Clock::now();
  if (p.done == last_.done && p.failed == last_.failed && what == last_what_ && now - last_print_ < std::chrono::minutes(1)) {
    return;
  }
  const double s = std::chrono::duration<double>(now - t0_).count();
  const int fitted = p.done - at_start_;
  std::ostringstream line;
  line << p.done << "/" << p.total << " frames done, " << p.failed << " failed; " << what << "; " << static_cast<int>(s)
       << " s";
  if (fitted > 0 && s > 0) line << ", " << fitted / s << " frames/s";
  BatchLog(line.str());
  last_ = p;
  last_what_ = what;
  last_print_ = now;
}

}  // namespace skycal::batch
