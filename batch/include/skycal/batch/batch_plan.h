// `skycal batch`'s plan and state on disk. A batch directory (--out) holds:
//   batch_plan.json     the frames in time order, their chunks, the forwarded fit options and
//                       the batch's identity (frames by path, size and modification time;
//                       the resolved fit options; chunking and warm starts): a later run
//                       with another identity is refused, the same one resumes.
//   state/<frame>.json  one per fitted frame, written atomically after its fit directory:
//                       {"status": "ok"|"failed", "message", errors, times, warm start}.
//   frames/<frame>/     the frame's `skycal calibrate` output (or `skycal fit`'s, with the
//                       fit frame job; atomic, core/staged_directory.h).
//   logs/               each chunk's (and the Slurm reduce's) log.
//   day/, tables/, batch.json   the reduce step's outputs (day_inputs/: the calibrated
//                       frames' photos linked by frame name for the day fit).
// A frame is done when its state says ok and its fit directory holds preset.json; --resume
// fits every other frame again.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace skycal::batch {

struct BatchFrame {
  std::string path;  // absolute
  std::string name;  // file name without .exr: frames/<name>/, state/<name>.json
  double time_of_day_h = 0.0;          // the skycalTimeOfDay attribute, hours
  std::array<double, 3> sun_dir{};     // the sunDirection attribute, unit vector
  int width = 0, height = 0;           // pixels
  long long size_bytes = 0;
  long long mtime_ns = 0;              // modification time, ns since the epoch
};

// The paths `pattern` matches (glob(3), sorted); throws naming --references when none.
std::vector<std::string> ExpandReferenceGlob(const std::string& pattern);

// Reads every frame's EXR header (no pixels): each must carry sunDirection and
// skycalTimeOfDay, all must share one size, names and times must be unique. Returns the
// frames sorted by time of day. Throws skycal::Error naming the file(s) and the field.
std::vector<BatchFrame> ScanBatchFrames(const std::vector<std::string>& paths);

// Consecutive runs of at most `per_job` frame indices (0-based, time order).
std::vector<std::vector<int>> ChunkFrames(int frames, int per_job);

struct BatchPlan {
  std::vector<BatchFrame> frames;
  std::vector<std::vector<int>> chunks;
  std::vector<std::string> argv;  // the batch's arguments after the verb (workers re-parse them)
  nlohmann::json identity;        // compared on every later run
};

nlohmann::json BatchPlanToJson(const BatchPlan& plan);
BatchPlan LoadBatchPlan(const std::string& out_dir);  // throws naming batch_plan.json

// An exclusive flock(2) on <out_dir>/.batch.lock, held while alive. The descriptor is
// inherited by the local engine's workers (not close-on-exec), so a driver killed alone
// leaves the lock with its still-running workers and a second batch on the same --out is
// refused until they finish.
class BatchLock {
 public:
  explicit BatchLock(int fd) : fd_(fd) {}
  ~BatchLock();
  BatchLock(const BatchLock&) = delete;
  BatchLock& operator=(const BatchLock&) = delete;
  BatchLock(BatchLock&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }

 private:
  int fd_;
};

// Creates `out_dir` (its parent must exist) or checks that it holds this batch's state:
// another batch's (a different identity) or a directory that is no batch directory is
// refused; this batch's own state is refused without `resume` (nothing is redone by
// accident); a batch still running there is refused. Then writes the plan (atomically)
// and the state/, frames/, logs/ folders. The returned lock must outlive the run.
BatchLock PrepareBatchDirectory(const std::string& out_dir, const BatchPlan& plan, bool resume);

std::string FrameStatePath(const std::string& out_dir, const std::string& frame);
std::string FrameFitDir(const std::string& out_dir, const std::string& frame);
std::optional<nlohmann::json> ReadFrameState(const std::string& out_dir, const std::string& frame);
// The state says ok and frames/<name>/preset.json exists.
bool FrameDone(const std::string& out_dir, const std::string& frame);

struct BatchProgress {
  int done = 0, failed = 0, total = 0;
};
BatchProgress CountBatchProgress(const std::string& out_dir, const BatchPlan& plan);

// Indices of the chunks holding a frame that is not done.
std::vector<int> PendingChunks(const std::string& out_dir, const BatchPlan& plan);

}  // namespace skycal::batch
