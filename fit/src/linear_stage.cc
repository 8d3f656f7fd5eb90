#include "linear_stage.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

#include "linear_sky.h"
#include "pyramid.h"
#include "robust_residual.h"
#include "skycal/core/error.h"

namespace skycal::fit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// The render check's threshold: the backends' parity bound (2e-5,
// tests/render_parity_test.cc) plus the LUT's float storage.
constexpr double kRenderCheckThreshold = 5e-5;
// The g search decimates the robust level only when that leaves at least this many samples
// (pixels x channels): 3,000 is ~1/16 of a clear 256x128 sky's.
constexpr int kMinDecimatedSamples = 3000;
// Gauss-Newton steps of the day's joint solve (from the combined per-reference start).
constexpr int kDayGaussNewtonSteps = 4;
constexpr double kDaySettled = 0.05;  // a step gaining less than 5% of the cost is the last
// The day's per-reference starts run their g search and robust steps on every
// kDayStartStride-th pixel of every kDayStartStride-th row of the finest level (the search
// on every second of those), then the final steps on every pixel (they place the columns
// only the rows nearest the horizon see). Decimated, not area-averaged: an averaged
// coarser level differs from the model at its nodes near the sun's peak. Measured on
// bench_fit --day: averaged 128-wide starts began the joint steps at 150x the cost and
// ended at 10% worst rel RMSE; decimated without the final steps at 100x, 1.1%; with
// them the same start and result as every pixel throughout (0.114%) at 0.6x the CPU time.
constexpr int kDayStartStride = 2;
// References of a day that search g in their starts (the rest hold the median of theirs).
constexpr size_t kDayGSearchReferences = 6;

std::vector<RingScaleReport> RingScaleReports(const RingLossScales& r) {
  std::vector<RingScaleReport> out;
  double inner = 0.0;
  for (int k = 0; k < RingLossScales::kRings; ++k) {
    out.push_back({inner, RingLossScales::kOuterEdgeDeg[k], r.ring[k]});
    inner = RingLossScales::kOuterEdgeDeg[k];
  }
  return out;
}

RenderCheckReport MakeRenderCheckReport(const render::SkyRenderer& renderer, double difference, double seconds) {
  return {renderer.Describe(), difference, kRenderCheckThreshold, seconds};
}

// Whether the Ceres polish still runs after the linear stage, and why (in `skipped`, or a
// warning when the render check failed). `converged` says what made the polish needless.
void DecidePolish(const FitOptions& o, bool probed, const std::string& converged, LinearStageOutcome* out,
                  FitResult* result) {
  out->render_agrees = out->render_difference <= kRenderCheckThreshold;
  out->polish = o.polish || probed || !out->render_agrees;
  if (!out->polish) {
    result->skipped.push_back({"Ceres polish (all pyramid levels)",
                               converged + " and the " + std::string(render::ToString(o.backend)) +
                                   " render reproduces its values (render_check)"});
  } else if (!out->render_agrees) {
    result->warnings.push_back("the render check failed (max relative difference " +
                               std::to_string(out->render_difference) + "): the Ceres polish runs through the backend");
  }
}

// LUT row coordinate of a sun direction (fractional), as lut_row of the shared source.
double SunRowPosition(const render::LutGrid& grid, const std::array<double, 3>& sun) {
  return render::LutRowPosition(grid, sun[1]);
}

// The render check: the backend draws the state at the level size of each reference and
// must reproduce the linear structure's values of `sol`.
double RenderCheck(const LinearSky& sky, const LinearSkySolution& sol, const std::vector<double>& exposures,
                   const std::vector<Reference>& refs, const std::vector<const FitLevel*>& levels,
                   const FitState& state, render::SkyRenderer& renderer) {
  const render::Preset candidate = state.ToPreset();
  std::vector<ImageRGB> images;
  for (size_t r = 0; r < refs.size(); ++r) {
    render::RenderRequest req;
    req.sun_dir = refs[r].sun_dir;
    req.width = levels[r]->width;
    req.height = levels[r]->height;
    req.sun_disc = false;
    req.ground = render::GroundMode::kZero;
    images.push_back(renderer.Render(candidate, req));
  }
  return sky.MaxRelativeDifference(sol, exposures, images);
}

