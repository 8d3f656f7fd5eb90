// `skycal batch`: a time-lapse day fitted frame by frame, in chunks (each chunk in time
// order, every frame warm-started from the previous frame's fit), on the local cores or as
// a Slurm array, then a reduce step: the day's multi-reference fit over all frames or a
// subsample, the keyframe tables (`skycal export` over the frames' presets) and batch.json.
// The directory layout and the resume rules are in batch_plan.h.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/fit/fit_options.h"

namespace skycal::cli {

enum class BatchEngine { kLocal, kSlurm };

struct BatchOptions {
  std::string references_glob;      // 'DIR/*.exr' (expanded by skycal, not the shell)
  std::string out_dir;              // the batch directory (batch_plan.h)
  int frames_per_job = 8;           // frames per chunk (one process or one Slurm array task)
  BatchEngine engine = BatchEngine::kLocal;
  int jobs = 0;                     // local: chunks fitted at once (0: the machine's cores)
  bool resume = false;              // complete this --out's batch: fit only missing/failed frames
  bool cold_start = false;          // every frame from --init (no warm start; the benchmark's baseline)
  int day_frames = 24;              // frames in the reduce's day fit, evenly spaced in time (0: all)
  double poll_s = 2.0;              // slurm: seconds between squeue polls
  std::vector<std::string> slurm_options;  // slurm: extra sbatch arguments (--partition=x, --time=10)
  std::string init_preset;          // cold start preset (empty: the bundled default)
  fit::FitOptions fit;              // forwarded to every frame's fit and the day fit
  // Internal modes (the engines start skycal itself with these): fit chunk K of --out's
  // plan; run the reduce of --out's plan.
  int worker_chunk = -1;
  bool reduce_only = false;
  std::vector<std::string> argv;    // the arguments after the verb, recorded in the plan
  bool IsValid(std::string* why) const;
};

nlohmann::json RunBatchImpl(const BatchOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
BatchOptions ParseBatchArgs(int argc, char** argv);
BatchOptions ParseBatchArgs(const std::vector<std::string>& args);
int RunBatch(int argc, char** argv);

}  // namespace skycal::cli
