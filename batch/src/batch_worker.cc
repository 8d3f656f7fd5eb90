#include "batch_worker.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "batch_process.h"
#include "skycal/export/game_export.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/report/report.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"

namespace skycal::batch {
namespace fs = std::filesystem;
namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string Hostname() {
  char host[256] = {0};
  ::gethostname(host, sizeof host - 1);
  return host;
}

// The reduce's day-fit frames: `m` indices evenly spaced over `n` (all when m is 0 or >= n).
std::vector<int> DaySubsample(int n, int m) {
  std::vector<int> idx;
  if (m <= 0 || m >= n) {
    for (int i = 0; i < n; ++i) idx.push_back(i);
    return idx;
  }
  for (int k = 0; k < m; ++k) {
    const int i = m == 1 ? 0 : static_cast<int>(std::lround(static_cast<double>(k) * (n - 1) / (m - 1)));
    if (idx.empty() || idx.back() != i) idx.push_back(i);
  }
  return idx;
}

// OUT/report.html (skycal_report) over the frames' fits (two levels: frames/<name>/).
void WriteBatchReport(const std::string& out_dir) {
  report::ReportOptions ro;
  ro.max_depth = 2;
  report::ReportSummary s;
  try {
    s = report::WriteReport(out_dir, ro);
  } catch (const Error& e) {
    throw Error(std::string("report.html: ") + e.what() + " (the report of the batch's fits)");
  }
  BatchLog("report.html: " + std::to_string(s.images) + " images, " + std::to_string(s.plots) + " plots, " +
           std::to_string(s.bytes / 1024) + " KiB");
}

// One frame's job (BatchOptions::frame_job) from `start` (a preset; empty: the bundled
// default) into fit_dir; its fit.json.
fit::FitResultFile RunFrameJob(const BatchOptions& o, const BatchFrame& f, const std::string& fit_dir,
                               const std::string& start, const BatchHooks& hooks) {
  if (o.frame_job == FrameJob::kCalibrate) {
    CalibrateRequest c;
    c.photo = f.path;
    c.frames_dir = fs::path(fit_dir).parent_path().string();
    c.init_preset = start;
    c.time_of_day_h = f.time_of_day_h;
    c.backend = o.fit.backend;
    c.verbose = o.fit.verbose;
    return fit::FitResultFileFromJson(hooks.calibrate(c), fit_dir + "/fit.json");
  }
  FitRequest fo;
  fo.report = false;  // the batch's report covers every frame (a page per frame would cost ~0.1 s each)
  fo.references = {f.path};
  fo.init_preset = start;
  fo.out_dir = fit_dir;
  fo.fit = o.fit;
  return fit::FitResultFileFromJson(hooks.fit(fo), fit_dir + "/fit.json");
}

// The reduce's day fit: the frames themselves, or (calibrated frames) the photos as the
// calibration read them (frames/<name>/photo.exr, linked as day_inputs/<name>.exr: a
// reference is named by its file), each with its own sky mask.
FitRequest DayFitRequest(const BatchOptions& o, const BatchPlan& plan, const std::string& out_dir,
                         const std::vector<int>& day_idx) {
  FitRequest day;
  for (int i : day_idx) {
    const BatchFrame& f = plan.frames[i];
    if (o.frame_job == FrameJob::kFit) {
      day.references.push_back(f.path);
      continue;
    }
    const fs::path dir = FrameFitDir(out_dir, f.name), link = fs::path(out_dir) / "day_inputs" / (f.name + ".exr");
    fs::create_directories(link.parent_path());
    std::error_code ec;
    fs::remove(link, ec);
    fs::create_symlink(fs::path("..") / fs::relative(dir, out_dir) / "photo.exr", link);
    day.references.push_back(link.string());
    day.fit.mask_paths.push_back((dir / "mask.exr").string());
  }
  const std::vector<std::string> masks = day.fit.mask_paths;
  day.fit = o.fit;
  day.fit.mask_paths = masks;
  day.init_preset = o.init_preset;
  day.out_dir = (fs::path(out_dir) / "day").string();
  day.report = false;  // part of the batch's report
  return day;
}

}  // namespace

