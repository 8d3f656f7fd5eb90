#include "skycal/fit/sky_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <set>

#include "fit_decisions.h"
#include "fit_finish.h"
#include "fit_state.h"
#include "fit_term.h"
#include "level_solve.h"
#include "linear_stage.h"
#include "probe_terms.h"
#include "pyramid.h"
#include "sky_fit_terms.h"
#include "sky_terms.h"
#include "unseen_profile_term.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::fit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// In ffxv-iso the overcast term is folded into the isotropic table: L_z held at this
// fraction of the start's (the table, non-negative, can add the term's shape but not
// subtract it). Measured (bench/results/fit_decisions.md, first version of the decision):
// L_z held at the start's 4000 cd/m^2 with weight 0.2 left 25%, 285% and 327% rel RMSE on
// three skies dimmer than that term somewhere, against 0.002-2% with L_z fitted.
constexpr double kFoldedOvercastFraction = 1e-6;

// Which blocks the scene does not need (fit.json `skipped`); returns whether L_z is fitted.
// The overcast term only where the sky asks for it: absent when its weight is 0, and
// folded into the isotropic table in ffxv-iso, where that table spans its shape (a
// function of the view elevation only) and L_z is not separable from it
// (tests/linear_sky_test.cc).
bool PlanSharedBlocks(const FitState& state, const FitOptions& o, FitResult* result) {
  if (state.tables == 2) result->skipped.push_back({"isotropic LUT", "model ffxv has no isotropic term"});
  const bool has_overcast = state.preset.overcast_weight > 0.0;
  const bool inseparable = state.tables == 3 && o.hold_inseparable_overcast;
  const bool fit_overcast = o.fit_overcast && has_overcast && !inseparable;
  if (!fit_overcast) {
    result->skipped.push_back(
        {"overcast_zenith_luminance",
         !has_overcast ? "overcast_weight is 0 in the initial preset: the term is absent (its weight is not separable "
                         "from the LUT scale, so the fit never changes it)"
         : !o.fit_overcast ? "disabled by option"
                           : "model ffxv-iso: the overcast shape depends on the view elevation only, which the "
                             "isotropic table spans, so L_z is not separable from it: folded into that table (L_z "
                             "held at 1e-6 of the initial preset's)"});
  }
  if (o.absolute) result->skipped.push_back({"exposure", "FitOptions::absolute: references are calibrated"});
  if (!o.fit_haziness) result->skipped.push_back({"haziness_g", "disabled by option"});
  return fit_overcast;
}

// LUT rows each reference constrains (its sun position between two rows); with several
// references the rows between the observed ones are fitted too (held by the smoothness
// prior); rows outside the observed range are not parameters at all.
std::vector<bool> PlanRows(const std::vector<Reference>& refs, FitState* state, FitResult* result) {
  const render::LutGrid& grid = state->preset.luts.grid;
  std::set<int> observed;
  for (const Reference& ref : refs) {
    const double pos = render::LutRowPosition(grid, ref.sun_dir[1]);
    const int r0 = SunLutRow0(grid, ref.sun_dir[1]);
    ReferenceFit rf;
    rf.observed_rows.push_back(r0);
    if (pos - r0 > 0.0) rf.observed_rows.push_back(r0 + 1);
    for (int row : rf.observed_rows) observed.insert(row);
    result->references.push_back(rf);
  }
  const int first_row = *observed.begin(), last_row = *observed.rbegin();
  std::vector<bool> row_fitted(grid.n_theta, false);
  for (int row = first_row; row <= last_row; ++row) row_fitted[row] = refs.size() > 1 || observed.count(row);
  // One reference sees only a blend of the two rows around its sun angle: tie them.
  if (refs.size() == 1) state->tied_rows.assign(observed.begin(), observed.end());
  for (int row = 0; row < grid.n_theta; ++row) {
    if (row_fitted[row]) continue;
    result->unobserved_rows.push_back({row, render::LutRowSunZenithRad(grid, row) * 180.0 / M_PI,
                                       "no reference has its sun near this row: held at the initial preset"});
  }
  if (!result->unobserved_rows.empty()) {
    result->skipped.push_back({"LUT rows without observations",
                               std::to_string(result->unobserved_rows.size()) + " of " + std::to_string(grid.n_theta) +
                                   " rows: no reference sun angle near them (see unobserved_rows)"});
  }
  return row_fitted;
}

// What the fit's choices saved (fit.json `decisions`), once the stages have run.
struct DecisionFacts {
  int finest_width = 0;
  std::vector<int> coarse_widths_skipped;  // pyramid levels the linear start made needless
  bool polish_skipped = false;
  bool overcast_held_inseparable = false;  // ffxv-iso with an overcast weight
  bool overcast_absent = false;
  int extrapolated_columns = 0;
  long long samples = 0;                   // the finest level's fitted samples
  double evaluation_s = 0.0;               // measured: the linear stage and the Ceres levels
  double polish_level_s = 0.0;             // measured: the finest Ceres level, when it ran
  int polish_level_width = 0;
};

