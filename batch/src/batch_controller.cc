#include "skycal/batch/batch.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

#include "batch_engines.h"
#include "batch_process.h"
#include "batch_worker.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"

namespace skycal::batch {
namespace fs = std::filesystem;

bool BatchOptions::IsValid(std::string* why) const {
  // Ceres style: the field, its value, what was expected.
  auto bad = [&](const std::string& m) {
    *why = "BatchOptions::" + m;
    return false;
  };
  if (out_dir.empty()) return bad("out_dir is required (the batch directory)");
  if (worker_chunk >= 0 || reduce_only) {
    if (worker_chunk >= 0 && reduce_only)
      return bad("worker_chunk = " + std::to_string(worker_chunk) + " and BatchOptions::reduce_only are separate modes");
    return true;  // the rest comes from the plan in out_dir
  }
  if (references_glob.empty()) return bad("references_glob is required (a glob such as 'day/*.exr')");
  if (frames_per_job < 1)
    return bad("frames_per_job = " + std::to_string(frames_per_job) + " (expected a positive integer)");
  if (jobs < 0) return bad("jobs = " + std::to_string(jobs) + " (expected a positive integer, or 0: the machine's cores)");
  if (day_frames < 0)
    return bad("day_frames = " + std::to_string(day_frames) + " (expected 0: all frames, or a positive integer)");
  if (!(poll_s >= 0.05 && poll_s <= 600.0))
    return bad("poll_s = " + FormatNumber(poll_s) + " (expected seconds in [0.05, 600])");
  if (fit.sun_dir || fit.time_of_day_h)
    return bad("fit.sun_dir and fit.time_of_day_h must be unset (a batch takes each frame's sun direction and time "
               "from its EXR attributes)");
  return fit.IsValid(why);
}

namespace {

// The arguments a worker re-parses: the fit options and the plan-shaping ones, with paths
// made absolute (a Slurm task may start elsewhere).
std::vector<std::string> WorkerArgv(const BatchOptions& o) {
  std::vector<std::string> a = o.argv;
  for (size_t i = 0; i < a.size(); ++i) {
    for (const char* opt : {"--init", "--mask"}) {
      const std::string eq = std::string(opt) + "=";
      if (a[i] == opt && i + 1 < a.size()) a[i + 1] = fs::absolute(a[i + 1]).string();
      else if (a[i].rfind(eq, 0) == 0) a[i] = eq + fs::absolute(a[i].substr(eq.size())).string();
    }
  }
  return a;
}

// A worker's mode: one chunk; a failed frame fails the process (its engine reports it).
nlohmann::json RunWorkerChunk(const BatchOptions& o, const BatchHooks& hooks) {
  nlohmann::json r = RunBatchChunk(o.out_dir, o.worker_chunk, hooks);
  if (!r["failed"].empty()) {
    std::string s;
    for (const auto& f : r["failed"]) s += "\n  " + f["frame"].get<std::string>() + ": " + f["message"].get<std::string>();
    throw Error("chunk " + std::to_string(o.worker_chunk) + ": " + std::to_string(r["failed"].size()) + " frame(s) failed:" + s);
  }
  return r;
}

// The local engine's run, then the reduce here; unfitted frames are refused before it.
nlohmann::json RunLocal(const BatchOptions& o, const BatchPlan& plan, int jobs, const BatchHooks& hooks,
                        nlohmann::json* engine) {
  *engine = RunLocalEngine(o.out_dir, plan, jobs);
  const BatchProgress p = CountBatchProgress(o.out_dir, plan);
  if (p.done != p.total) {
    throw Error(std::to_string(p.total - p.done) + " of " + std::to_string(p.total) + " frames are not fitted (logs in " +
                (fs::path(o.out_dir) / "logs").string() + "):" + DescribeUnfinishedFrames(o.out_dir, plan, 10) +
                "\nthe other frames are kept: fix the cause and run again with BatchOptions::resume (no reduce was run)");
  }
  return RunBatchReduce(o.out_dir, hooks);
}

// The Slurm engine's run (its reduce job writes batch.json); what is missing is named.
nlohmann::json RunSlurm(const BatchOptions& o, const BatchPlan& plan, nlohmann::json* engine_out) {
  const nlohmann::json& engine = *engine_out = RunSlurmEngine(o.out_dir, plan, o);
  const BatchProgress p = CountBatchProgress(o.out_dir, plan);
  const fs::path bj = fs::path(o.out_dir) / "batch.json";
  std::error_code ec;
  if (p.done == p.total && !fs::exists(bj, ec)) {
    throw Error("every frame is fitted but the reduce job " + engine.value("reduce_job", std::string("?")) + " ended " +
                engine.value("reduce_state", std::string("?")) + " without batch.json: see " +
                (fs::path(o.out_dir) / "logs/reduce.log").string() +
                "; run again with BatchOptions::resume to reduce again");
  }
  if (p.done != p.total) {
    throw Error(std::to_string(p.total - p.done) + " of " + std::to_string(p.total) + " frames are not fitted; the reduce job " +
                engine.value("reduce_job", std::string("?")) + " is " + engine.value("reduce_state", std::string("?")) +
                (engine.contains("reduce_reason") ? " (" + engine["reduce_reason"].get<std::string>() + ")" : std::string()) +
                " (logs in " + (fs::path(o.out_dir) / "logs").string() + "):" + DescribeUnfinishedFrames(o.out_dir, plan, 10) +
                "\nthe other frames are kept: run again with BatchOptions::resume to resubmit only the missing or "
                "failed ones");
  }
  return ReadJsonFile(bj.string());
}

}  // namespace

nlohmann::json RunBatch(const BatchOptions& o, const BatchHooks& hooks) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (o.worker_chunk >= 0) return RunWorkerChunk(o, hooks);
  if (o.reduce_only) return RunBatchReduce(o.out_dir, hooks);

