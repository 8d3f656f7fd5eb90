// Suite `fit-decisions`: what each of the fit's skip decisions saves -- what the retired
// `bench_fit --decisions` measured (bench/results/fit_decisions.md), now a suite of `skycal
// bench`. Each decision is switched off through FitOptions (or the start) and the fit timed
// with it and without it, on three 512x256 skies the default preset was not built from: a
// CIE sky the model cannot reach (type 12, sun 30 deg; ceiling ~2%), a clear and a hazy
// bake of the standard atmosphere variants (sun 30 and 2 deg). Vulkan backend.
//
// Grid: FitDecisionsGridPlan (last_suite_grids.h), one case per fit configuration; a
// decision's on/off pair is two cases (DecisionSwitches), so a configuration two decisions
// share (the forced polish) is measured once. Time: the sum over the skies of each sky's
// median fit time (3 runs after a warm-up); error: the mean rel RMSE over the skies. `extra`:
// per sky its median ms, rel RMSE and the fit's samples; the markdown pairs the cases into
// the old table (saved ms = off - on; change = on - off, percentage points).
// --quick: 128x64 skies, one run each, no warm-up.
#include <filesystem>
#include <map>
#include <memory>

#include "skycal/bench/last_suite_grids.h"
#include "skycal/core/latlong.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "skycal/render/preset.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

FitDecisionsPlan FitDecisionsGridPlan(bool quick) {
  FitDecisionsPlan p;
  p.grid.axes = {{"variant", {"default", "polish", "polish+coarse-levels", "overcast0.2", "overcast0.2+lz-free"}, "default"}};
  if (quick) p.width = 128, p.runs = 1;
  return p;
}

const std::vector<DecisionSwitch>& DecisionSwitches() {
  static const std::vector<DecisionSwitch> s = {
      {"Ceres polish", "Ceres polish skipped after the linear start (off: --polish)", "default", "polish"},
      // Measured with the polish running in both, so its own cost is not counted twice: off
      // runs the coarse pyramid levels (64, 128, 256 wide) before the finest.
      {"coarse levels", "coarse pyramid levels skipped after the linear start (both with --polish)", "polish",
       "polish+coarse-levels"},
      {"overcast held (ffxv-iso)", "L_z held in ffxv-iso (overcast_weight 0.2 start)", "overcast0.2",
       "overcast0.2+lz-free"},
  };
  return s;
}

namespace {

struct Sky {
  std::string name;
  fit::Reference ref;
};

// The three skies, written as EXR into `dir` and loaded as the fit loads them.
std::vector<Sky> MakeSkies(const std::filesystem::path& dir, int width) {
  fit::FitOptions o;
  o.verbose = false;
  std::vector<Sky> skies;
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  const std::string cie = (dir / "decisions_cie12_30.exr").string();
  refsky::WriteCieReference(cie, types[11], latlong::DirectionFromElevationAzimuthDeg(30.0, 20.0), width);
  skies.push_back({"CIE 12 sun 30", fit::LoadReference(cie, o)});
  const auto variants = refsky::StandardAtmosphereVariants();
  for (const auto& [k, el] : {std::pair<size_t, double>{0, 30.0}, {1, 2.0}}) {
    const std::string path = (dir / ("decisions_" + variants[k].name + ".exr")).string();
    refsky::WriteModelReference(path, refsky::BakeVariant(variants[k]),
                                latlong::DirectionFromElevationAzimuthDeg(el, -50.0), width);
    skies.push_back({variants[k].name + " sun " + std::to_string(static_cast<int>(el)), fit::LoadReference(path, o)});
  }
  return skies;
}

// The options and start of a variant.
fit::FitOptions VariantOptions(const std::string& v) {
  fit::FitOptions o;
  o.verbose = false;
  if (v == "polish" || v == "polish+coarse-levels") o.polish = true;
  if (v == "polish+coarse-levels") o.skip_coarse_levels = false;
  if (v == "overcast0.2+lz-free") o.hold_inseparable_overcast = false;
  return o;
}

double SkyNumber(const CaseResult& c, size_t k, const char* key) { return c.extra["skies"][k][key].get<double>(); }

std::string Markdown(const std::vector<CaseResult>& cases) {
  std::map<std::string, const CaseResult*> by_variant;
  for (const CaseResult& c : cases)
    if (c.outcome == Outcome::kOk && c.extra.contains("skies")) by_variant[Get(c.settings, "variant")] = &c;
  std::string md =
      "# Skip decisions of the fit\n\n"
      "`skycal bench --suite fit-decisions` (bench/src/fit_decisions_suite.cc; it replaced `bench_fit --decisions`). "
      "Each decision switched off through FitOptions on 3 skies the bundled default preset was not built from "
      "(Vulkan backend, each sky's median of its timed runs after a warm-up). saved ms = fit time with the decision "
      "off minus on; rel RMSE change = with the skip minus without (percentage points; negative: the skip lowered "
      "the error). The machine and date are in results.json.\n\n" +
      CaseTable(cases, "mean rel RMSE", {}) +
      "\n| decision | sky | on ms | off ms | saved ms | rel RMSE on % | off % | change (pp) |\n"
      "|---|---|---|---|---|---|---|---|\n";
  std::string summary =
      "\n| decision | median saved ms | median rel RMSE change (pp) | basis |\n|---|---|---|---|\n";
  for (const DecisionSwitch& s : DecisionSwitches()) {
    if (!by_variant.count(s.on) || !by_variant.count(s.off)) continue;
    const CaseResult &on = *by_variant[s.on], &off = *by_variant[s.off];
    std::vector<double> saved, change;
    for (size_t k = 0; k < on.extra["skies"].size(); ++k) {
      const double on_ms = SkyNumber(on, k, "ms"), off_ms = SkyNumber(off, k, "ms");
      const double on_e = SkyNumber(on, k, "rel_rmse"), off_e = SkyNumber(off, k, "rel_rmse");
      saved.push_back(off_ms - on_ms);
      change.push_back(on_e - off_e);
      md += "| " + s.what + " | " + on.extra["skies"][k]["sky"].get<std::string>() + " | " + FormatG(on_ms, 4) + " | " +
            FormatG(off_ms, 4) + " | " + FormatG(off_ms - on_ms, 4) + " | " + FormatG(100 * on_e, 4) + " | " +
            FormatG(100 * off_e, 4) + " | " + FormatG(100 * (on_e - off_e), 4) + " |\n";
    }
    summary += "| " + s.row + " | " + FormatG(FromSamples(saved).median_ms, 4) + " | " +
               FormatG(100 * FromSamples(change).median_ms, 4) + " | measured (switched off) |\n";
  }
  md += summary;
  if (by_variant.count("default")) {
    const CaseResult& d = *by_variant["default"];
    md += "| pixels below the horizon not evaluated | " + FormatG(d.extra["below_horizon_saved_ms_median"].get<double>(), 4) +
          " | 0 (not in the error measure) | estimated in fit.json: the skipped samples x the run's measured time per "
          "evaluated sample (not switchable: the ground has no sky value to match) |\n"
          "| unobserved LUT rows / columns held | 0 | 0 | none: no pixel reads them (not switchable) |\n"
          "| probe blocks only where samples exist | 0 | 0 | none: nothing to evaluate without samples |\n"
          "\nMedian fitted samples (pixels x channels) of the final level: " +
          FormatG(d.extra["samples_median"].get<double>(), 4) +
          " (the scale fit.json's estimates use, fit/src/fit_decisions.cc).\n";
  }
  return md;
}

}  // namespace