void RecordDecisions(const std::vector<Reference>& refs, const DecisionFacts& f, FitResult* result) {
  std::vector<FitDecision>& d = result->decisions;
  AddPixelDecisions(refs, f.finest_width, f.evaluation_s, f.samples, &d);
  const BenchDecisionCosts& bench = MeasuredDecisionCosts();
  if (!f.coarse_widths_skipped.empty()) {
    std::string widths;
    for (int w : f.coarse_widths_skipped) widths += (widths.empty() ? "" : ", ") + std::to_string(w);
    const std::string what = "coarse pyramid levels (" + widths + " wide) not solved";
    const std::string why = "the linear start already placed the LUT and g at the optimum of the linear structure "
                            "(the model's ceiling in the fit's error measure)";
    FitDecision from_bench = DecisionFromBench(what, why, bench.coarse_levels, "coarse levels", f.samples);
    // The finest level ran in this run (the polish): the skipped levels from its measured time.
    d.push_back(f.polish_level_s > 0.0 ? SkippedLevelsFromThisRun(std::move(from_bench), f.coarse_widths_skipped,
                                                                  f.polish_level_width, f.polish_level_s)
                                       : std::move(from_bench));
  }
  if (f.polish_skipped) {
    d.push_back(DecisionFromBench("Ceres polish skipped",
                                  "the linear start converged on the robust log objective itself and the backend's "
                                  "render reproduces its values (linear_start.render_check)",
                                  bench.polish, "Ceres polish", f.samples));
  }
  if (f.overcast_held_inseparable) {
    d.push_back(DecisionFromBench("overcast zenith luminance L_z held (model ffxv-iso)",
                                  "not separable from the isotropic table, which spans the overcast shape (a function "
                                  "of the view elevation only): the term is folded into that table (L_z held at 1e-6 "
                                  "of the start's)",
                                  bench.inseparable_overcast, "overcast held (ffxv-iso)", f.samples));
  }
  if (f.overcast_absent) {
    d.push_back(NoCostDecision("overcast term not fitted", "overcast_weight is 0: the term contributes nothing",
                               "none: L_z was never a parameter; nothing is evaluated for it"));
  }
  if (!result->unobserved_rows.empty()) {
    d.push_back(NoCostDecision(std::to_string(result->unobserved_rows.size()) + " unobserved LUT rows held",
                               "no reference has its sun near them (see unobserved_lut_rows)",
                               "none: no pixel reads them, so they are in no residual block; as parameters they would "
                               "be held by the prior alone (not switchable)"));
  }
  if (f.extrapolated_columns > 0) {
    d.push_back(NoCostDecision(std::to_string(f.extrapolated_columns) +
                                   " unobserved (table, LUT column) pairs held out of the solve",
                               "no fitted pixel reaches them (view elevations within ~0.1 deg of the horizon): they "
                               "take the change of the nearest observed column",
                               "none measured: they are in no residual block; as free parameters held by the weak "
                               "prior alone they made the normal equations nearly singular (not switchable)"));
  }
}

}  // namespace

ImageRGB RenderAtReference(const Reference& ref, const render::Preset& preset, render::SkyRenderer& renderer) {
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = ref.radiance.width;
  req.height = ref.radiance.height;
  if (!ref.row_mapping) return renderer.Render(preset, req);
  // Horizon-biased rows: a uniform render at least as dense, through the same resampling
  // `skycal resample` applied to the reference (band means of the rows).
  req.height = UniformHeightCovering(*ref.row_mapping);
  return ResampleToRows(renderer.Render(preset, req), *ref.row_mapping);
}

ImageErrors CompareToReference(const Reference& ref, const ImageRGB& fit) {
  ImageErrors e;
  double wsum = 0.0, rel = 0.0, lg = 0.0;
  const int w = ref.radiance.width, h = ref.radiance.height;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (ref.pixel_class[i] != PixelClass::kSky) continue;
      const double omega = ref.PixelSolidAngle(x, y);
      for (int c = 0; c < 3; ++c) {
        const double r = ref.radiance.pixels[3 * i + c], f = fit.pixels[3 * i + c];
        rel += omega * ((f - r) / r) * ((f - r) / r);
        const double d = f > 0.0 ? std::log(f / r) : 50.0;
        lg += omega * d * d;
      }
      wsum += 3.0 * omega;
      ++e.pixels;
    }
  }
  e.rel_rmse = std::sqrt(rel / wsum);
  e.log_rmse = std::sqrt(lg / wsum);
  return e;
}