LinearStageOutcome RunLinearStageSingle(const std::vector<Reference>& refs, const FitOptions& o, bool tied,
                                        const std::vector<bool>& row_fitted, bool fit_overcast, bool probed,
                                        int finest_width, int decimate, render::SkyRenderer* renderer,
                                        FitState* state, FitResult* result);

// The day's per-reference starts (tied rows, each reference on its own): their states,
// outcomes and reports, the references ordered by sun row position, and the day's g.
struct DayStarts {
  std::vector<FitState> singles;
  std::vector<LinearStageOutcome> outcomes;
  std::vector<FitResult> reports;
  std::vector<std::pair<double, size_t>> order;  // (sun row position, reference), ascending
  double day_g = 0.0;
};

// Reference r's start: a one-reference state from the day's preset at g, tied to the two
// LUT rows around its sun.
void RunDayStart(const std::vector<Reference>& refs, size_t r, const FitOptions& options, bool fit_overcast,
                 int finest_width, double g, const FitState& state, FitState* start, LinearStageOutcome* outcome,
                 FitResult* report) {
  const auto& grid = state.preset.luts.grid;
  FitState& st = *start;
  st = FitState::FromPreset(state.preset, state.preset.variant, 1);
  st.initial_log_lut = state.initial_log_lut;
  st.log_lut = state.initial_log_lut;
  st.g = g;
  const int r0 = SunLutRow0(grid, refs[r].sun_dir[1]);
  st.tied_rows = {r0, r0 + 1};
  const std::vector<bool> rows = SunLutRows(grid, refs[r].sun_dir[1]);
  // No render check of its own (the day's joint solution is checked), decimated
  // (kDayStartStride): this start only seeds the joint steps.
  *outcome = RunLinearStageSingle({refs[r]}, options, true, rows, fit_overcast, false, finest_width, kDayStartStride,
                                  nullptr, &st, report);
}

DayStarts RunDayStarts(const std::vector<Reference>& refs, const FitOptions& o, bool fit_overcast, int finest_width,
                       const FitState& state) {
  const auto& grid = state.preset.luts.grid;
  const size_t n = refs.size();
  DayStarts s;
  s.singles.resize(n);
  s.outcomes.resize(n);
  s.reports.resize(n);
  std::vector<std::string> errors(n);
  FitOptions single_options = o;
  single_options.verbose = false;
  single_options.polish = true;
  single_options.linear_threads = 1;  // the references themselves run two at a time
  // g is shared by the day: searched only by kDayGSearchReferences references spread over
  // the sun angles (the first phase), the others start at their median (held).
  for (size_t r = 0; r < n; ++r) s.order.emplace_back(SunRowPosition(grid, refs[r].sun_dir), r);
  std::sort(s.order.begin(), s.order.end());
  std::vector<size_t> searching, holding;
  {
    const size_t k = std::min(n, kDayGSearchReferences);
    std::vector<bool> picked(n, false);
    for (size_t i = 0; i < k; ++i) picked[s.order[std::min(n - 1, (2 * i + 1) * n / (2 * k))].second] = true;
    for (size_t r = 0; r < n; ++r) (picked[r] ? searching : holding).push_back(r);
  }
  FitOptions holding_options = single_options;
  holding_options.fit_haziness = false;
  s.day_g = state.g;
  auto run = [&](size_t r) {
    try {
      const bool search_g = o.fit_haziness && std::find(searching.begin(), searching.end(), r) != searching.end();
      RunDayStart(refs, r, search_g ? single_options : holding_options, fit_overcast, finest_width, s.day_g, state,
                  &s.singles[r], &s.outcomes[r], &s.reports[r]);
    } catch (const std::exception& e) {
      errors[r] = refs[r].name + ": " + e.what();
    }
  };
  // Two workers per phase.
  auto run_all = [&](const std::vector<size_t>& which) {
    std::atomic<size_t> next{0};
    auto worker = [&] {
      for (size_t i = next++; i < which.size(); i = next++) run(which[i]);
    };
    std::thread second(worker);
    worker();
    second.join();
    for (const std::string& e : errors) {
      if (!e.empty()) throw Error("fit: linear start of " + e);
    }
  };
  run_all(searching);
  if (o.fit_haziness) {
    std::vector<double> searched;
    for (size_t r : searching) searched.push_back(s.singles[r].g);
    std::nth_element(searched.begin(), searched.begin() + searched.size() / 2, searched.end());
    s.day_g = searched[searched.size() / 2];
  }
  run_all(holding);
  return s;
}

