// Suite `batch`: `skycal batch` on a synthetic time-lapse day -- what the retired
// bench/batch_day.sh measured (bench/results/batch.md), now a suite of `skycal bench`. The
// day: BatchGridPlan's frames, the sun of 70 deg N at the June solstice (midnight sun:
// elevation 3.4 ... 43.4 deg), rendered (cpu, controllers::WriteGameRender) from the default preset with
// haziness g 0.6 instead of 0.8 and 15% CIE overcast, fitted from the default preset. Each
// case is one `skycal batch` process (--backend cpu --quiet --poll 0.2) into its own
// directory. Time: the process's wall time (one run: a day takes tens of seconds); error:
// the frames' mean rel RMSE (batch.json). `extra`: batch.json's run wall, frames/s, reduce
// time, chunks, and per set of frames (all, warm-started, first of a chunk) their count, mean
// fit s, iterations and rel RMSE. The slurm case needs root and slurm-wlm + munge (it starts
// the cluster with tests/slurm_cluster.sh for its one run); elsewhere it ends as a clear
// error "skipped: why". --quick: 8 frames, 4 per job.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "skycal/bench/last_suite_grids.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

BatchPlan BatchGridPlan(bool quick) {
  BatchPlan p;
  p.grid.axes = {{"run", {"warm", "cold", "warm-ceres", "cold-ceres", "slurm"}, "warm"}};
  if (quick) p.frames = 8, p.frames_per_job = 4;
  return p;
}

void BatchDaySun(double hour, double* elevation_deg, double* azimuth_deg) {
  constexpr double kDeg = M_PI / 180.0;
  const double lat = 70.0 * kDeg, dec = 23.44 * kDeg, ha = 15.0 * (hour - 12.0) * kDeg;  // hour angle
  *elevation_deg = std::asin(std::sin(lat) * std::sin(dec) + std::cos(lat) * std::cos(dec) * std::cos(ha)) / kDeg;
  *azimuth_deg = std::atan2(-std::sin(ha) * std::cos(dec),
                            std::cos(lat) * std::sin(dec) - std::sin(lat) * std::cos(dec) * std::cos(ha)) / kDeg;
}

