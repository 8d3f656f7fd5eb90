// Suite `fit-clouds-process`: the cloud lighting fit's whole process -- what the retired
// bench/fit_clouds.sh measured (bench/results/fit_clouds.txt), now a suite of `skycal bench`.
// One cloudy reference rendered from the bundled cloudy preset (sky + clouds, Vulkan, sun 30
// deg at azimuth 40 deg, 512x256; --quick: 128x64), then `skycal fit --reference R --clouds
// on --cloud-preset <the cloudy preset> --quiet --out DIR` run as a child process, relative
// (from the bundled clear preset) and absolute (--init <the cloudy preset> --absolute: the
// reference's own sky). Time: the process's wall time (median of repeats, 1 by default after
// the warm-up); `extra`: its CPU time (user + system, s, last run), fit.json's time_s and
// clouds.solve, the cloud and clear pixels' log RMSE. Error: fit.json's whole-sky rel RMSE.
// No Pareto plot: the absolute start needs the truth, it is not a user's speed setting.
#include <cmath>
#include <filesystem>

#include "skycal/bench/last_suite_grids.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/fit_result_file.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

FitCloudsProcessPlan FitCloudsProcessGridPlan(bool quick) {
  FitCloudsProcessPlan p;
  p.grid.axes = {{"start", {"relative", "absolute"}, "relative"}};
  if (quick) p.width = 128;
  return p;
}

namespace {

std::string Markdown(const std::vector<CaseResult>& cases) {
  std::string md =
      "# The cloud lighting fit's whole process\n\n"
      "`skycal bench --suite fit-clouds-process` (bench/src/fit_clouds_process_suite.cc; it replaced "
      "bench/fit_clouds.sh). `skycal fit --clouds on --cloud-preset datasets/presets/default_cloudy.json --quiet` as a "
      "child process on one cloudy reference rendered from that preset (Vulkan, sun 30 deg, azimuth 40 deg): relative "
      "from the bundled clear preset, absolute from the cloudy preset's own sky (`--init` it `--absolute`). Wall: the "
      "process, start-up and files included; CPU: user + system of the last run. Error: fit.json's whole-sky rel "
      "RMSE. Machine and date: results.json.\n\n" +
      CaseTable(cases, "whole-sky rel RMSE",
                {{"CPU s", [](const CaseResult& c) { return ExtraNumber(c, "cpu_s"); }},
                 {"fit.json time_s", [](const CaseResult& c) { return ExtraNumber(c, "fit_time_s"); }},
                 {"cloud log RMSE initial", [](const CaseResult& c) { return ExtraNumber(c, "cloud_log_rmse_initial"); }},
                 {"final", [](const CaseResult& c) { return ExtraNumber(c, "cloud_log_rmse_final"); }},
                 {"clear log RMSE", [](const CaseResult& c) { return ExtraNumber(c, "clear_log_rmse"); }},
                 {"cloud pixels", [](const CaseResult& c) { return ExtraNumber(c, "cloud_pixels"); }}});
  for (const CaseResult& c : cases)
    if (c.extra.contains("solve")) md += "\n" + c.name + ": clouds.solve " + c.extra["solve"].dump() + "\n";
  return md;
}

}  // namespace

Suite FitCloudsProcessSuite() {
  Suite s;
  s.name = "fit-clouds-process";
  s.summary = "skycal fit --clouds on as a whole process (wall and CPU time) on one cloudy 512x256 reference "
              "(--quick: 128x64) rendered from the bundled cloudy preset: relative and absolute start";
  s.error_metric = "fit.json's whole-sky rel RMSE against the cloudy reference";
  s.error_axis = "whole-sky rel RMSE";
  s.pareto = false;
  s.markdown = Markdown;
  s.run = [](const SuiteOptions& o) {
    const FitCloudsProcessPlan plan = FitCloudsProcessGridPlan(o.quick);
    const std::string cloudy = controllers::DefaultCloudyPresetPath();
    std::string reference;  // rendered by the first case (an error there is that case's clear error)
    return RunGrid("fit-clouds-process", plan.grid, o, [&](CaseResult& c) {
      const std::string exe = SelfExecutable("fit-clouds-process");
      if (reference.empty()) {
        controllers::GameRenderFileOptions ro;
        ro.render.preset_path = cloudy;
        ro.render.sun_dir = latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0);
        ro.render.width = plan.width;
        ro.render.height = plan.width / 2;
        ro.render.clouds.enabled = true;
        ro.out_exr = (o.scratch / "fit_clouds_process_cloudy.exr").string();
        ro.render.verbose = o.verb_logs;
        controllers::WriteGameRender(ro);
        reference = ro.out_exr;
      }
      const std::string start = Get(c.settings, "start");
      const std::string out = (o.scratch / ("fit_clouds_process_" + start)).string();
      std::vector<std::string> args = {exe, "fit", "--reference", reference, "--clouds", "on", "--cloud-preset", cloudy};
      if (start == "absolute") args.insert(args.end(), {"--init", cloudy, "--absolute"});
      args.insert(args.end(), {"--quiet", "--out", out});
      double cpu_s = 0.0;
      c.time = Measure(
          [&] {
            std::filesystem::remove_all(out);
            cpu_s = RunProcessCpuS("fit-clouds-process", args);
          },
          o.quick ? 0 : o.warmup, o.Repeats(1));
      const std::string fit_json = out + "/fit.json";
      const fit::FitResultFile j = fit::ReadFitResultFile(fit_json);
      if (j.clouds.is_null()) throw Error(fit_json + ": no 'clouds' section (expected with --clouds on)");
      const nlohmann::json& cl = j.clouds;
      c.error = j.references.at(0).rel_rmse;
      if (!std::isfinite(c.error)) {
        c.outcome = Outcome::kNonFinite;
        c.message = fit_json + ": non-finite rel_rmse";
      }
      c.extra = {{"cpu_s", cpu_s},
                 {"fit_time_s", j.time_s},
                 {"cloud_pixels", cl.at("cloud_pixels").at("count")},
                 {"cloud_log_rmse_initial", cl.at("cloud_pixels").at("initial").at("log_rmse")},
                 {"cloud_log_rmse_final", cl.at("cloud_pixels").at("final").at("log_rmse")},
                 {"clear_log_rmse", cl.at("clear_pixels").at("log_rmse")},
                 {"solve", cl.at("solve")}};
    });
  };
  return s;
}

}  // namespace skycal::bench