// Combine: log change per (table, column, channel) at each reference's row position.
void CombineDayStarts(const DayStarts& s, const std::vector<bool>& row_fitted, FitState* state) {
  const auto& grid = state->preset.luts.grid;
  const auto& order = s.order;
  const auto& singles = s.singles;
  for (int t = 0; t < state->tables; ++t)
    for (int col = 0; col < grid.n_gamma; ++col)
      for (int ch = 0; ch < 3; ++ch) {
        const size_t d = state->DeltaIndex(t, col, ch);
        for (int row = 0; row < grid.n_theta; ++row) {
          if (!row_fitted[row]) continue;
          double change = 0.0;
          if (row <= order.front().first) {
            change = singles[order.front().second].log_delta[d];
          } else if (row >= order.back().first) {
            change = singles[order.back().second].log_delta[d];
          } else {
            size_t k = 0;
            while (k + 1 < order.size() && order[k + 1].first < row) ++k;
            const double a = order[k].first, b = order[k + 1].first;
            const double w = b > a ? (row - a) / (b - a) : 0.0;
            change = (1.0 - w) * singles[order[k].second].log_delta[d] + w * singles[order[k + 1].second].log_delta[d];
          }
          const size_t i = state->Index(t, row, col, ch);
          state->log_lut[i] = state->initial_log_lut[i] + change;
        }
      }
}

// The day's joint Gauss-Newton steps: the solution, exposures and robust cost per step.
struct DayJoint {
  LinearSkySolution sol;
  std::vector<double> exposures;
  std::vector<double> costs;
};

// Steps from the state (the combined start) until one no longer lowers the robust cost;
// writes the result into the state (LUT, L_z, exposures of the n references).
DayJoint RunDayJoint(const LinearSky& day, const FitOptions& o, const std::vector<RingLossScales>& ring_scales,
                     size_t n, FitState* state) {
  DayJoint j;
  for (double le : state->log_exposure) j.exposures.push_back(std::exp(le));
  j.sol = day.FromState(*state);
  std::vector<double> scales(day.num_samples());
  for (size_t i = 0; i < scales.size(); ++i) {
    scales[i] = ring_scales[day.SampleReference(i)].At(day.sun_angles_deg()[i]);
  }
  std::vector<double> e = day.LogErrors(j.sol, j.exposures);  // of the current solution
  double cost = day.RobustCostOf(e, o.loss, scales);
  j.costs.push_back(cost);
  for (int step = 0; step < kDayGaussNewtonSteps; ++step) {
    std::vector<double> weights(e.size(), 1.0);
    for (size_t i = 0; i < e.size() && o.loss != RobustLoss::kNone; ++i) {
      double rho = 0.0, drho = 1.0;
      RobustRho(o.loss, (e[i] / scales[i]) * (e[i] / scales[i]), &rho, &drho);
      weights[i] = drho;
    }
    LinearSkySolution next = day.Solve(state->g, j.exposures, weights, &j.sol);
    std::vector<double> next_exposures = j.exposures;
    if (!o.absolute) {
      const std::vector<double> best = day.BestExposures(next, weights);
      for (size_t r = 1; r < n; ++r) next_exposures[r] *= best[r];
    }
    std::vector<double> next_e = day.LogErrors(next, next_exposures);
    const double next_cost = day.RobustCostOf(next_e, o.loss, scales);
    j.costs.push_back(next_cost);
    // A step is kept only when it lowers the robust cost (the exposures' alternation and
    // the linearised priors can overshoot); the first step that does not ends the loop.
    if (!(next_cost < cost)) break;
    const bool settled = cost - next_cost < kDaySettled * cost;
    j.sol = std::move(next);
    j.exposures = std::move(next_exposures);
    e = std::move(next_e);
    cost = next_cost;
    if (settled) break;
  }
  day.Apply(j.sol, state);
  for (size_t r = 0; r < n; ++r) state->log_exposure[r] = std::log(j.exposures[r]);
  return j;
}