nlohmann::json RunBatchChunk(const std::string& out_dir, int chunk, const BatchHooks& hooks) {
  const BatchPlan plan = LoadBatchPlan(out_dir);
  if (chunk < 0 || chunk >= static_cast<int>(plan.chunks.size())) {
    throw Error("BatchOptions::worker_chunk = " + std::to_string(chunk) + ": the plan in " + out_dir + " has " +
                std::to_string(plan.chunks.size()) + " chunks");
  }
  const BatchOptions o = hooks.parse_options(plan.argv);
  const auto& members = plan.chunks[chunk];
  BatchLog("chunk " + std::to_string(chunk) + ": " + std::to_string(members.size()) + " frames on " + Hostname() +
                   " (pid " + std::to_string(::getpid()) + ")");
  std::string warm;  // the previous fitted frame's preset
  nlohmann::json failed = nlohmann::json::array();
  int fitted = 0;
  for (size_t k = 0; k < members.size(); ++k) {
    const BatchFrame& f = plan.frames[members[k]];
    const std::string fit_dir = FrameFitDir(out_dir, f.name);
    if (FrameDone(out_dir, f.name)) {
      warm = (fs::path(fit_dir) / "preset.json").string();
      BatchLog(f.name + ": done earlier, kept");
      continue;
    }
    std::error_code ec;
    fs::remove(FrameStatePath(out_dir, f.name), ec);  // a failed attempt's state: this one replaces it
    const bool use_warm = !o.cold_start && !warm.empty();
    nlohmann::json state = {{"frame", f.name},
                            {"path", f.path},
                            {"chunk", chunk},
                            {"time_of_day_h", f.time_of_day_h},
                            {"sun_elevation_deg", latlong::ElevationDeg(f.sun_dir)},
                            {"warm_start_from", use_warm ? nlohmann::json(fs::path(warm).parent_path().filename().string())
                                                         : nlohmann::json()},
                            {"host", Hostname()}};
    BatchLog("frame " + std::to_string(k + 1) + "/" + std::to_string(members.size()) + " of chunk " +
                     std::to_string(chunk) + ": " + f.name + " (" + std::to_string(f.time_of_day_h) + " h, " +
                     (use_warm ? "warm start from " + state["warm_start_from"].get<std::string>() : std::string("cold start")) +
                     ")");
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const fit::FitResultFile s = RunFrameJob(o, f, fit_dir, use_warm ? warm : o.init_preset, hooks);
      const fit::FitReferenceEntry& r = s.references.at(0);
      state["status"] = "ok";
      if (s.calibration) {
        state["sky_kind"] = s.calibration->sky_kind;
        state["game_per_pixel_log_rmse"] = s.calibration->game_per_pixel_log_rmse;
        state["game_appearance_error"] = s.calibration->game_appearance_error;
      }
      state["rel_rmse"] = r.rel_rmse;
      state["log_rmse"] = r.log_rmse;
      state["exposure"] = r.exposure;
      state["haziness_g"] = s.haziness_g;
      state["fit_time_s"] = s.time_s;
      state["iterations"] = s.iterations;
      warm = (fs::path(fit_dir) / "preset.json").string();
      ++fitted;
    } catch (const std::exception& e) {
      state["status"] = "failed";
      state["message"] = e.what();
      failed.push_back({{"frame", f.name}, {"message", e.what()}});
      BatchLog(f.name + ": failed: " + e.what());
    }
    state["wall_s"] = Seconds(t0, std::chrono::steady_clock::now());
    WriteJsonFileAtomically(FrameStatePath(out_dir, f.name), state);
  }
  return {{"chunk", chunk}, {"fitted", fitted}, {"failed", failed}};
}

std::string DescribeUnfinishedFrames(const std::string& out_dir, const BatchPlan& plan, int limit) {
  std::string s;
  int n = 0;
  for (const BatchFrame& f : plan.frames) {
    if (FrameDone(out_dir, f.name)) continue;
    if (n++ >= limit) continue;
    const auto st = ReadFrameState(out_dir, f.name);
    s += "\n  " + f.name + ": " +
         (st && st->contains("message") ? st->at("message").get<std::string>()
                                        : std::string("no result (its chunk did not finish it)"));
  }
  if (n > limit) s += "\n  ... and " + std::to_string(n - limit) + " more";
  return s;
}