FitResult FitSky(const std::vector<Reference>& refs, const render::Preset& init, const FitOptions& o,
                 render::SkyRenderer& renderer, const std::vector<const ProbeSamples*>& probes) {
  return FitSkyWithTerms(refs, init, o, renderer, probes, {});
}

namespace {

// The linear start (fit/src/linear_stage.h): the LUT, g, L_z and the exposures at the
// robust optimum of the linear structure; the Ceres levels then run only where needed
// (`widths` keeps the levels still to solve).
LinearStageOutcome RunLinearStartStage(const std::vector<Reference>& refs, const FitOptions& o, bool tied,
                                       const std::vector<bool>& row_fitted, bool fit_overcast, bool needs_polish,
                                       render::SkyRenderer& renderer, std::vector<int>* widths, DecisionFacts* facts,
                                       FitState* state, FitResult* result) {
  LinearStageOutcome linear;
  if (!o.linear_start) return linear;
  linear = RunLinearStage(refs, o, tied, row_fitted, fit_overcast, needs_polish, widths->back(), renderer, state,
                          result);
  if (widths->size() > 1 && o.skip_coarse_levels) facts->coarse_widths_skipped.assign(widths->begin(), widths->end() - 1);
  if (!linear.polish && o.skip_coarse_levels) {
    facts->polish_skipped = true;
    widths->clear();
  } else if (widths->size() > 1 && o.skip_coarse_levels) {
    std::string skipped_widths;
    for (size_t i = 0; i + 1 < widths->size(); ++i) skipped_widths += (i ? ", " : "") + std::to_string((*widths)[i]);
    result->skipped.push_back({"coarse pyramid levels (" + skipped_widths + " wide)",
                               "the linear start already placed the LUT and g at the optimum of the linear "
                               "structure: only the finest level is polished"});
    *widths = {widths->back()};
  }
  return linear;
}

SkyRowsTerm::Setup SkyRowsSetup(size_t n_refs, const FitOptions& o, bool tied, const LinearStageOutcome& linear) {
  SkyRowsTerm::Setup sky_setup;
  sky_setup.tied = tied;
  sky_setup.loss = o.loss;
  sky_setup.numeric_derivatives = o.numeric_derivatives;
  sky_setup.use_ring_scales = linear.ran;
  sky_setup.ring_scales = linear.ring_scales_per_reference.size() == n_refs
                              ? linear.ring_scales_per_reference
                              : std::vector<RingLossScales>(n_refs, linear.ring_scales.value_or(RingLossScales{}));
  return sky_setup;
}

// The Ceres levels still to solve, coarse to fine.
void SolveLevels(const std::vector<FitTerm*>& terms, const std::vector<Reference>& refs, const FitOptions& o,
                 const std::vector<int>& widths, const LinearStageOutcome& linear, bool fit_overcast,
                 Clock::time_point t_start, render::SkyRenderer& renderer, FitState* state, FitResult* result) {
  LevelSolveOptions lo;
  lo.count = widths.size();
  lo.render_in_loop = o.backend == render::Backend::kVulkan && !o.numeric_derivatives;
  lo.fit_haziness = o.fit_haziness;
  lo.fit_overcast = fit_overcast;
  lo.absolute = o.absolute;
  lo.after_linear_start = o.linear_start;
  lo.max_iterations = o.max_iterations_per_level;
  lo.verbose = o.verbose;
  lo.start = t_start;
  lo.held = linear.held;
  for (size_t li = 0; li < widths.size(); ++li) {
    lo.width = widths[li];
    lo.index = li;
    // Graduated non-convexity: the robust loss starts wide on coarse levels (x2 per level
    // above the finest) so a far start is not trapped by down-weighted pixels.
    lo.loss_scale = linear.ran ? linear.loss_scale
                               : o.loss_scale * std::pow(2.0, static_cast<double>(widths.size() - 1 - li));
    result->levels.push_back(SolveLevel(terms, refs, lo, renderer, state));
    result->iterations += result->levels.back().iterations;
    result->termination = result->levels.back().termination;
  }
}

// Columns no pixel reached: the change (log) of the nearest observed column, per row.
void ExtrapolateColumns(const std::set<std::pair<int, int>>& observed, const std::vector<bool>& row_fitted,
                        DecisionFacts* facts, FitState* state, FitResult* result) {
  facts->extrapolated_columns = ExtrapolateUnobservedColumns(observed, row_fitted, state);
  if (facts->extrapolated_columns > 0) {
    result->skipped.push_back({"LUT columns without observations",
                               std::to_string(facts->extrapolated_columns) +
                                   " (table, column) pairs no fitted pixel reaches (view elevations the reference "
                                   "does not sample, e.g. within ~0.1 deg of the horizon): given the change of "
                                   "the nearest observed column"});
  }
}

// The fitted preset, and per reference its exposure, render and errors.
void ReportReferences(const std::vector<Reference>& refs, const FitState& state, render::SkyRenderer& renderer,
                      FitResult* result) {
  result->preset = state.ToPreset();
  render::ValidatePreset(result->preset, "fitted preset");
  for (size_t r = 0; r < refs.size(); ++r) {
    ReferenceFit& rf = result->references[r];
    rf.exposure = std::exp(state.log_exposure[r]);
    rf.rendered = RenderAtReference(refs[r], result->preset, renderer);
    for (float& v : rf.rendered.pixels) v = static_cast<float>(v * rf.exposure);
    rf.errors = CompareToReference(refs[r], rf.rendered);
  }
}

}  // namespace