LinearStageOutcome RunLinearStageDay(const std::vector<Reference>& refs, const FitOptions& o,
                                     const std::vector<bool>& row_fitted, bool fit_overcast, bool probed,
                                     int finest_width, render::SkyRenderer& renderer, FitState* state,
                                     FitResult* result) {
  const auto t0 = Clock::now();
  const size_t n = refs.size();
  const DayStarts starts = RunDayStarts(refs, o, fit_overcast, finest_width, *state);
  CombineDayStarts(starts, row_fitted, state);
  LinearStageOutcome out;
  out.ran = true;
  for (size_t r = 0; r < n; ++r) {
    out.ring_scales_per_reference.push_back(starts.outcomes[r].ring_scales.value_or(RingLossScales{}));
    out.loss_scale = std::max(out.loss_scale, starts.outcomes[r].loss_scale);
    for (const auto& tc : starts.outcomes[r].observed_columns) out.observed_columns.insert(tc);
  }
  state->g = starts.day_g;
  if (fit_overcast) {
    double sum = 0.0;
    for (const FitState& st : starts.singles) sum += st.log_overcast_zenith;
    state->log_overcast_zenith = sum / static_cast<double>(n);
  }
  const double per_reference_time = Seconds(t0, Clock::now());

  // The day jointly: Gauss-Newton steps of the robust log objective over every fitted LUT
  // row (free rows, log-space smoothness and pull linearised at the current point), from
  // the combined start, each reference's pixels under its own ring scales, the exposures
  // alternated (unless --absolute; the first reference's holds the gauge), g at the median.
  const auto t_joint = Clock::now();
  std::vector<FitLevel> levels;
  std::vector<const FitLevel*> level_ptrs;
  for (const Reference& ref : refs) levels.push_back(BuildLevel(ref, finest_width));
  for (const FitLevel& lv : levels) level_ptrs.push_back(&lv);
  LinearSkyOptions lo;
  lo.unknowns = LinearUnknowns::kFreeRows;
  lo.row_fitted = row_fitted;
  lo.fit_overcast = fit_overcast;
  lo.smoothness = o.smoothness;
  lo.prior_weight = o.prior_weight;
  lo.unseen_profile = o.unseen_profile;
  const LinearSky day(*state, level_ptrs, refs, lo);
  const DayJoint joint = RunDayJoint(day, o, out.ring_scales_per_reference, n, state);
  const double joint_time = Seconds(t_joint, Clock::now());
  const auto t_check = Clock::now();
  out.render_difference = RenderCheck(day, joint.sol, joint.exposures, refs, level_ptrs, *state, renderer);
  const double check_time = Seconds(t_check, Clock::now());
  out.observed_columns.clear();
  for (const auto& tc : day.ObservedColumns()) out.observed_columns.insert(tc);
  out.unseen_profile = day.UnseenProfileResiduals(state);

  LinearStartDayReport report;
  report.mode = "each reference on its own (tied rows), combined along the LUT rows, then Gauss-Newton steps of the "
                "whole day (free rows)";
  report.haziness_g = state->g;
  report.loss_scale = out.loss_scale;
  report.per_reference_time_s = per_reference_time;
  report.joint_unknowns = day.num_unknowns();
  report.joint_samples = static_cast<long long>(day.num_samples());
  report.joint_robust_cost_per_step = joint.costs;
  report.joint_time_s = joint_time;
  report.render_check = MakeRenderCheckReport(renderer, out.render_difference, check_time);
  for (size_t r = 0; r < n; ++r) {
    report.references.emplace_back(refs[r].name,
                                   starts.reports[r].linear_start.single.value_or(LinearStartSingleReport{}));
  }
  report.time_s = Seconds(t0, Clock::now());
  result->linear_start.day = std::move(report);
  DecidePolish(o, probed, "the day's joint Gauss-Newton steps minimised the robust log objective", &out, result);
  if (o.verbose) {
    std::cerr << "[fit] linear start of " << n << " references: median g " << state->g << ", "
              << Seconds(t0, Clock::now()) << " s" << std::endl;
  }
  return out;
}

// The linear sky problems of one reference's start: the search level (g and the
// exposures), the robust level and the final level (which may be the robust one), and
// the strides the search and robust problems take on the robust level.
struct SingleSkies {
  std::vector<std::unique_ptr<LinearSky>> skies;  // front: robust; back: final
  std::unique_ptr<LinearSky> search;
  int robust_stride = 1;
  int search_stride = 1;
};

