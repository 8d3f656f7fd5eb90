// The fit's start: variable projection over the model's linear structure (linear_sky.h),
// then a robust reweighting whose loss scales come from the residuals themselves.
//
// 1. Haziness g, on the search level (every k-th pixel of the robust level): a scan over
//    [0, 0.98] and golden sections in the best bracket; each g scored by the log error
//    after one Gauss-Newton step from the relative-error solve (two sparse linear solves
//    of the LUT and L_z). With several references the exposures are alternated.
// 2. Least squares of the log error on the robust level (Gauss-Newton steps, no weights),
//    then the loss scales (RingLossScales): sigma = 1.4826 x the weighted median of |e|
//    (the MAD, consistent for Gaussian errors, unaffected by up to half the pixels being
//    outliers), s = max(FitOptions::loss_scale, 2.385 sigma) globally and per ring around
//    the sun (2.385: the Cauchy loss's 95%-efficiency tuning constant, Holland & Welsch
//    1977). A clean sky's residuals are the model's own misfit, so the scale grows with it
//    where it lives and the loss never calls a whole region (the sun's surroundings) an
//    outlier; clouds or buildings over a minority of a ring keep its median small and lose
//    their pull.
// 3. Graduated non-convexity in log space: Gauss-Newton steps of the robust log objective
//    (each a weighted linear solve linearised at the current model, LinearSky::Solve),
//    weights rho'((e/s)^2) with the scales annealed 8x, 4x, 2x, 1x; the scales re-estimated
//    from the robust fit until they stop shrinking; then steps until the cost settles.
// 4. g refined under the robust log cost (golden sections in a narrow bracket that follows
//    a minimum on its edge; the scan's other local minima re-ranked), steps of 3 repeated.
// 5. On the final level: a relative least-squares solve (it places the LUT columns only
//    the finer pixels see), then Gauss-Newton steps at the final scales.
// The result is the optimum of the same objective as the Ceres sky rows (sky_row_cost.h),
// up to the regularisation: the Ceres polish is then needed only for what the linear
// structure does not hold (the probe's sun and ground, see linear_stage.h).
#pragma once
#include <string>
#include <vector>

#include "fit_state.h"
#include "linear_sky.h"
#include "skycal/fit/fit_options.h"
#include "skycal/fit/fit_report.h"

namespace skycal::fit {

// The robust loss's scale per ring of angular distance from the sun: the global scale
// (2.385 x the MAD-sigma of all residuals, at least FitOptions::loss_scale), widened in a
// ring to 2.385 x that ring's own MAD-sigma. The model's misfit is coherent around the sun
// (a whole ring off by 10-15% where one Mie lobe cannot form a CIE sky's aureole): a ring's
// median sees that misfit and keeps its pixels in the fit, while clouds or a building,
// which cover less than half of a ring, stay outliers within it.
struct RingLossScales {
  static constexpr int kRings = 7;
  static constexpr double kOuterEdgeDeg[kRings] = {6.0, 10.0, 15.0, 25.0, 40.0, 70.0, 180.0};
  double global = 0.05;
  double ring[kRings] = {};     // natural-log units, >= global
  double At(double sun_angle_deg) const;
};

struct LinearStartReport {
  double g = 0.0;
  double loss_scale = 0.0;       // the global scale s, natural-log units
  RingLossScales ring_scales;    // per ring around the sun (>= s)
  double residual_sigma = 0.0;   // 1.4826 MAD of the least-squares log residuals
  double rel_rmse_least_squares = 0.0;  // at the level it ran on
  double rel_rmse_robust = 0.0;
  double robust_cost = 0.0;      // 1/2 sum w s^2 rho((e/s)^2), log errors, final level
  int solves = 0;
  double search_time_s = 0.0;    // step 1 on the search level (g scan + golden sections)
  double robust_time_s = 0.0;    // steps 2-4 on the robust level
  double final_time_s = 0.0;     // step 5 on the final level
  int gauss_newton_steps = 0;
  std::vector<CostStep> cost_per_step;  // after each Gauss-Newton step (fit_report.h)
  int held_non_positive = 0;     // LUT entries the linear solve wanted <= 0 (held at a floor)
  std::vector<double> exposures; // model -> image factor per reference
  std::vector<double*> held;     // state parameters held at their floor (LinearSky::HeldParameters)
  LinearSkySolution solution;    // at the final level
};

// Global and per-ring scales from log residuals e (LinearSky::LogErrors layout), the global
// one at least `floor`; *sigma receives the global MAD-sigma.
RingLossScales EstimateRingScales(const LinearSky& sky, const std::vector<double>& e, double floor, double* sigma);

// Weighted median of |values| (weights > 0).
double WeightedMedianAbs(const std::vector<double>& values, const std::vector<double>& weights);

// Runs step 1 on `search` (a coarse level: g and the exposures), steps 2-4 on `robust` (a
// middle level) and Gauss-Newton steps of step 3 at the final g on `final` (the level the
// fit reports at, so every LUT column it sees is solved; may be the same object as
// `robust`), and writes the result into `state` (LUT, g, L_z, exposures). fit_g: search g
// (else held at state->g); fit_exposures: alternate exposures of the references after the
// first.
LinearStartReport RunLinearStart(const LinearSky& search, const LinearSky& robust, const LinearSky& final,
                                 FitState* state, const FitOptions& o, bool fit_g, bool fit_exposures);

// The model's ceiling on one reference: the least-squares optimum of relative error (what
// rel_rmse reports) over the LUT and L_z for each g, minimised over g. Used by the
// `skycal ceiling` verb and the tests.
struct CeilingReport {
  double g = 0.0;
  double rel_rmse = 0.0;
  int held_non_positive = 0;
};
CeilingReport MinimiseOverHaziness(const LinearSky& sky, const std::vector<double>& exposures, double g_hint);

}  // namespace skycal::fit
