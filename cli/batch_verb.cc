#include "batch_verb.h"

#include <chrono>
#include <filesystem>
#include <thread>

#include "batch_engines.h"
#include "batch_plan.h"
#include "batch_worker.h"
#include "command_line.h"
#include "fit_option_args.h"
#include "render_verb.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/sha256.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;

bool BatchOptions::IsValid(std::string* why) const {
  if (out_dir.empty()) {
    *why = "--out DIR is required";
    return false;
  }
  if (worker_chunk >= 0 || reduce_only) {
    if (worker_chunk >= 0 && reduce_only) {
      *why = "--worker-chunk and --reduce are separate modes";
      return false;
    }
    return true;  // the rest comes from the plan in --out
  }
  if (references_glob.empty()) {
    *why = "--references 'GLOB' is required (e.g. 'day/*.exr', quoted)";
    return false;
  }
  if (frames_per_job < 1) {
    *why = "--frames-per-job: expected a positive integer";
    return false;
  }
  if (jobs < 0) {
    *why = "--jobs: expected a positive integer (0: the machine's cores)";
    return false;
  }
  if (day_frames < 0) {
    *why = "--day-frames: expected 0 (all frames) or a positive integer";
    return false;
  }
  if (!(poll_s >= 0.05 && poll_s <= 600.0)) {
    *why = "--poll: expected seconds in [0.05, 600]";
    return false;
  }
  if (fit.sun_dir || fit.time_of_day_h) {
    *why = "a batch takes each frame's sun direction and time from its EXR attributes";
    return false;
  }
  return fit.IsValid(why);
}

BatchOptions ParseBatchArgs(int argc, char** argv) {
  VerbCommandLine cl("batch", "skycal batch: fit a time-lapse day frame by frame (warm starts), then the day's tables",
                     "  skycal batch --references 'DIR/*.exr' --out DIR [--frames-per-job N] [--engine local|slurm]\n"
                     "               [--jobs N] [--resume] [--day-frames N] [fit options] [--json]",
                     "Each frame needs the EXR attributes sunDirection and skycalTimeOfDay (capture --time,\n"
                     "render --time-of-day). Layout of DIR and the resume rules: README, Batch: a time-lapse day.");
  BatchOptions o;
  std::optional<std::string> engine;
  FitOptionArgs fa;
  bool json = false;
  cl.Text("--references", &o.references_glob, "'GLOB'", "the day's frames, a glob expanded by skycal (quote it)");
  cl.Text("--out", &o.out_dir, "DIR", "the batch directory: plan, per-frame fits and states, logs, day/, tables/, batch.json");
  cl.Integer("--frames-per-job", &o.frames_per_job, -1e9, 1e9, "expected an integer", "N",
             "frames per chunk: one process (local) or array task (slurm), fitted in time order\n"
             "with warm starts (default 8)");
  cl.Text("--engine", &engine, "NAME", "local (default: a process pool over the cores) or slurm (sbatch --array + afterok reduce)");
  cl.Integer("--jobs", &o.jobs, -1e9, 1e9, "expected an integer", "N", "local: chunks fitted at once (default 0: the machine's cores)");
  cl.Flag("--resume", &o.resume, "complete the batch in --out: fit only its missing or failed frames, then reduce");
  cl.Flag("--cold-start", &o.cold_start, "start every frame from --init, not from the previous frame (to measure warm starts)");
  cl.Integer("--day-frames", &o.day_frames, -1e9, 1e9, "expected an integer", "N",
             "frames in the reduce's day fit, evenly spaced in time (default 24; 0: all)");
  cl.Number("--poll", &o.poll_s, "S", "slurm: seconds between squeue polls (default 2)");
  cl.Repeatable("--slurm-option", &o.slurm_options, "ARG", "slurm: one more sbatch argument (repeatable), e.g. --slurm-option=--partition=day");
  RegisterFitOptionArgs(cl, &fa, &o.fit, &o.init_preset);
  cl.Integer("--worker-chunk", &o.worker_chunk, -1, 1e9, "expected a chunk index", "K",
             "internal (the engines run it): fit chunk K of the plan in --out");
  cl.Flag("--reduce", &o.reduce_only, "internal (the slurm engine's reduce job): the reduce of the plan in --out");
  cl.Flag("--json", &json, "print batch.json on stdout");
  cl.Parse(argc, argv);
  if (engine) {
    if (*engine == "local") o.engine = BatchEngine::kLocal;
    else if (*engine == "slurm") o.engine = BatchEngine::kSlurm;
    else throw Error("--engine: unknown engine '" + *engine + "' (expected local or slurm)");
  }
  ApplyFitOptionArgs(fa, &o.fit);
  for (int i = 0; i < argc; ++i) o.argv.emplace_back(argv[i]);
  return o;
}

BatchOptions ParseBatchArgs(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  return ParseBatchArgs(static_cast<int>(argv.size()), argv.data());
}

namespace {

// What makes two runs the same batch: the frames (path, size, modification time), the fit
// options, the cold start preset, the chunking and warm starts, the day fit's subsample.
nlohmann::json Identity(const BatchOptions& o, const std::vector<BatchFrame>& frames) {
  nlohmann::json fr = nlohmann::json::array();
  for (const BatchFrame& f : frames) fr.push_back({{"path", f.path}, {"size_bytes", f.size_bytes}, {"mtime_ns", f.mtime_ns}});
  const std::string init = o.init_preset.empty() ? DefaultPresetPath() : o.init_preset;
  return {{"frames", fr},
          {"fit_options", ResolvedFitOptionsJson(o.fit)},
          {"init_preset", {{"path", fs::absolute(init).lexically_normal().string()}, {"sha256", Sha256OfFile(init)}}},
          {"frames_per_job", o.frames_per_job},
          {"warm_start", !o.cold_start},
          {"day_frames", o.day_frames}};
}

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

}  // namespace