SingleSkies BuildSingleSkies(const std::vector<Reference>& refs, const LinearSkyOptions& lo,
                             const std::vector<std::vector<const FitLevel*>>& level_ptrs, int decimate,
                             int robust_width, int linear_width, const FitState& state) {
  // A sparse reference (a mask leaving a few rows) keeps every pixel: the decimation
  // could drop whole rows, or all of them.
  size_t valid_samples = 0;  // pixels x channels of the robust level
  for (const FitLevel* lv : level_ptrs.front())
    for (double w : lv->weight) valid_samples += w > 0.0 ? 3 : 0;
  // A decimation by k keeps it only when at least kMinDecimatedSamples remain.
  auto keeps_enough = [&](int k) { return valid_samples >= static_cast<size_t>(kMinDecimatedSamples) * k * k; };
  SingleSkies s;
  LinearSkyOptions robust_options = lo;
  robust_options.stride = decimate > 1 && keeps_enough(decimate) ? decimate : 1;
  // The finest level first: the coarser ones smooth the azimuths it leaves unseen.
  std::unique_ptr<LinearSky> finest;
  if (level_ptrs.size() > 1 || robust_options.stride > 1) finest = std::make_unique<LinearSky>(state, level_ptrs.back(), refs, lo);
  if (finest) robust_options.column_sectors = finest->column_sectors();
  s.skies.push_back(std::make_unique<LinearSky>(state, level_ptrs.front(), refs, robust_options));
  if (finest) s.skies.push_back(std::move(finest));
  LinearSkyOptions search_options = lo;
  search_options.column_sectors = s.skies.back()->column_sectors();
  const int search_stride = decimate > 1 ? 2 * robust_options.stride : std::max(1, robust_width / linear_width);
  search_options.stride = keeps_enough(search_stride) ? search_stride : robust_options.stride;
  s.search = std::make_unique<LinearSky>(state, level_ptrs.front(), refs, search_options);
  s.robust_stride = robust_options.stride;
  s.search_stride = search_options.stride;
  return s;
}

// The start's report (without the render check) from RunLinearStart's.
LinearStartSingleReport MakeSingleReport(const LinearStartReport& rep, const FitOptions& o, const SingleSkies& skies,
                                         int robust_width, int final_width, double linear_time) {
  const LinearSky& sky = *skies.skies.back();
  LinearStartSingleReport report;
  report.search_width = robust_width / skies.search_stride;
  report.robust_width = robust_width / skies.robust_stride;
  report.width = final_width;
  report.unknowns = sky.num_unknowns();
  report.samples = static_cast<long long>(sky.num_samples());
  report.solves = rep.solves;
  report.gauss_newton_steps = rep.gauss_newton_steps;
  report.cost_per_step = rep.cost_per_step;
  report.search_time_s = rep.search_time_s;
  report.robust_time_s = rep.robust_time_s;
  report.final_time_s = rep.final_time_s;
  report.haziness_g = rep.g;
  report.rel_rmse_least_squares = rep.rel_rmse_least_squares;
  report.rel_rmse_robust = rep.rel_rmse_robust;
  report.residual_sigma_log = rep.residual_sigma;
  report.loss_scale = rep.loss_scale;
  report.loss_scale_floor = o.loss_scale;
  report.loss_scale_by_sun_distance = RingScaleReports(rep.ring_scales);
  report.held_non_positive = rep.held_non_positive;
  report.partly_seen_columns = sky.partly_seen_columns();
  report.unseen_profile_terms = sky.unseen_profile_terms();
  report.time_s = linear_time;
  return report;
}

