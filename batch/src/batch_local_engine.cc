// The local engine of `skycal batch`: a pool of child processes over the cores.
#include "batch_engines.h"

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <sstream>
#include <thread>

#include "batch_process.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"

namespace skycal::batch {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string SelfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error("cannot find the running skycal binary (/proc/self/exe: " + ec.message() + ")");
  return p.string();
}

nlohmann::json RunLocalEngine(const std::string& out_dir, const BatchPlan& plan, int jobs) {
  const std::vector<int> pending = PendingChunks(out_dir, plan);
  const std::string exe = SelfExecutable();
  const std::string out_abs = fs::absolute(out_dir).string();
  ProgressPrinter progress(CountBatchProgress(out_dir, plan).done);
  std::map<pid_t, int> running;  // pid -> chunk
  nlohmann::json exits = nlohmann::json::array();
  size_t next = 0;
  auto last_count = Clock::now();
  while (next < pending.size() || !running.empty()) {
    while (next < pending.size() && static_cast<int>(running.size()) < jobs) {
      const int c = pending[next++];
      const pid_t pid = Spawn({exe, "batch", "--worker-chunk", std::to_string(c), "--out", out_abs},
                              LogPath(out_dir, "chunk-" + std::to_string(c) + ".log"), nullptr);
      running[pid] = c;
    }
    for (auto it = running.begin(); it != running.end();) {
      int status = 0;
      const pid_t r = ::waitpid(it->first, &status, WNOHANG);
      if (r == it->first) {
        exits.push_back({{"chunk", it->second}, {"status", DescribeWaitStatus(status)}});
        if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
          BatchLog("chunk " + std::to_string(it->second) + ": " + DescribeWaitStatus(status) + " (log: " +
                           LogPath(out_dir, "chunk-" + std::to_string(it->second) + ".log") + ")");
        }
        it = running.erase(it);
      } else {
        ++it;
      }
    }
    // The states are re-read every 2 s (a day of thousands of frames is thousands of files).
    if (Clock::now() - last_count > std::chrono::seconds(2) || running.empty()) {
      progress.Update(CountBatchProgress(out_dir, plan),
                      std::to_string(running.size()) + " chunks running, " + std::to_string(pending.size() - next) + " waiting");
      last_count = Clock::now();
    }
    if (!running.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return {{"engine", "local"}, {"jobs", jobs}, {"chunks", pending.size()}, {"exits", exits}};
}

}  // namespace skycal::batch
