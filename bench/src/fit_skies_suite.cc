// Suite `fit-skies`: the fit where users start (the bundled default preset, default
// options) over many skies the preset was not built from -- the study bench_fit ran, now a
// suite. Skies: CIE general skies 1, 3, 7, 12, 15 at sun 10, 30, 60 deg and the three other
// standard atmospheres' bakes at sun 2, 30, 70 deg, 512x256 (24 skies; --quick: CIE 3 and
// 12 and the three bakes at sun 30 deg, 128x64). Grid: path (the linear start: the
// default; the old coarse-to-fine Ceres path; `skycal fit` as a user runs it, one process
// per sky, outputs and report included) x backend x the Ceres polish, each away from the
// default alone. Time: all skies' fits, median of repeats; error: their mean rel RMSE
// against their references (noiseless: what the model class can reach is the ceiling).
// `extra`: median ms per sky, the fit / LUT-ceiling ratios (fit/include/skycal/fit/
// ceiling.h), how many skies end within 1.2x the ceiling + 0.1%, the linear start's stage
// medians, and the per-sky table.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/ceiling.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

extern char** environ;

namespace skycal::bench {
namespace {

struct Sky {
  std::string name, path;
  fit::Reference ref;
  double ceiling = 0.0;  // the LUT ceiling's rel RMSE
};

std::vector<Sky> WriteSkies(const SuiteOptions& o, int width, const render::Preset& start, const fit::FitOptions& fo) {
  std::vector<Sky> skies;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const std::string dir = o.scratch.string();
  const std::vector<int> cie = o.quick ? std::vector<int>{3, 12} : std::vector<int>{1, 3, 7, 12, 15};
  const std::vector<double> cie_el = o.quick ? std::vector<double>{30.0} : std::vector<double>{10.0, 30.0, 60.0};
  const std::vector<double> bake_el = o.quick ? std::vector<double>{30.0} : std::vector<double>{2.0, 30.0, 70.0};
  for (int t : cie)
    for (double el : cie_el) {
      const std::string name = "CIE " + std::to_string(t) + " sun " + FormatG(el);
      const std::string path = dir + "/skies_cie" + std::to_string(t) + "_" + FormatG(el) + ".exr";
      refsky::WriteCieReference(path, types.at(t - 1), latlong::DirectionFromElevationAzimuthDeg(el, 20.0), width);
      skies.push_back({name, path, {}, 0.0});
    }
  for (const auto& v : refsky::StandardAtmosphereVariants()) {
    const render::Preset truth = refsky::BakeVariant(v);
    for (double el : bake_el) {
      const std::string path = dir + "/skies_" + v.name + "_" + FormatG(el) + ".exr";
      refsky::WriteModelReference(path, truth, latlong::DirectionFromElevationAzimuthDeg(el, -50.0), width);
      skies.push_back({v.name + " sun " + FormatG(el), path, {}, 0.0});
    }
  }
  for (Sky& s : skies) {
    s.ref = fit::LoadReference(s.path, fo);
    s.ceiling = fit::ModelCeiling(s.ref, start, fo).lut_rel_rmse;
  }
  return skies;
}

// `exe fit --quiet --reference REF --out OUT` with its output discarded; throws skycal::Error
// unless it exits 0.
void RunFitProcess(const std::string& exe, const std::string& reference, const std::string& out) {
  std::filesystem::remove_all(out);
  RunProcessCpuS("fit-skies", {exe, "fit", "--quiet", "--reference", reference, "--out", out});
}

double MedianOf(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string FitSkiesMarkdown(const std::vector<CaseResult>& cases) {
  std::string md = "# skycal bench --suite fit-skies\n\nThe fit from the bundled default preset over skies it was not "
                   "built from (what bench_fit measured). Error: mean rel RMSE of the fits against their references "
                   "(a fraction); the LUT ceiling: what the model class can reach (fit/ceiling.h).\n\n";
  md += CaseTable(cases, "mean rel RMSE",
                  {{"ms per sky (median)", [](const CaseResult& c) { return ExtraNumber(c, "ms_per_sky_median_last_run"); }},
                   {"fit / ceiling (median)", [](const CaseResult& c) { return ExtraNumber(c, "fit_over_ceiling_median"); }},
                   {"within 1.2x ceiling + 0.1%", [](const CaseResult& c) { return ExtraNumber(c, "within_1.2x_ceiling_plus_0.1pct"); }}});
  for (const CaseResult& c : cases) {
    if (!c.is_default || !c.extra.contains("per_sky")) continue;
    md += "\n## The default, per sky\n\n| sky | ms (last run) | rel RMSE % | LUT ceiling % | g |\n|---|---|---|---|---|\n";
    for (const auto& r : c.extra["per_sky"])
      md += "| " + r.value("sky", std::string()) + " | " + FormatG(r.value("ms_last_run", 0.0), 4) + " | " +
            FormatG(100.0 * r.value("rel_rmse", 0.0), 4) + " | " + FormatG(100.0 * r.value("ceiling_lut", 0.0), 4) + " | " +
            FormatG(r.value("haziness_g", 0.0), 4) + " |\n";
    if (c.extra.contains("linear_start_stage_median_ms")) {
      const auto& st = c.extra["linear_start_stage_median_ms"];
      md += "\nLinear start stages (median ms): g search " + FormatG(st.value("g_search", 0.0)) + ", robust steps " +
            FormatG(st.value("robust_steps", 0.0)) + ", final level " + FormatG(st.value("final_level_steps", 0.0)) +
            ", render check " + FormatG(st.value("render_check", 0.0)) + ".\n";
    }
  }
  return md;
}

// What every case shares: the skies, the start preset, the base options, the renderers and
// the skycal binary (for path=process).
struct FitSkiesContext {
  const SuiteOptions& o;
  int width;
  const std::vector<Sky>& skies;
  const render::Preset& start;
  const fit::FitOptions& base;
  std::map<std::string, std::unique_ptr<render::SkyRenderer>>& renderers;
  const std::string& exe;
  bool exe_error;
};

// The case's errors against the ceilings: error, outcome and extra (per sky, the linear
// start's stage times) into c.
void SummariseSkies(CaseResult& c, const FitSkiesContext& x, const std::vector<double>& errors,
                    const std::vector<double>& sky_ms, const std::vector<fit::FitResult>& results, const std::string& path) {
  const std::vector<Sky>& skies = x.skies;
  double sum = 0.0;
  int within = 0;
  std::vector<double> ratios, search, robust, final_level, check;
  nlohmann::json per = nlohmann::json::array();
  bool finite = true;
  for (size_t i = 0; i < skies.size(); ++i) {
    finite = finite && std::isfinite(errors[i]);
    sum += errors[i];
    ratios.push_back(errors[i] / std::max(skies[i].ceiling, 1e-9));
    within += errors[i] <= 1.2 * skies[i].ceiling + 1e-3;
    nlohmann::json row = {{"sky", skies[i].name}, {"rel_rmse", errors[i]}, {"ceiling_lut", skies[i].ceiling},
                          {"ms_last_run", sky_ms[i]}};
    if (path != "process") {
      row["haziness_g"] = results[i].preset.haziness_g;
      if (const auto& ls = results[i].linear_start.single) {
        search.push_back(1e3 * ls->search_time_s);
        robust.push_back(1e3 * ls->robust_time_s);
        final_level.push_back(1e3 * ls->final_time_s);
        check.push_back(1e3 * (ls->render_check ? ls->render_check->time_s : 0.0));
      }
    }
    per.push_back(row);
  }
  c.error = sum / skies.size();
  c.converged = finite;
  if (!finite) {
    c.outcome = Outcome::kNonFinite;
    c.message = "a sky's fit error is non-finite";
  }
  c.extra = {{"skies", skies.size()},
             {"width", x.width},
             {"ms_per_sky_median_last_run", MedianOf(sky_ms)},
             {"fit_over_ceiling_median", MedianOf(ratios)},
             {"fit_over_ceiling_max", *std::max_element(ratios.begin(), ratios.end())},
             {"within_1.2x_ceiling_plus_0.1pct", within},
             {"per_sky", per}};
  if (!search.empty())
    c.extra["linear_start_stage_median_ms"] = {{"g_search", MedianOf(search)},
                                               {"robust_steps", MedianOf(robust)},
                                               {"final_level_steps", MedianOf(final_level)},
                                               {"render_check", MedianOf(check)}};
}

// One case: every sky fitted (in process, or by the skycal binary for path=process), timed.
void RunFitSkiesCase(CaseResult& c, const FitSkiesContext& x) {
  const SuiteOptions& o = x.o;
  const std::vector<Sky>& skies = x.skies;
  const std::string& path = Get(c.settings, "path");
  fit::FitOptions f = x.base;
  f.linear_start = path != "ceres";
  f.polish = Get(c.settings, "polish") == "on";
  f.backend = render::ParseBackend(Get(c.settings, "backend"), "backend");
  std::vector<double> errors(skies.size(), std::nan("")), sky_ms(skies.size(), 0.0);
  std::vector<fit::FitResult> results(skies.size());
  // The old path takes seconds per sky: one run, no warm-up.
  const bool slow = path == "ceres";
  const int repeats = slow ? 1 : o.Repeats(o.quick ? 1 : 3);
  c.time = Measure(
      [&] {
        for (size_t i = 0; i < skies.size(); ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          if (path == "process") {
            if (x.exe_error || x.exe.empty()) throw Error("fit-skies: path=process needs /proc/self/exe (the skycal binary)");
            RunFitProcess(x.exe, skies[i].path, (o.scratch / "skies_process_out").string());
            errors[i] = fit::ReadFitResultFile((o.scratch / "skies_process_out" / "fit.json").string()).references.at(0).rel_rmse;
          } else {
            results[i] = fit::FitSky({skies[i].ref}, x.start, f, *x.renderers.at(Get(c.settings, "backend")));
            errors[i] = results[i].references.at(0).errors.rel_rmse;
          }
          sky_ms[i] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        }
      },
      slow ? 0 : o.warmup, repeats);
  SummariseSkies(c, x, errors, sky_ms, results, path);
}

std::vector<CaseResult> RunFitSkies(const SuiteOptions& o) {
  const int width = o.quick ? 128 : 512;
  Grid grid;
  grid.axes = {{"path", {"linear-start", "ceres", "process"}, "linear-start"},
               {"backend", {"vulkan", "cpu"}, "vulkan"},
               {"polish", {"off", "on"}, "off"}};
  grid.skip = [](const Settings& st) -> std::string {
    const bool off_default = Get(st, "backend") != "vulkan" || Get(st, "polish") != "off";
    if (Get(st, "path") != "linear-start" && off_default) return "the old path and the process: with the defaults only";
    if (Get(st, "backend") == "cpu" && Get(st, "polish") == "on") return "one setting away from the default at a time";
    return "";
  };
  fit::FitOptions base;
  base.verbose = false;
  const render::Preset start = render::LoadPreset(DefaultPresetPath());
  const std::vector<Sky> skies = WriteSkies(o, width, start, base);
  o.Log("[fit-skies] " + std::to_string(skies.size()) + " skies at " + std::to_string(width) + "x" +
        std::to_string(width / 2) + ", ceilings computed");
  auto renderers = SkyRenderersByBackend();
  std::error_code ec;
  const std::string exe = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  const FitSkiesContext x{o, width, skies, start, base, renderers, exe, static_cast<bool>(ec)};
  return RunGrid("fit-skies", grid, o, [&](CaseResult& c) { RunFitSkiesCase(c, x); });
}

}  // namespace

Suite FitSkiesSuite() {
  Suite s;
  s.name = "fit-skies";
  s.summary = "the default fit over 24 skies the preset was not built from, 512x256: path (linear start, old Ceres, "
              "whole process) x backend x polish";
  s.error_metric = "mean rel RMSE of the fits against their references (noiseless CIE skies and other atmospheres)";
  s.error_axis = "mean rel RMSE over the skies";
  s.markdown = FitSkiesMarkdown;
  s.run = RunFitSkies;
  return s;
}

}  // namespace skycal::bench