Suite FitDecisionsSuite() {
  Suite s;
  s.name = "fit-decisions";
  s.summary = "what each of the fit's skip decisions saves: the fit with each switched off (polish forced, coarse "
              "levels run, L_z freed) on 3 skies of 512x256 (--quick: 128x64), Vulkan";
  s.error_metric = "mean rel RMSE over the 3 skies (CIE 12, clear, hazy) vs the reference";
  s.error_axis = "mean rel RMSE over 3 skies";
  s.markdown = Markdown;
  s.run = [](const SuiteOptions& o) {
    const FitDecisionsPlan plan = FitDecisionsGridPlan(o.quick);
    auto renderer = render::CreateRenderer(render::Backend::kVulkan);
    const render::Preset start = render::LoadPreset(DefaultPresetPath());
    render::Preset overcast_start = start;  // the overcast decision needs a term to hold
    overcast_start.overcast_weight = 0.2;
    std::vector<Sky> skies;  // made by the first case (an error there is that case's clear error)
    return RunGrid("fit-decisions", plan.grid, o, [&](CaseResult& c) {
      if (skies.empty()) skies = MakeSkies(o.scratch, plan.width);
      const std::string variant = Get(c.settings, "variant");
      const fit::FitOptions fo = VariantOptions(variant);
      const render::Preset& st = variant.rfind("overcast", 0) == 0 ? overcast_start : start;
      const int warmup = o.quick ? 0 : o.warmup, runs = o.Repeats(plan.runs);
      nlohmann::json rows = nlohmann::json::array();
      std::vector<double> samples, below, sky_ms;
      double error_sum = 0.0, min_sum = 0.0, max_sum = 0.0;
      for (const Sky& sky : skies) {
        fit::FitResult r;
        const Timing t = Measure([&] { r = fit::FitSky({sky.ref}, st, fo, *renderer); }, warmup, runs);
        const double e = r.references.at(0).errors.rel_rmse;
        error_sum += e;
        sky_ms.push_back(t.median_ms);
        min_sum += t.min_ms;
        max_sum += t.max_ms;
        samples.push_back(static_cast<double>(r.linear_start.samples()));
        for (const fit::FitDecision& d : r.decisions)
          if (d.what.find("below the horizon") != std::string::npos) below.push_back(d.saved_ms);
        rows.push_back({{"sky", sky.name}, {"ms", t.median_ms}, {"rel_rmse", e},
                        {"samples", r.linear_start.samples()}});
        o.Log("[bench fit-decisions] " + variant + ", " + sky.name + ": " + FormatG(t.median_ms, 4) + " ms, rel RMSE " +
              FormatG(e, 4));
      }
      double sum = 0.0;
      for (double v : sky_ms) sum += v;
      c.time = Timing{sum, min_sum, max_sum, runs};
      c.error = error_sum / skies.size();
      c.extra = {{"skies", rows},
                 {"samples_median", FromSamples(samples).median_ms},
                 {"below_horizon_saved_ms_median", FromSamples(below).median_ms}};
    });
  };
  return s;
}

}  // namespace skycal::bench