namespace {

std::string Root() { return SKYCAL_SOURCE_DIR; }

// The day's frames in dir/day, from the perturbed preset written into dir/preset.
void WriteDay(const std::filesystem::path& dir, const BatchPlan& plan, bool verbose) {
  namespace fs = std::filesystem;
  fs::create_directories(dir / "preset");
  fs::create_directories(dir / "day");
  for (const auto& e : fs::directory_iterator(Root() + "/datasets/presets"))
    if (e.path().filename().string().rfind("default_clear.", 0) == 0)
      fs::copy_file(e.path(), dir / "preset" / e.path().filename(), fs::copy_options::overwrite_existing);
  const std::string preset = (dir / "preset" / "default_clear.json").string();
  nlohmann::json p = ReadJsonFile(preset);
  p.at("parameters").at("haziness_g")["value"] = 0.6;
  p.at("parameters").at("overcast_weight")["value"] = 0.15;
  std::ofstream(preset) << p.dump(1);
  for (int i = 0; i < plan.frames; ++i) {
    controllers::GameRenderFileOptions ro;
    ro.render.preset_path = preset;
    ro.render.backend = render::Backend::kCpu;
    ro.render.width = plan.width;
    ro.render.height = plan.width / 2;
    const double h = 24.0 * i / plan.frames;
    double el = 0.0, az = 0.0;
    BatchDaySun(h, &el, &az);
    // Rounded to 1e-4 deg as bench/batch_day.sh's sun path file was: the same frames, so the
    // same fits (the Ceres path's iterations moved with the last digits).
    ro.render.sun_dir = latlong::DirectionFromElevationAzimuthDeg(std::round(el * 1e4) / 1e4, std::round(az * 1e4) / 1e4);
    ro.time_of_day_h = h;
    char name[32];
    std::snprintf(name, sizeof name, "frame%03d.exr", i);
    ro.out_exr = (dir / "day" / name).string();
    ro.render.verbose = verbose;
    controllers::WriteGameRender(ro);
  }
}

nlohmann::json Stats(const nlohmann::json& frames, int which) {  // which: 0 all, 1 warm-started, 2 first of a chunk
  double fit = 0, it = 0, err = 0, worst = 0;
  int n = 0;
  for (const auto& f : frames) {
    const bool warm = !f["warm_start_from"].is_null();
    if ((which == 1 && !warm) || (which == 2 && warm)) continue;
    ++n;
    fit += f["fit_time_s"].get<double>();
    it += f["iterations"].get<double>();
    err += f["rel_rmse"].get<double>();
    worst = std::max(worst, f["rel_rmse"].get<double>());
  }
  if (n == 0) return {{"frames", 0}};
  return {{"frames", n}, {"fit_s_mean", fit / n}, {"iterations_mean", it / n}, {"rel_rmse_mean", err / n},
          {"rel_rmse_max", worst}};
}

std::string Pct(const nlohmann::json& j, const char* key) {
  return j.contains(key) ? FormatFixed(100 * j[key].get<double>(), 4) + "%" : "-";
}
std::string Fix(const nlohmann::json& j, const char* key, int d) {
  return j.contains(key) ? FormatFixed(j[key].get<double>(), d) : "-";
}

std::string Markdown(const std::vector<CaseResult>& cases) {
  std::string md =
      "# skycal batch: a synthetic day (70 deg N June solstice sun, perturbed preset)\n\n"
      "`skycal bench --suite batch` (bench/src/batch_suite.cc; it replaced bench/batch_day.sh); fit backend cpu. "
      "Times are wall-clock on the machine in results.json (compare within one run).\n\n" +
      CaseTable(cases, "rel RMSE mean", {}) +
      "\n| run | wall s | frames/s (incl. reduce) | reduce s | fit s/frame (mean) | iterations (mean) | rel RMSE mean | "
      "rel RMSE max |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  std::string warm = "\nWarm-started frames only (the chunks' first frames start cold in every run):\n\n"
                     "| run | frames | fit s/frame | iterations | rel RMSE mean |\n| --- | ---: | ---: | ---: | ---: |\n";
  std::string notes;
  for (const CaseResult& c : cases) {
    const std::string run = Get(c.settings, "run");
    if (c.outcome != Outcome::kOk || !c.extra.contains("all")) {
      notes += "\n" + run + ": " + c.message + "\n";
      continue;
    }
    const nlohmann::json &e = c.extra, &a = e["all"], &w = e["warm_frames"];
    md += "| " + run + " | " + Fix(e, "wall_s", 1) + " | " + Fix(e, "frames_per_s", 2) + " | " + Fix(e, "reduce_s", 1) +
          " | " + Fix(a, "fit_s_mean", 3) + " | " + Fix(a, "iterations_mean", 1) + " | " + Pct(a, "rel_rmse_mean") +
          " | " + Pct(a, "rel_rmse_max") + " |\n";
    if (w["frames"].get<int>() > 0)
      warm += "| " + run + " | " + std::to_string(w["frames"].get<int>()) + " | " + Fix(w, "fit_s_mean", 3) + " | " +
              Fix(w, "iterations_mean", 1) + " | " + Pct(w, "rel_rmse_mean") + " |\n";
  }
  std::map<std::string, const CaseResult*> by;
  for (const CaseResult& c : cases)
    if (c.outcome == Outcome::kOk && c.extra.contains("all")) by[Get(c.settings, "run")] = &c;
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"warm", "cold"}, {"warm-ceres", "cold-ceres"}}) {
    if (!by.count(a) || !by.count(b)) continue;
    const nlohmann::json &x = by[a]->extra, &y = by[b]->extra;
    const double fa = x["all"]["fit_s_mean"].get<double>(), fb = y["all"]["fit_s_mean"].get<double>();
    notes += "\n" + a + " vs " + b + ": fit time per frame " + FormatFixed(fa, 3) + " s vs " + FormatFixed(fb, 3) + " s (" +
             FormatFixed(std::abs(100 * (1 - fa / fb)), 0) + "% " + (fa < fb ? "less" : "more") + "), wall " +
             Fix(x, "wall_s", 1) + " s vs " + Fix(y, "wall_s", 1) + " s, rel RMSE mean " + Pct(x["all"], "rel_rmse_mean") +
             " vs " + Pct(y["all"], "rel_rmse_mean") + ".\n";
  }
  if (by.count("slurm") && by.count("warm")) {
    const nlohmann::json &sl = by["slurm"]->extra, &w = by["warm"]->extra;
    const int jobs = sl["chunks"].get<int>() + 1;  // the array tasks + the reduce
    const double over = (sl["wall_s"].get<double>() - w["wall_s"].get<double>()) / jobs;
    notes += "\nSlurm (single node, same chunks): batch wall " + Fix(sl, "wall_s", 1) + " s vs local " + Fix(w, "wall_s", 1) +
             " s over " + std::to_string(jobs) + " jobs (" + std::to_string(jobs - 1) + " array tasks + the reduce): overhead " +
             FormatFixed(over, 2) + " s per job (submission, scheduling, squeue polling every 0.2 s, task start). The "
             "case's own time also counts starting the cluster.\n";
  }
  return md + warm + notes;
}

}  // namespace