// One reference; without a renderer no render check and no polish decision (a day's
// per-reference start).
LinearStageOutcome RunLinearStageSingle(const std::vector<Reference>& refs, const FitOptions& o, bool tied,
                                        const std::vector<bool>& row_fitted, bool fit_overcast, bool probed,
                                        int finest_width, int decimate, render::SkyRenderer* renderer,
                                        FitState* state, FitResult* result) {
  LinearStageOutcome out;
  const auto t_linear = Clock::now();
  const int linear_width = std::min(o.linear_width, finest_width);
  // Two levels: the robust steps (twice the search width) and the final Gauss-Newton
  // steps (the finest pyramid width); the g search runs on every k-th pixel of the
  // robust level (LinearSkyOptions::stride), so it is linear_width wide. Decimated (a
  // day's start): one level, the finest, its every `decimate`-th pixel for the robust
  // steps and every 2 x decimate-th for the search, every pixel for the final steps.
  const int robust_width = decimate > 1 ? finest_width : std::min(2 * linear_width, finest_width);
  std::vector<std::vector<FitLevel>> linear_levels;
  std::vector<std::vector<const FitLevel*>> level_ptrs;
  for (int w : {robust_width, finest_width}) {
    if (!linear_levels.empty() && linear_levels.back()[0].width == w) continue;
    linear_levels.emplace_back();
    for (const Reference& ref : refs) linear_levels.back().push_back(BuildLevel(ref, w));
  }
  for (const auto& lvs : linear_levels) {
    level_ptrs.emplace_back();
    for (const FitLevel& lv : lvs) level_ptrs.back().push_back(&lv);
  }
  const std::vector<const FitLevel*>& final_ptrs = level_ptrs.back();
  LinearSkyOptions lo;
  lo.unknowns = tied ? LinearUnknowns::kTiedRows : LinearUnknowns::kFreeRows;
  lo.row_fitted = row_fitted;
  lo.fit_overcast = fit_overcast;
  lo.smoothness = o.smoothness;
  lo.prior_weight = o.prior_weight;
  lo.unseen_profile = o.unseen_profile;
  lo.threads = o.linear_threads;
  const SingleSkies skies = BuildSingleSkies(refs, lo, level_ptrs, decimate, robust_width, linear_width, *state);
  const LinearSky& sky = *skies.skies.back();
  const LinearSky& robust = *skies.skies.front();
  const LinearStartReport rep =
      RunLinearStart(*skies.search, robust, sky, state, o, o.fit_haziness, !o.absolute && refs.size() > 1);
  out.ran = true;
  out.loss_scale = rep.loss_scale;
  out.ring_scales = rep.ring_scales;
  out.held = rep.held;
  if (!out.held.empty()) {
    result->skipped.push_back({std::to_string(out.held.size()) + " LUT parameters",
                               "the linear least-squares solve wants them <= 0 (a table the sky does not "
                               "need there): held at 1e-6 of their start, not polished in log space"});
  }
  const double linear_time = Seconds(t_linear, Clock::now());
  LinearStartSingleReport report = MakeSingleReport(rep, o, skies, robust_width, final_ptrs[0]->width, linear_time);
  if (o.verbose) {
    std::cerr << "[fit] linear start at " << linear_width << " wide: g " << rep.g << ", rel RMSE "
              << rep.rel_rmse_least_squares << " (least squares) -> " << rep.rel_rmse_robust << " (robust, scale "
              << rep.loss_scale << "), " << rep.solves << " solves, " << linear_time << " s" << std::endl;
  }
  // The render check: the selected backend draws the linear solution at the final level,
  // and must reproduce the linear structure's values (threshold: the backends' parity
  // bound, tests/render_parity_test.cc, 2e-5, plus float LUT storage: 5e-5).
  if (renderer) {
    const auto t_check = Clock::now();
    out.render_difference = RenderCheck(sky, rep.solution, rep.exposures, refs, final_ptrs, *state, *renderer);
    report.render_check = MakeRenderCheckReport(*renderer, out.render_difference, Seconds(t_check, Clock::now()));
  }
  result->linear_start.single = std::move(report);
  for (const auto& tc : sky.ObservedColumns()) out.observed_columns.insert(tc);
  // A day's per-reference start (no renderer) only seeds the joint steps: the polish reads the
  // day's own terms.
  if (renderer) out.unseen_profile = sky.UnseenProfileResiduals(state);
  if (renderer) DecidePolish(o, probed, "the linear start converged on the robust log objective itself", &out, result);
  return out;
}

}  // namespace

LinearStageOutcome RunLinearStage(const std::vector<Reference>& refs, const FitOptions& o, bool tied,
                                  const std::vector<bool>& row_fitted, bool fit_overcast, bool probed,
                                  int finest_width, render::SkyRenderer& renderer, FitState* state,
                                  FitResult* result) {
  if (refs.size() > 1) {
    return RunLinearStageDay(refs, o, row_fitted, fit_overcast, probed, finest_width, renderer, state, result);
  }
  return RunLinearStageSingle(refs, o, tied, row_fitted, fit_overcast, probed, finest_width, 1, &renderer, state,
                              result);
}

}  // namespace skycal::fit
