#include "fit_decisions.h"

#include <algorithm>
#include <cstdio>

namespace skycal::fit {
namespace {

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

const BenchDecisionCosts& MeasuredDecisionCosts() {
  // Measured by bench_fit --decisions (now `skycal bench --suite fit-decisions`, which
  // reproduces its error digits), 2026-11-24, this project's 2-core machine (shared,
  // loaded): medians over its 3 skies (bench/results/fit_decisions.md). Re-run the suite and
  // update these after changing the fit's stages.
  static const BenchDecisionCosts costs{
      /*polish=*/{1432.8, -3.117e-4, 196410},
      /*coarse_levels=*/{689.2, -5.73e-6, 196410},
      /*inseparable_overcast=*/{15.5, -6.5e-8, 196410},
  };
  return costs;
}

void AddPixelDecisions(const std::vector<Reference>& refs, int finest_width, double evaluation_s,
                       long long evaluated_samples, std::vector<FitDecision>* decisions) {
  long long below = 0, masked = 0, sun_cone = 0, invalid = 0, clipped = 0, user = 0;
  double scale = 0.0;  // finest-level pixels per reference pixel (area)
  for (const Reference& ref : refs) {
    below += ref.counts.below_horizon;
    sun_cone += ref.counts.sun_cone;
    invalid += ref.counts.invalid;
    clipped += ref.counts.clipped;
    user += ref.counts.user_masked;
    const double f = std::min(1.0, static_cast<double>(finest_width) / ref.radiance.width);
    scale = f * f;
  }
  masked = sun_cone + invalid + clipped + user;
  const double per_sample_ms = evaluated_samples > 0 ? 1e3 * evaluation_s / static_cast<double>(evaluated_samples) : 0.0;
  auto add = [&](long long pixels, std::string what, std::string why) {
    if (pixels <= 0) return;
    const double level_samples = 3.0 * static_cast<double>(pixels) * scale;
    FitDecision d;
    d.what = std::move(what);
    d.why = std::move(why);
    d.saved_ms = level_samples * per_sample_ms;
    d.saved_ms_basis = "estimated: " + Number(level_samples) + " samples (pixels x channels at the " +
                       std::to_string(finest_width) + "-wide level) x this run's measured evaluation time per fitted " +
                       "sample (" + Number(1e3 * evaluation_s) + " ms / " + std::to_string(evaluated_samples) + ")";
    decisions->push_back(std::move(d));
  };
  add(below, std::to_string(below) + " pixels below the horizon not evaluated",
      "ground, not sky: the model describes the sky above the horizon (rows below it have no residual block)");
  add(masked,
      std::to_string(masked) + " masked pixels not evaluated (sun cone " + std::to_string(sun_cone) + ", invalid " +
          std::to_string(invalid) + ", clipped " + std::to_string(clipped) + ", user mask " + std::to_string(user) + ")",
      "no trustworthy sky value to match (disc and flare, NaN/Inf/non-positive, sensor clamp, masked by the user); "
      "rows fully masked have no residual block");
}

FitDecision DecisionFromBench(std::string what, std::string why, const BenchDecisionCost& bench,
                              const std::string& bench_row, long long samples) {
  FitDecision d;
  d.what = std::move(what);
  d.why = std::move(why);
  const double ratio = bench.samples > 0 && samples > 0 ? static_cast<double>(samples) / bench.samples : 1.0;
  d.saved_ms = std::max(0.0, bench.saved_ms * ratio);
  d.saved_ms_basis = "estimated from the fit-decisions bench suite (bench/results/fit_decisions.md, row '" + bench_row +
                     "'): median " + Number(bench.saved_ms) + " ms at " + std::to_string(bench.samples) +
                     " samples, scaled by this fit's " + std::to_string(samples);
  d.rel_rmse_change = bench.rel_rmse_change;
  d.rel_rmse_change_basis = "estimated: the same benchmark's median";
  return d;
}

FitDecision SkippedLevelsFromThisRun(FitDecision from_bench, const std::vector<int>& skipped_widths, int finest_width,
                                     double finest_level_s) {
  double share = 0.0;
  for (int w : skipped_widths) {
    const double f = static_cast<double>(w) / finest_width;
    share += f * f;
  }
  FitDecision d = std::move(from_bench);
  const std::string bench_estimate = Number(d.saved_ms) + " ms";
  d.saved_ms = 1e3 * finest_level_s * share;
  d.saved_ms_basis = "estimated from this run: the finest level (" + std::to_string(finest_width) + " wide) took " +
                     Number(1e3 * finest_level_s) + " ms; the skipped levels hold " + Number(share) +
                     " of its samples (sum of (width / " + std::to_string(finest_width) +
                     ")^2), at equal iterations per level. Cross-check, the fit-decisions bench suite scaled to this fit: " +
                     bench_estimate;
  return d;
}

FitDecision NoCostDecision(std::string what, std::string why, std::string basis) {
  FitDecision d;
  d.what = std::move(what);
  d.why = std::move(why);
  d.saved_ms = 0.0;
  d.saved_ms_basis = std::move(basis);
  d.rel_rmse_change = 0.0;
  d.rel_rmse_change_basis = "exact: no fitted pixel reads what was left out";
  return d;
}

}  // namespace skycal::fit
