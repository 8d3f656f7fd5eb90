// A time-lapse day fitted frame by frame, in chunks (each chunk in time order, every frame
// warm-started from the previous frame's fit), on the local cores or as a Slurm array, then
// a reduce step: the day's multi-reference fit over all frames or a subsample, the keyframe
// tables (skycal_export over the frames' presets) and batch.json. The directory layout and
// the resume rules are in batch_plan.h.
//
// The seam to the program above: the engines run the program itself again (the running
// binary, /proc/self/exe, as `skycal batch --worker-chunk K --out DIR`), and a worker reads
// its options back from the arguments the plan recorded. Reading those arguments and running
// a fit belong to the command line and the fit verb, which sit above this library; the
// program hands them in as a table of functions (BatchHooks) instead of this library
// calling up into cli/.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/batch/batch_plan.h"
#include "skycal/fit/fit_options.h"

namespace skycal::batch {

enum class BatchEngine { kLocal, kSlurm };

// What a frame gets: `skycal calibrate`'s pipeline (sky segmentation, the kind of sky, clouds
// where there are clouds, the game's image against the frame; the default), or the plain fit
// with the fit options as given (for frames prepared by hand: masks, cloud flags).
enum class FrameJob { kCalibrate, kFit };

struct BatchOptions {
  std::string references_glob;      // 'DIR/*.exr' (expanded by skycal, not the shell)
  std::string out_dir;              // the batch directory (batch_plan.h)
  int frames_per_job = 8;           // frames per chunk (one process or one Slurm array task)
  BatchEngine engine = BatchEngine::kLocal;
  int jobs = 0;                     // local: chunks fitted at once (0: the machine's cores)
  bool resume = false;              // complete this out_dir's batch: fit only missing/failed frames
  bool cold_start = false;          // every frame from init_preset (no warm start; the benchmark's baseline)
  int day_frames = 24;              // frames in the reduce's day fit, evenly spaced in time (0: all)
  double poll_s = 2.0;              // slurm: seconds between squeue polls
  std::vector<std::string> slurm_options;  // slurm: extra sbatch arguments (--partition=x, --time=10)
  std::string init_preset;          // cold start preset (empty: the bundled default)
  FrameJob frame_job = FrameJob::kCalibrate;
  // Forwarded to every frame's fit (frame_job kFit; kCalibrate takes only the backend and
  // verbose) and to the day fit.
  fit::FitOptions fit;
  // Internal modes (the engines start skycal itself with these): fit chunk K of out_dir's
  // plan; run the reduce of out_dir's plan.
  int worker_chunk = -1;
  bool reduce_only = false;
  std::vector<std::string> argv;    // the arguments after the verb, recorded in the plan
  bool IsValid(std::string* why) const;
};

// One fit the batch asks for: a frame (one reference) or the day (several).
struct FitRequest {
  std::vector<std::string> references;
  std::string init_preset;  // empty: the bundled default
  std::string out_dir;      // written atomically
  fit::FitOptions fit;
  bool report = false;      // the batch's own report covers every fit
};

// One frame calibrated (FrameJob::kCalibrate): into frames_dir/<the photo's stem>.
struct CalibrateRequest {
  std::string photo;
  std::string frames_dir;
  std::string init_preset;  // the previous frame's preset (a warm start); empty: the bundled default
  double time_of_day_h = 0.0;
  render::Backend backend = render::Backend::kVulkan;
  bool verbose = true;
};

struct BatchHooks {
  // A plan's recorded arguments (BatchPlan::argv) back to options: the verb's own parser.
  std::function<BatchOptions(const std::vector<std::string>& args)> parse_options;
  // Runs one fit; returns its summary (fit.json: references[].rel_rmse, log_rmse, exposure,
  // name; haziness_g, time_s, iterations). Throws on failure.
  std::function<nlohmann::json(const FitRequest& request)> fit;
  // Calibrates one frame (the calibrate controller); returns its fit.json. Throws on failure
  // or refusal (a night frame, no sky), leaving nothing behind.
  std::function<nlohmann::json(const CalibrateRequest& request)> calibrate;
  // What makes two runs the same batch (BatchPlan::identity): the frames, the resolved fit
  // options and init preset, the chunking and warm starts.
  std::function<nlohmann::json(const BatchOptions& options, const std::vector<BatchFrame>& frames)> identity;
};

// The controller: by options' mode, one chunk (worker_chunk), the reduce (reduce_only), or
// the whole batch (plan, engine, reduce). Returns batch.json (or the chunk's result).
// Throws skycal::Error naming the frames that failed.
nlohmann::json RunBatch(const BatchOptions& options, const BatchHooks& hooks);

}  // namespace skycal::batch