Suite BatchSuite() {
  Suite s;
  s.name = "batch";
  s.summary = "skycal batch on a synthetic 96-frame 128x64 day (--quick: 8 frames): warm/cold starts, linear start "
              "on/off, the Slurm engine (root only)";
  s.error_metric = "mean rel RMSE over the day's frames (batch.json)";
  s.error_axis = "mean rel RMSE over the frames";
  s.markdown = Markdown;
  s.run = [](const SuiteOptions& o) {
    const BatchPlan plan = BatchGridPlan(o.quick);
    bool day_written = false;
    return RunGrid("batch", plan.grid, o, [&](CaseResult& c) {
      const std::string exe = SelfExecutable("batch");
      if (!day_written) {
        o.Log("[bench batch] rendering " + std::to_string(plan.frames) + " frames");
        WriteDay(o.scratch / "batch", plan, o.verb_logs);
        day_written = true;
      }
      const std::string run = Get(c.settings, "run");
      const std::string out = (o.scratch / "batch" / ("run_" + run)).string();
      std::filesystem::remove_all(out);
      std::vector<std::string> args = {exe, "batch", "--references", (o.scratch / "batch" / "day" / "*.exr").string(),
                                       "--out", out, "--engine", run == "slurm" ? "slurm" : "local",
                                       "--jobs", std::to_string(plan.jobs), "--frames-per-job",
                                       std::to_string(plan.frames_per_job), "--backend", "cpu", "--quiet", "--poll", "0.2",
                                       // the fit per frame (what bench/results/batch.md measures), not calibrate's
                                       "--frame-job", "fit"};
      if (run.rfind("cold", 0) == 0) args.push_back("--cold-start");
      if (run.find("ceres") != std::string::npos) args.push_back("--no-linear-start");
      if (run == "slurm") {
        // One shell holds the cluster for the batch's run: tests/slurm_cluster.sh starts it
        // (SLURM_CONF exported to the batch) and stops every daemon it started on exit.
        std::string cmd;
        for (const std::string& a : args) cmd += " '" + a + "'";
        const std::string tmp = (o.scratch / "batch" / "slurm_cluster").string();
        const std::string why = (o.scratch / "batch" / "slurm_why.txt").string();
        std::filesystem::create_directories(tmp);
        const std::string script = "cd '" + Root() + "' && source tests/slurm_cluster.sh && if ! slurm_cluster_check > '" +
                                   why + "'; then exit 77; fi; trap slurm_cluster_stop EXIT; slurm_cluster_start '" + tmp +
                                   "' && " + cmd.substr(1);
        args = {"/bin/bash", "-c", script};
        try {
          c.time = Measure([&] { RunProcessCpuS("batch", args); }, 0, 1);
        } catch (const Error&) {
          std::ifstream in(why);
          std::string reason;
          std::getline(in, reason);
          if (!reason.empty()) throw Error("skipped: " + reason);
          throw;
        }
      } else {
        c.time = Measure([&] { RunProcessCpuS("batch", args); }, 0, 1);
      }
      const nlohmann::json b = ReadJsonFile(out + "/batch.json");
      const nlohmann::json& frames = b.at("frames");
      double wall_sum = 0;
      for (const auto& f : frames) wall_sum += f.at("wall_s").get<double>();
      c.extra = {{"wall_s", b.at("run").at("wall_s")},
                 {"frames_per_s", b.at("run").at("frames_per_s")},
                 {"reduce_s", b.at("reduce_s")},
                 {"chunks", b.at("counts").at("chunks")},
                 {"all", Stats(frames, 0)},
                 {"warm_frames", Stats(frames, 1)},
                 {"first_of_chunk", Stats(frames, 2)},
                 {"frame_wall_s_mean", frames.empty() ? 0.0 : wall_sum / frames.size()}};
      c.error = c.extra["all"].value("rel_rmse_mean", std::nan(""));
      if (!std::isfinite(c.error)) {
        c.outcome = Outcome::kNonFinite;
        c.message = out + "/batch.json: non-finite or no frames' rel RMSE";
      }
    });
  };
  return s;
}

}  // namespace skycal::bench