  const auto t0 = std::chrono::steady_clock::now();
  if (o.engine == BatchEngine::kSlurm) RequireSlurmClient();  // before out_dir is touched
  BatchPlan plan;
  plan.frames = ScanBatchFrames(ExpandReferenceGlob(o.references_glob));
  plan.chunks = ChunkFrames(static_cast<int>(plan.frames.size()), o.frames_per_job);
  plan.argv = WorkerArgv(o);
  plan.identity = hooks.identity(o, plan.frames);
  const BatchLock lock = PrepareBatchDirectory(o.out_dir, plan, o.resume);
  std::error_code ec;
  fs::remove(fs::path(o.out_dir) / "batch.json", ec);  // this run's reduce writes it anew
  const BatchProgress start = CountBatchProgress(o.out_dir, plan);
  const std::vector<int> pending = PendingChunks(o.out_dir, plan);
  const int jobs = o.jobs > 0 ? o.jobs : std::max(1u, std::thread::hardware_concurrency());
  BatchLog(std::to_string(plan.frames.size()) + " frames (" + std::to_string(plan.frames.front().time_of_day_h) + " to " +
           std::to_string(plan.frames.back().time_of_day_h) + " h, " + std::to_string(plan.frames[0].width) + "x" +
           std::to_string(plan.frames[0].height) + ") in " + std::to_string(plan.chunks.size()) + " chunks of <= " +
           std::to_string(o.frames_per_job) + "; " + std::to_string(start.done) + " done earlier, " +
           std::to_string(pending.size()) + " chunks to run" +
           (o.engine == BatchEngine::kLocal ? " on " + std::to_string(jobs) + " local processes" : " on Slurm"));
  nlohmann::json engine;
  nlohmann::json batch = o.engine == BatchEngine::kLocal ? RunLocal(o, plan, jobs, hooks, &engine) : RunSlurm(o, plan, &engine);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int fitted = static_cast<int>(plan.frames.size()) - start.done;
  engine["wall_s"] = wall;
  engine["frames_fitted"] = fitted;
  engine["frames_per_s"] = wall > 0 ? fitted / wall : 0.0;
  engine["resumed_with_done"] = start.done;
  batch["run"] = engine;
  WriteJsonFileAtomically((fs::path(o.out_dir) / "batch.json").string(), batch);
  BatchLog("wrote " + o.out_dir + ": " + std::to_string(fitted) + " frames fitted in " + std::to_string(wall) + " s (" +
           std::to_string(engine["frames_per_s"].get<double>()) + " frames/s incl. the reduce)");
  return batch;
}

}  // namespace skycal::batch
