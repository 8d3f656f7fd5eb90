// The fit's linear stage inside FitSky: builds the levels, runs the linear start
// (linear_start.h), checks that the selected backend renders what it predicts, and decides
// whether the Ceres polish still has work (probe samples, --polish, a failed render check).
// Writes its report into FitResult::linear_start and its decisions into `skipped`.
#pragma once
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "fit_state.h"
#include "linear_start.h"
#include "skycal/fit/sky_fit.h"
#include "unseen_profile.h"

namespace skycal::fit {

struct LinearStageOutcome {
  bool ran = false;
  double loss_scale = 0.0;                     // the global robust scale (log units)
  std::optional<RingLossScales> ring_scales;   // per ring around the sun, for the polish
  std::vector<RingLossScales> ring_scales_per_reference;  // several references: each one's
  std::vector<double*> held;                   // state parameters held at their floor
  std::set<std::pair<int, int>> observed_columns;  // (table, LUT column) some pixel reads
  double render_difference = 0.0;              // the render check's max relative difference
  bool render_agrees = false;
  bool polish = true;                          // the Ceres polish still runs
  // FitOptions::unseen_profile's terms on the state's parameters, for the polish.
  std::vector<UnseenProfileResidual> unseen_profile;
};

// One reference: the linear start on the tied rows, the render check, the polish decision.
// Several references (a day): the linear start of each reference on its own (tied rows,
// its own loss scales; two threads, no render check; the robust steps on every second
// pixel of every second row, the final steps on all), g searched by six references spread
// over the sun angles and held by the others at the median of theirs; combined into the
// day's start: every fitted LUT row takes the log change of the references around its sun
// angle, interpolated along the row coordinate. Then Gauss-Newton steps of the whole day
// (free rows, the log-space priors linearised, the exposures alternated) until a step no
// longer lowers the robust cost, and one render check of the joint solution.
LinearStageOutcome RunLinearStage(const std::vector<Reference>& refs, const FitOptions& o, bool tied,
                                  const std::vector<bool>& row_fitted, bool fit_overcast, bool probed,
                                  int finest_width, render::SkyRenderer& renderer, FitState* state,
                                  FitResult* result);

}  // namespace skycal::fit