FitResult FitSkyWithTerms(const std::vector<Reference>& refs, const render::Preset& init, const FitOptions& o,
                          render::SkyRenderer& renderer, const std::vector<const ProbeSamples*>& probes,
                          const std::vector<FitTerm*>& extra_terms) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (refs.empty()) throw Error("fit: no reference given");
  // The start must be a valid preset (names the field or table on a NaN, a negative
  // entry or an out-of-range parameter); zero LUT entries start at a floor (FitState).
  render::ValidatePreset(init, "initial preset '" + init.name + "'");
  const auto t_start = Clock::now();
  FitResult result;
  result.backend_description = renderer.Describe();
  FitState state = FitState::FromPreset(init, o.variant, static_cast<int>(refs.size()));
  const bool tied = refs.size() == 1;

  // The terms of the Ceres problem: the probe is known now; the sky rows and LUT priors
  // once the linear start has set the loss scales.
  ProbeTerm probe(refs, probes, o, tied, init.ground_albedo);
  probe.ReportSkips(&result.skipped, &result.decisions);
  for (const FitTerm* term : extra_terms) term->ReportSkips(&result.skipped, &result.decisions);
  const bool fit_overcast = PlanSharedBlocks(state, o, &result);
  const std::vector<bool> row_fitted = PlanRows(refs, &state, &result);
  state.StartDarkRowsFlat(row_fitted);

  DecisionFacts facts;
  facts.overcast_absent = state.preset.overcast_weight <= 0.0;
  facts.overcast_held_inseparable = !facts.overcast_absent && o.fit_overcast && state.tables == 3 &&
                                    o.hold_inseparable_overcast;
  if (facts.overcast_held_inseparable) state.log_overcast_zenith += std::log(kFoldedOvercastFraction);
  std::vector<int> widths = o.pyramid_widths.empty() ? AutomaticPyramid(refs[0].radiance.width) : o.pyramid_widths;
  facts.finest_width = std::min(widths.back(), refs[0].radiance.width);
  // Terms beyond the linear structure (the probe, extra terms) need the Ceres polish.
  const LinearStageOutcome linear = RunLinearStartStage(refs, o, tied, row_fitted, fit_overcast,
                                                        probe.any() || !extra_terms.empty(), renderer, &widths,
                                                        &facts, &state, &result);

  SkyRowsTerm sky_rows(SkyRowsSetup(refs.size(), o, tied, linear));
  LutPriorTerm priors({&sky_rows, row_fitted, tied, o.prior_weight, o.smoothness});
  UnseenProfileTerm unseen(linear.unseen_profile);
  // Order matters only for the problem's block order: the sky rows, the probe, the
  // priors, then any extra term (a cloud-lighting term plugs in here, FitSkyWithTerms).
  std::vector<FitTerm*> terms = {&sky_rows, &probe, &priors, &unseen};
  terms.insert(terms.end(), extra_terms.begin(), extra_terms.end());
  SolveLevels(terms, refs, o, widths, linear, fit_overcast, t_start, renderer, &state, &result);

  state.ApplyTiedRows();
  ExtrapolateColumns(widths.empty() ? linear.observed_columns : sky_rows.observed_columns(), row_fitted, &facts, &state,
                     &result);
  // Move the LUT scale gauge onto the exposures (fit/src/fit_finish.h).
  if (!o.absolute) probe.MoveScaleGauge(MoveScaleGaugeToExposures(row_fitted, fit_overcast, &state), &state);

  facts.evaluation_s = result.linear_start.time_s();
  for (const LevelReport& l : result.levels) facts.evaluation_s += l.time_s;
  if (!result.levels.empty()) {
    facts.polish_level_s = result.levels.back().time_s;
    facts.polish_level_width = result.levels.back().width;
  }
  facts.samples = linear.ran ? result.linear_start.samples() : sky_rows.last_residuals();

  ReportReferences(refs, state, renderer, &result);
  for (const FitTerm* term : terms) term->Summarise(state, &result);
  RecordDecisions(refs, facts, &result);
  result.time_s = Seconds(t_start, Clock::now());
  return result;
}

}  // namespace skycal::fit
