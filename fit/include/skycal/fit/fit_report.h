// What a sky fit reports beside the preset: typed, so the fit never builds JSON; the cli's
// fit verb serialises it into fit.json (skycal/fit/fit_result_file.h). Compared member by
// member (operator==: exact, the round-trip tests of fit.json use it).
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace skycal::fit {

// A parameter block or pass the fit left out, and why (fit.json `skipped`).
struct SkipNote {
  std::string block, reason;
  bool operator==(const SkipNote&) const = default;
};

// A decision of what not to evaluate or fit, with what it saved (fit.json `decisions`).
// saved_ms is measured in this run or estimated; saved_ms_basis says which and from what
// ("measured: ...", "estimated from ...", "none: ..."). rel_rmse_change: the reference
// rel RMSE with the skip minus without it (fraction; negative: the skip lowered the
// error), when known, with its basis.
struct FitDecision {
  std::string what, why;
  double saved_ms = 0.0;
  std::string saved_ms_basis;
  std::optional<double> rel_rmse_change;
  std::string rel_rmse_change_basis;
  bool operator==(const FitDecision&) const = default;
};

// A LUT row no reference's sun angle constrains (held at the initial preset).
struct UnobservedRow {
  int row = 0;
  double sun_zenith_deg = 0.0;
  std::string reason;
  bool operator==(const UnobservedRow&) const = default;
};

// One Ceres pyramid level (fit.json `levels`).
struct LevelReport {
  int width = 0, height = 0;
  long long residuals = 0;
  int parameters = 0;
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;
  std::vector<double> cost_per_iteration;  // Ceres' cost at iteration 0 (the start), 1, ...
  std::string termination;
  int renders = 0;                       // backend renders at new evaluation points
  int probe_final_solve_iterations = 0;  // the sun / ground refit after the finest level
  double time_s = 0.0;
  double render_wall_ms = 0.0;           // the renders' wall time, summed
  std::optional<double> render_gpu_ms;   // their device time (timestamps); none: CPU or no timestamps
  bool operator==(const LevelReport&) const = default;
};

// The render check of the linear stage: the backend must reproduce the linear values.
struct RenderCheckReport {
  std::string backend;
  double max_relative_difference = 0.0;
  double threshold = 0.0;
  double time_s = 0.0;
  bool operator==(const RenderCheckReport&) const = default;
};

// The robust log cost after one Gauss-Newton step of the linear start (the convergence
// curve of fit.json's linear_start.cost_per_step): the level width it ran on, and the cost
// 1/2 sum w s^2 rho((e/s)^2) with that step's loss scales (they narrow between rounds, so
// the curve can step up where a scale changed).
struct CostStep {
  int width = 0;
  double cost = 0.0;
  bool operator==(const CostStep&) const = default;
};

// The robust loss scale of one ring of angular distance from the sun (log units).
struct RingScaleReport {
  double from_deg = 0.0, to_deg = 0.0, scale = 0.0;
  bool operator==(const RingScaleReport&) const = default;
};

// The linear start of one reference (fit/src/linear_start.h).
struct LinearStartSingleReport {
  int search_width = 0, robust_width = 0, width = 0;
  int unknowns = 0;
  long long samples = 0;
  int solves = 0, gauss_newton_steps = 0;
  double search_time_s = 0.0, robust_time_s = 0.0, final_time_s = 0.0;
  double haziness_g = 0.0;
  double rel_rmse_least_squares = 0.0, rel_rmse_robust = 0.0;
  double residual_sigma_log = 0.0, loss_scale = 0.0, loss_scale_floor = 0.0;
  std::vector<RingScaleReport> loss_scale_by_sun_distance;
  int held_non_positive = 0;
  // LUT columns some fitted pixel reads at some azimuths but not all round, and the terms
  // of FitOptions::unseen_profile that draw them there (0 with the prior off).
  int partly_seen_columns = 0, unseen_profile_terms = 0;
  std::vector<CostStep> cost_per_step;
  double time_s = 0.0;
  std::optional<RenderCheckReport> render_check;
  bool operator==(const LinearStartSingleReport&) const = default;
};

// A day's linear start: each reference on its own, combined, then joint steps.
struct LinearStartDayReport {
  std::string mode;
  double haziness_g = 0.0, loss_scale = 0.0;
  double per_reference_time_s = 0.0;
  int joint_unknowns = 0;
  long long joint_samples = 0;
  std::vector<double> joint_robust_cost_per_step;
  double joint_time_s = 0.0;
  RenderCheckReport render_check;
  std::vector<std::pair<std::string, LinearStartSingleReport>> references;  // name, report
  double time_s = 0.0;
  bool operator==(const LinearStartDayReport&) const = default;
};

// Exactly one of the two when the linear start ran; neither with --no-linear-start.
struct LinearStartReportOut {
  std::optional<LinearStartSingleReport> single;
  std::optional<LinearStartDayReport> day;
  bool ran() const { return single.has_value() || day.has_value(); }
  double time_s() const { return single ? single->time_s : day ? day->time_s : 0.0; }
  double loss_scale() const { return single ? single->loss_scale : day ? day->loss_scale : 0.0; }
  long long samples() const { return single ? single->samples : day ? day->joint_samples : 0; }
  bool operator==(const LinearStartReportOut&) const = default;
};

// With probe samples (fit.json `probe`).
struct ProbeReport {
  int references = 0;
  double weight = 0.0;
  int quadrature_width = 0;
  long long residuals = 0;
  int dropped_samples = 0;
  double evaluation_time_s = 0.0;
  bool ground_albedo_fitted = false;
  double ground_albedo_value = 0.0, ground_albedo_initial = 0.0;
  std::string ground_albedo_reason;  // empty when fitted
  bool operator==(const ProbeReport&) const = default;
};

}  // namespace skycal::fit
