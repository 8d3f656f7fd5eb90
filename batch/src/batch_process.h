// Processes for `skycal batch`'s engines: starting skycal's workers and the Slurm client,
// capturing a command's output, finding a program on PATH, and the progress line.
#pragma once
#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

#include "skycal/batch/batch_plan.h"

namespace skycal::batch {

// "exit code N" / "killed by signal S" for a waitpid status.
std::string DescribeWaitStatus(int status);

// Starts `args` (args[0] a path or a name on PATH) with stdout and stderr appended to `log`
// (or, with an empty log, stdout to a pipe returned in *out_fd). Throws naming what failed.
pid_t Spawn(const std::vector<std::string>& args, const std::string& log, int* out_fd);

struct Captured {
  int status = 0;   // waitpid status
  std::string out;  // stdout (stderr goes to ours)
};
Captured RunCapture(const std::vector<std::string>& args);

// `name` on $PATH, else empty.
std::string FindOnPath(const std::string& name);

// "[batch] message" on stderr (the log line every verb's log has).
void BatchLog(const std::string& message);

// <out_dir>/logs/<name>
std::string LogPath(const std::string& out_dir, const std::string& name);

// One log line when the counts change (or every minute): done, failed, what runs, frames/s.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(int done_at_start);
  void Update(const BatchProgress& p, const std::string& what);

 private:
  using Clock = std::chrono::steady_clock;
  int at_start_;
  Clock::time_point t0_, last_print_;
  BatchProgress last_{-1, -1, -1};
  std::string last_what_;
};

}  // namespace skycal::batch