nlohmann::json RunBatchImpl(const BatchOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (o.worker_chunk >= 0) {
    nlohmann::json r = RunBatchChunk(o.out_dir, o.worker_chunk);
    if (!r["failed"].empty()) {
      std::string s;
      for (const auto& f : r["failed"]) s += "\n  " + f["frame"].get<std::string>() + ": " + f["message"].get<std::string>();
      throw Error("chunk " + std::to_string(o.worker_chunk) + ": " + std::to_string(r["failed"].size()) + " frame(s) failed:" + s);
    }
    return r;
  }
  if (o.reduce_only) return RunBatchReduce(o.out_dir);

  const auto t0 = std::chrono::steady_clock::now();
  if (o.engine == BatchEngine::kSlurm) RequireSlurmClient();  // before --out is touched
  BatchPlan plan;
  plan.frames = ScanBatchFrames(ExpandReferenceGlob(o.references_glob));
  plan.chunks = ChunkFrames(static_cast<int>(plan.frames.size()), o.frames_per_job);
  plan.argv = WorkerArgv(o);
  plan.identity = Identity(o, plan.frames);
  const BatchLock lock = PrepareBatchDirectory(o.out_dir, plan, o.resume);
  std::error_code ec;
  fs::remove(fs::path(o.out_dir) / "batch.json", ec);  // this run's reduce writes it anew
  const BatchProgress start = CountBatchProgress(o.out_dir, plan);
  const std::vector<int> pending = PendingChunks(o.out_dir, plan);
  const int jobs = o.jobs > 0 ? o.jobs : std::max(1u, std::thread::hardware_concurrency());
  Log("batch", std::to_string(plan.frames.size()) + " frames (" + std::to_string(plan.frames.front().time_of_day_h) + " to " +
                   std::to_string(plan.frames.back().time_of_day_h) + " h, " + std::to_string(plan.frames[0].width) + "x" +
                   std::to_string(plan.frames[0].height) + ") in " + std::to_string(plan.chunks.size()) + " chunks of <= " +
                   std::to_string(o.frames_per_job) + "; " + std::to_string(start.done) + " done earlier, " +
                   std::to_string(pending.size()) + " chunks to run" +
                   (o.engine == BatchEngine::kLocal ? " on " + std::to_string(jobs) + " local processes" : " on Slurm"));
  nlohmann::json engine;
  nlohmann::json batch;
  if (o.engine == BatchEngine::kLocal) {
    engine = RunLocalEngine(o.out_dir, plan, jobs);
    const BatchProgress p = CountBatchProgress(o.out_dir, plan);
    if (p.done != p.total) {
      throw Error(std::to_string(p.total - p.done) + " of " + std::to_string(p.total) + " frames are not fitted (logs in " +
                  (fs::path(o.out_dir) / "logs").string() + "):" + DescribeUnfinishedFrames(o.out_dir, plan, 10) +
                  "\nthe other frames are kept: fix the cause and run again with --resume (no reduce was run)");
    }
    batch = RunBatchReduce(o.out_dir);
  } else {
    engine = RunSlurmEngine(o.out_dir, plan, o);
    const BatchProgress p = CountBatchProgress(o.out_dir, plan);
    const fs::path bj = fs::path(o.out_dir) / "batch.json";
    if (p.done == p.total && !fs::exists(bj, ec)) {
      throw Error("every frame is fitted but the reduce job " + engine.value("reduce_job", std::string("?")) + " ended " +
                  engine.value("reduce_state", std::string("?")) + " without batch.json: see " +
                  (fs::path(o.out_dir) / "logs/reduce.log").string() + "; run again with --resume to reduce again");
    }
    if (p.done != p.total) {
      throw Error(std::to_string(p.total - p.done) + " of " + std::to_string(p.total) + " frames are not fitted; the reduce job " +
                  engine.value("reduce_job", std::string("?")) + " is " + engine.value("reduce_state", std::string("?")) +
                  (engine.contains("reduce_reason") ? " (" + engine["reduce_reason"].get<std::string>() + ")" : std::string()) +
                  " (logs in " + (fs::path(o.out_dir) / "logs").string() + "):" + DescribeUnfinishedFrames(o.out_dir, plan, 10) +
                  "\nthe other frames are kept: run again with --resume to resubmit only the missing or failed ones");
    }
    batch = ReadJsonFile(bj.string());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int fitted = static_cast<int>(plan.frames.size()) - start.done;
  engine["wall_s"] = wall;
  engine["frames_fitted"] = fitted;
  engine["frames_per_s"] = wall > 0 ? fitted / wall : 0.0;
  engine["resumed_with_done"] = start.done;
  batch["run"] = engine;
  WriteJsonFileAtomically((fs::path(o.out_dir) / "batch.json").string(), batch);
  Log("batch", "wrote " + o.out_dir + ": " + std::to_string(fitted) + " frames fitted in " + std::to_string(wall) + " s (" +
                   std::to_string(engine["frames_per_s"].get<double>()) + " frames/s incl. the reduce)");
  return batch;
}

int RunBatch(int argc, char** argv) {
  return RunVerb("batch", WantsJson(argc, argv), [&]() { return RunBatchImpl(ParseBatchArgs(argc, argv)); });
}

}  // namespace skycal::cli
