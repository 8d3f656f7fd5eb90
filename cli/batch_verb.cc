#include "batch_verb.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "fit_verb.h"
#include "fit_option_args.h"
#include "render_verb.h"
#include "skycal/controllers/calibrate.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/sha256.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;

namespace {

// Calibrated frames choose their own fit (segmentation, start preset, clouds): a fit option
// other than the backend and --quiet given with them is refused by name.
void RefuseFitOptionsForCalibrate(const fit::FitOptions& given, const std::string& init_preset) {
  fit::FitOptions plain;
  plain.backend = given.backend;
  plain.verbose = given.verbose;
  const nlohmann::json a = ResolvedFitOptionsJson(given), b = ResolvedFitOptionsJson(plain);
  std::string set;
  for (const auto& [k, v] : a.items())
    if (!b.contains(k) || b[k] != v) set += (set.empty() ? "" : ", ") + k;
  if (!init_preset.empty()) set += (set.empty() ? "" : ", ") + std::string("init");
  if (!set.empty())
    throw Error("fit options (" + set + ") given with --frame-job calibrate (the default), which chooses the fit per "
                "frame; pass --frame-job fit to fit every frame with them");
}

}  // namespace

BatchOptions ParseBatchArgs(int argc, char** argv) {
  VerbCommandLine cl("batch", "skycal batch: calibrate a time-lapse day frame by frame (warm starts), then the day's fit and tables",
                     "  skycal batch --references 'DIR/*.exr' --out DIR [--frames-per-job N] [--engine local|slurm]\n"
                     "               [--jobs N] [--resume] [--day-frames N] [fit options] [--json]",
                     "Each frame needs the EXR attributes sunDirection and skycalTimeOfDay (capture --time,\n"
                     "render --time-of-day). Layout of DIR and the resume rules: docs/batch.md.");
  BatchOptions o;
  std::optional<std::string> engine, frame_job;
  FitOptionArgs fa;
  bool json = false;
  cl.Text("--references", &o.references_glob, "'GLOB'", "the day's frames, a glob expanded by skycal (quote it)");
  cl.Text("--out", &o.out_dir, "DIR", "the batch directory: plan, per-frame fits and states, logs, day/, tables/, batch.json");
  cl.Integer("--frames-per-job", &o.frames_per_job, -1e9, 1e9, "expected an integer", "N",
             "frames per chunk: one process (local) or array task (slurm), fitted in time order\n"
             "with warm starts (default 8)");
  cl.Text("--frame-job", &frame_job, "JOB",
          "calibrate (default: skycal calibrate per frame: segmentation, the kind of sky, clouds,\n"
          "the game's image) or fit (the fit options below, as given, for frames prepared by hand)");
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
  if (frame_job) {
    if (*frame_job == "calibrate") o.frame_job = batch::FrameJob::kCalibrate;
    else if (*frame_job == "fit") o.frame_job = batch::FrameJob::kFit;
    else throw Error("--frame-job: unknown job '" + *frame_job + "' (expected calibrate or fit)");
  }
  ApplyFitOptionArgs(fa, &o.fit);
  if (o.frame_job == batch::FrameJob::kCalibrate) RefuseFitOptionsForCalibrate(o.fit, o.init_preset);
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
nlohmann::json Identity(const BatchOptions& o, const std::vector<batch::BatchFrame>& frames) {
  nlohmann::json fr = nlohmann::json::array();
  for (const batch::BatchFrame& f : frames) fr.push_back({{"path", f.path}, {"size_bytes", f.size_bytes}, {"mtime_ns", f.mtime_ns}});
  const std::string init = o.init_preset.empty() ? DefaultPresetPath() : o.init_preset;
  return {{"frames", fr},
          {"fit_options", ResolvedFitOptionsJson(o.fit)},
          {"init_preset", {{"path", fs::absolute(init).lexically_normal().string()}, {"sha256", Sha256OfFile(init)}}},
          {"frames_per_job", o.frames_per_job},
          {"frame_job", o.frame_job == batch::FrameJob::kCalibrate ? "calibrate" : "fit"},
          {"warm_start", !o.cold_start},
          {"day_frames", o.day_frames}};
}

// The batch library's hooks: the plan's arguments read by this verb's parser, each fit run
// by the fit verb, and the batch's identity with the resolved fit options and init preset.
batch::BatchHooks CliBatchHooks() {
  batch::BatchHooks hooks;
  hooks.parse_options = [](const std::vector<std::string>& args) { return ParseBatchArgs(args); };
  hooks.fit = [](const batch::FitRequest& r) {
    FitVerbOptions fo;
    fo.report = r.report;
    fo.references = r.references;
    fo.init_preset = r.init_preset;
    fo.out_dir = r.out_dir;
    fo.fit = r.fit;
    return RunFitImpl(fo);
  };
  hooks.calibrate = [](const batch::CalibrateRequest& r) {
    controllers::CalibrateOptions c;
    c.photos = {r.photo};
    c.out_dir = r.frames_dir;
    c.init_preset = r.init_preset;
    c.time_of_day_h = r.time_of_day_h;
    c.backend = r.backend;
    c.export_tables = false;  // the reduce's keyframe tables cover every frame
    c.report = false;         // the batch's report covers every frame
    c.verbose = r.verbose;
    std::string why;
    if (!c.IsValid(&why)) throw Error(why);
    const controllers::PhotoCalibration p = controllers::CalibratePhoto(r.photo, c);
    return ReadJsonFile(p.dir + "/fit.json");
  };
  hooks.identity = Identity;
  return hooks;
}

}  // namespace

namespace {

// The batch library's messages name BatchOptions' fields (and FitOptions' for the forwarded
// fit options); the user set them with these flags.
std::string WithBatchFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"BatchOptions::references_glob", "--references"},
                                     {"BatchOptions::out_dir", "--out"},
                                     {"BatchOptions::frames_per_job", "--frames-per-job"},
                                     {"BatchOptions::frame_job", "--frame-job"},
                                     {"BatchOptions::engine", "--engine"},
                                     {"BatchOptions::jobs", "--jobs"},
                                     {"BatchOptions::resume", "--resume"},
                                     {"BatchOptions::day_frames", "--day-frames"},
                                     {"BatchOptions::poll_s", "--poll"},
                                     {"BatchOptions::worker_chunk", "--worker-chunk"},
                                     {"BatchOptions::reduce_only", "--reduce"}};
  return WithFitFlags(FieldsAsFlags(message, kFlags));
}

}  // namespace

nlohmann::json RunBatchImpl(const BatchOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(WithBatchFlags(why));
  try {
    return batch::RunBatch(o, CliBatchHooks());
  } catch (const Error& e) {
    throw Error(WithBatchFlags(e.what()));
  }
}

int RunBatch(int argc, char** argv) {
  return RunVerb("batch", WantsJson(argc, argv), [&]() { return RunBatchImpl(ParseBatchArgs(argc, argv)); });
}

}  // namespace skycal::cli
