// The fit's skip decisions as fit.json `decisions`: what was not evaluated or not fitted,
// why, and what that saved (measured in this run, or estimated, with the basis named).
//
// Where the saving can be measured in the run, it is; where it cannot (the skipped work
// never ran), it is estimated either from this run's measured cost per evaluated sample
// or from the fit-decisions bench suite's measured cost of the decision switched off
// (bench/results/fit_decisions.md, through FitOptions' switches), scaled by this fit's sample count.
#pragma once
#include <string>
#include <vector>

#include "skycal/fit/fit_report.h"
#include "skycal/fit/reference.h"

namespace skycal::fit {

// What the fit-decisions bench suite measured for one decision switched off, median over its
// skies (one 512x256 reference, ffxv-iso, default preset).
struct BenchDecisionCost {
  double saved_ms = 0.0;         // fit time with the decision off minus with it on
  double rel_rmse_change = 0.0;  // rel RMSE with the skip minus without it (fraction)
  long long samples = 0;         // the final level's fitted samples (pixels x channels)
};
// Measured by `skycal bench --suite fit-decisions` (see bench/results/fit_decisions.md).
struct BenchDecisionCosts {
  BenchDecisionCost polish, coarse_levels, inseparable_overcast;
};
const BenchDecisionCosts& MeasuredDecisionCosts();

// Pixels of each reference that are not evaluated (below the horizon; masked: sun cone,
// invalid, clipped, user mask), at the finest fit level of `finest_width`: the time saved
// estimated from this run's measured evaluation time per fitted sample.
void AddPixelDecisions(const std::vector<Reference>& refs, int finest_width, double evaluation_s,
                       long long evaluated_samples, std::vector<FitDecision>* decisions);

// A decision whose saving is the fit-decisions suite's measurement, scaled by samples / bench samples.
FitDecision DecisionFromBench(std::string what, std::string why, const BenchDecisionCost& bench,
                              const std::string& bench_row, long long samples);

// Coarse pyramid levels not solved, when this run solved the finest level (the polish ran):
// saved = the finest level's measured time x sum over the skipped widths of (w / finest)^2
// (each level's share of the finest level's samples; Ceres' time per iteration scales with
// the samples, and the iterations are taken as equal per level). The bench estimate
// `from_bench` stays in the basis as the cross-check; what, why and the error change are
// kept from it.
FitDecision SkippedLevelsFromThisRun(FitDecision from_bench, const std::vector<int>& skipped_widths, int finest_width,
                                     double finest_level_s);

// A decision that saves nothing measurable (nothing would be evaluated), error unchanged.
FitDecision NoCostDecision(std::string what, std::string why, std::string basis);

}  // namespace skycal::fit