nlohmann::json RunBatchReduce(const std::string& out_dir, const BatchHooks& hooks) {
  const auto t0 = std::chrono::steady_clock::now();
  const BatchPlan plan = LoadBatchPlan(out_dir);
  const BatchOptions o = hooks.parse_options(plan.argv);
  const BatchProgress p = CountBatchProgress(out_dir, plan);
  if (p.done != p.total) {
    throw Error("reduce: " + std::to_string(p.total - p.done) + " of " + std::to_string(p.total) +
                " frames are not fitted:" + DescribeUnfinishedFrames(out_dir, plan, 10) +
                "\nrun the batch again with BatchOptions::resume and the same options to fit them");
  }
  nlohmann::json frames = nlohmann::json::array();
  double warm_s = 0, cold_s = 0;
  int warm_n = 0, cold_n = 0;
  for (const BatchFrame& f : plan.frames) {
    nlohmann::json s = *ReadFrameState(out_dir, f.name);
    s["fit_dir"] = "frames/" + f.name;
    const bool warm = !s.value("warm_start_from", nlohmann::json()).is_null();
    (warm ? warm_s : cold_s) += s.value("fit_time_s", 0.0);
    (warm ? warm_n : cold_n) += 1;
    frames.push_back(s);
  }
  // The day: one multi-reference fit over evenly spaced frames (every LUT row between the
  // lowest and highest sun, with the smoothness prior along sun zenith).
  const std::vector<int> day_idx = DaySubsample(static_cast<int>(plan.frames.size()), o.day_frames);
  const FitRequest day = DayFitRequest(o, plan, out_dir, day_idx);
  BatchLog("reduce: the day fit over " + std::to_string(day_idx.size()) + " of " + std::to_string(plan.frames.size()) +
                   " frames -> " + day.out_dir);
  const fit::FitResultFile day_summary = fit::FitResultFileFromJson(hooks.fit(day), day.out_dir + "/fit.json");
  // The keyframe tables: one key per frame, from each frame's own preset.
  exporter::ExportOptions ex;
  for (const BatchFrame& f : plan.frames) ex.presets.push_back((fs::path(FrameFitDir(out_dir, f.name)) / "preset.json").string());
  ex.out_dir = (fs::path(out_dir) / "tables").string();
  ex.backend = o.fit.backend;
  ex.report = false;  // part of the batch's report
  BatchLog("reduce: keyframe tables of " + std::to_string(ex.presets.size()) + " frames -> " + ex.out_dir);
  const nlohmann::json tables = exporter::ExportGameTables(ex);


  nlohmann::json day_refs = nlohmann::json::array();
  for (const fit::FitReferenceEntry& r : day_summary.references) {
    day_refs.push_back({{"name", r.name}, {"rel_rmse", r.rel_rmse}, {"log_rmse", r.log_rmse}});
  }
  nlohmann::json batch = {
      {"ok", true},
      {"out", out_dir},
      {"frames", frames},
      {"counts", {{"frames", plan.frames.size()}, {"chunks", plan.chunks.size()}, {"frames_per_job", o.frames_per_job}}},
      {"fit_time_s",
       {{"warm_started_frames", warm_n},
        {"warm_mean", warm_n ? warm_s / warm_n : 0.0},
        {"cold_started_frames", cold_n},
        {"cold_mean", cold_n ? cold_s / cold_n : 0.0},
        {"note", "each frame's fit time (fit.json time_s), seconds; warm = started from the previous frame's preset"}}},
      {"day", {{"dir", "day"}, {"frames", day_idx.size()}, {"haziness_g", day_summary.haziness_g},
               {"time_s", day_summary.time_s}, {"references", day_refs}}},
      {"tables", {{"dir", "tables"}, {"summary", tables}}},
      {"reduce_s", Seconds(t0, std::chrono::steady_clock::now())}};
  WriteJsonFileAtomically((fs::path(out_dir) / "batch.json").string(), batch);
  BatchLog("reduce: wrote " + (fs::path(out_dir) / "batch.json").string());
  // The day's HTML report (skycal report): every frame's fit (frames/<name>/, the day's
  // time-of-day plots), the day fit (day/) and the keyframe tables (tables/); written
  // through a temporary file like every report.
  WriteBatchReport(out_dir);
  return batch;
}

}  // namespace skycal::batch
