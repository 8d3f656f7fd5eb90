// The fit's start: variable projection over the model's linear structure (linear_sky.h),
// then a robust reweighting whose loss scale comes from the residuals themselves.
//
// 1. Haziness g: a scan over [0, 0.98] and a golden-section refinement of the best
//    bracket; each g costs one sparse linear least-squares solve of the LUT (and L_z).
//    With several references the exposures are alternated with the LUT solve.
// 2. Robust scale: from the least-squares residuals e (log units), sigma = 1.4826 x the
//    weighted median of |e| (the MAD, consistent for Gaussian errors, unaffected by up to
//    half the pixels being outliers), and the loss scale
//        s = max(FitOptions::loss_scale, 2.385 sigma)
//    (2.385: the Cauchy loss's 95%-efficiency tuning constant, Holland & Welsch 1977). A
//    clean sky's residuals are the model's own misfit, so the scale grows with it and the
//    loss never calls a whole region (the sun's surroundings) an outlier; a sky with a
//    few per cent of clouds or buildings keeps the median small and those pixels lose
//    their pull.
// 3. Graduated non-convexity in log space: Gauss-Newton steps of the robust log objective
//    (each a weighted linear solve linearised at the current model, LinearSky::Solve),
//    the weights rho'((e/s)^2) with the scale annealed 8s, 4s, 2s, then s until the cost
//    settles, starting from the least-squares solution, which has not given up any region.
// 4. g refined under the robust log cost (golden sections in a narrow bracket), and the
//    steps of 3 repeated at the new g.
// The result is the optimum of the same objective as the Ceres sky rows (sky_row_cost.h),
// up to the priors' linearisation: the Ceres polish is then needed only for what the
// linear structure does not hold (the probe's sun and ground, see sky_fit.cc).
#pragma once
#include <string>
#include <vector>

#include "fit_state.h"
#include "linear_sky.h"
#include "skycal/fit/fit_options.h"

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
