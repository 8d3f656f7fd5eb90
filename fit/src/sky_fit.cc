#include "skycal/fit/sky_fit.h"

#include <ceres/ceres.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <set>

#include "fit_state.h"
#include "fit_finish.h"
#include "linear_stage.h"
#include "probe_terms.h"
#include "pyramid.h"
#include "sky_row_cost.h"
#include "sky_terms.h"
#include "sun_from_probe.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::fit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }


// Renders the model at the current point for every reference, once per new evaluation
// point, before Ceres evaluates the residual blocks (the Vulkan backend's objective).
class RenderAtEvaluationPoint final : public ceres::EvaluationCallback {
 public:
  RenderAtEvaluationPoint(const FitState* state, const std::vector<Reference>* refs, render::SkyRenderer* renderer,
                          int width, int height, std::vector<ImageRGB>* images, bool* valid)
      : state_(state), refs_(refs), renderer_(renderer), width_(width), height_(height), images_(images), valid_(valid) {}
  void PrepareForEvaluation(bool /*evaluate_jacobians*/, bool new_evaluation_point) override {
    if (!new_evaluation_point && renders_ > 0) return;
    // A trial step far outside the model's domain (an overflowing LUT entry) is not
    // rendered: the residual blocks then report failure and Ceres shrinks the step.
    *valid_ = false;
    for (const auto* v : {&state_->log_lut, &state_->log_delta}) {
      for (double x : *v) {
        if (!(std::abs(x) < 80.0)) return;
      }
    }
    render::Preset preset;
    try {
      preset = state_->ToPreset();
      render::ValidatePreset(preset, "trial point");
    } catch (const Error&) {
      return;
    }
    for (size_t r = 0; r < refs_->size(); ++r) {
      render::RenderRequest req;
      req.sun_dir = (*refs_)[r].sun_dir;
      req.width = width_;
      req.height = height_;
      req.sun_disc = false;
      req.ground = render::GroundMode::kZero;
      (*images_)[r] = renderer_->Render(preset, req);
    }
    ++renders_;
    *valid_ = true;
  }
  int renders() const { return renders_; }

 private:
  const FitState* state_;
  const std::vector<Reference>* refs_;
  render::SkyRenderer* renderer_;
  int width_, height_;
  std::vector<ImageRGB>* images_;
  bool* valid_;
  int renders_ = 0;
};

class ProgressPrinter final : public ceres::IterationCallback {
 public:
  ProgressPrinter(std::string level, Clock::time_point start) : level_(std::move(level)), start_(start) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    std::cerr << "[fit] " << level_ << " iteration " << s.iteration << "  cost " << s.cost << "  |step| "
              << s.step_norm << "  elapsed " << Seconds(start_, Clock::now()) << " s" << std::endl;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::string level_;
  Clock::time_point start_;
};

}  // namespace

ImageErrors CompareToReference(const Reference& ref, const ImageRGB& fit) {
  ImageErrors e;
  double wsum = 0.0, rel = 0.0, lg = 0.0;
  const int w = ref.radiance.width, h = ref.radiance.height;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (ref.pixel_class[i] != PixelClass::kSky) continue;
      const double omega = latlong::PixelSolidAngle(x, y, w, h);
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
  // One reference sees only a blend of the two rows around its sun angle: tie them.
  const bool tied = refs.size() == 1;
  const render::LutGrid& grid = state.preset.luts.grid;

  // The gray probe: which references have one, what it can observe.
  std::vector<ProbeFrame> frames = PrepareProbeFrames(refs, probes);
  std::vector<bool> probed(refs.size(), false);
  int probed_count = 0, ground_facing = 0;
  for (size_t r = 0; r < refs.size(); ++r) {
    probed[r] = frames[r].probe != nullptr;
    probed_count += probed[r] ? 1 : 0;
    ground_facing += frames[r].ground_facing;
  }
  const bool fit_ground = probed_count > 0 && o.fit_ground_albedo && ground_facing >= 3;
  std::string ground_reason;
  if (probed_count == 0) {
    result.skipped.push_back({{"block", "sun illuminance, ground albedo"},
                              {"reason", "no reference has probe samples: only the probe observes them"}});
  } else {
    for (size_t r = 0; r < refs.size(); ++r) {
      if (!probed[r]) {
        result.skipped.push_back({{"block", "sun illuminance of " + refs[r].name}, {"reason", "no probe samples"}});
      } else if (!frames[r].sun_observable) {
        result.skipped.push_back({{"block", "sun illuminance of " + refs[r].name}, {"reason", frames[r].note}});
      }
    }
    if (!fit_ground) {
      ground_reason = o.fit_ground_albedo ? "only " + std::to_string(ground_facing) +
                                                " probe samples face the ground (normal y < -0.1; need 3): not observable"
                                          : "disabled by option";
      result.skipped.push_back({{"block", "ground_albedo"}, {"reason", ground_reason}});
    }
  }
  std::atomic<long long> probe_eval_ns{0};
  long long probe_residuals = 0;

  // What this scene does not need.
  if (state.tables == 2) result.skipped.push_back({{"block", "isotropic LUT"}, {"reason", "model ffxv has no isotropic term"}});
  const bool fit_overcast = o.fit_overcast && state.preset.overcast_weight > 0.0;
  if (!fit_overcast) {
    result.skipped.push_back({{"block", "overcast_zenith_luminance"},
                              {"reason", state.preset.overcast_weight > 0.0
                                             ? "disabled by option"
                                             : "overcast_weight is 0 in the initial preset: the term is absent (its "
                                               "weight is not separable from the LUT scale, so the fit never changes it)"}});
  }
  if (o.absolute) result.skipped.push_back({{"block", "exposure"}, {"reason", "--absolute: references are calibrated"}});
  if (!o.fit_haziness) result.skipped.push_back({{"block", "haziness_g"}, {"reason", "disabled by option"}});

  // LUT rows each reference constrains (its sun position between two rows).
  std::set<int> observed;
  for (size_t r = 0; r < refs.size(); ++r) {
    const double one_minus_cos_max = 1.0 - std::cos(grid.theta_max_deg * M_PI / 180.0);
    const double pos = std::clamp((1.0 - refs[r].sun_dir[1]) / one_minus_cos_max, 0.0, 1.0) * (grid.n_theta - 1);
    const int r0 = std::clamp(static_cast<int>(std::floor(pos)), 0, grid.n_theta - 2);
    ReferenceFit rf;
    rf.observed_rows.push_back(r0);
    if (pos - r0 > 0.0) rf.observed_rows.push_back(r0 + 1);
    for (int row : rf.observed_rows) observed.insert(row);
    result.references.push_back(rf);
  }
  // With several references the rows between the observed ones are fitted too (held by
  // the smoothness prior); rows outside the observed range are not parameters at all.
  const int first_row = *observed.begin(), last_row = *observed.rbegin();
  std::vector<bool> row_fitted(grid.n_theta, false);
  for (int row = first_row; row <= last_row; ++row) row_fitted[row] = refs.size() > 1 || observed.count(row);
  if (tied) state.tied_rows.assign(observed.begin(), observed.end());
  for (int row = 0; row < grid.n_theta; ++row) {
    if (row_fitted[row]) continue;
    result.unobserved_rows.push_back({{"row", row},
                                      {"sun_zenith_deg", render::LutRowSunZenithRad(grid, row) * 180.0 / M_PI},
                                      {"reason", "no reference has its sun near this row: held at the initial preset"}});
  }
  if (!result.unobserved_rows.empty()) {
    result.skipped.push_back({{"block", "LUT rows without observations"},
                              {"reason", std::to_string(result.unobserved_rows.size()) +
                                             " of " + std::to_string(grid.n_theta) +
                                             " rows: no reference sun angle near them (see unobserved_rows)"}});
  }

  const size_t table_size = state.preset.luts.table_size();
  std::set<std::pair<int, int>> last_observed_columns;  // at the finest level
  std::vector<int> widths = o.pyramid_widths.empty() ? AutomaticPyramid(refs[0].radiance.width) : o.pyramid_widths;
  const bool use_gpu = o.backend == render::Backend::kVulkan && !o.numeric_derivatives;
  // The linear start (fit/src/linear_stage.h): the LUT, g, L_z and the exposures at the
  // robust optimum of the linear structure; the Ceres levels then run only where needed.
  LinearStageOutcome linear;
  if (o.linear_start) {
    linear = RunLinearStage(refs, o, tied, row_fitted, fit_overcast, probed_count > 0, widths.back(), renderer, &state,
                            &result);
    if (!linear.polish) {
      widths.clear();
    } else if (widths.size() > 1) {
      std::string skipped_widths;
      for (size_t i = 0; i + 1 < widths.size(); ++i) skipped_widths += (i ? ", " : "") + std::to_string(widths[i]);
      result.skipped.push_back({{"block", "coarse pyramid levels (" + skipped_widths + " wide)"},
                                {"reason", "the linear start already placed the LUT and g at the optimum of the linear "
                                           "structure: only the finest level is polished"}});
      widths = {widths.back()};
    }
  }
  for (size_t li = 0; li < widths.size(); ++li) {
    const auto t_level = Clock::now();
    std::vector<FitLevel> levels;
    double total_weight = 0.0;
    for (const Reference& ref : refs) {
      levels.push_back(BuildLevel(ref, widths[li]));
      total_weight += levels.back().total_weight;
    }
    const int lw = levels[0].width, lh = levels[0].height;
    std::vector<ImageRGB> rendered(refs.size());
    bool rendered_valid = false;
    // Graduated non-convexity: the robust loss starts wide on coarse levels (x2 per level
    // above the finest) so a far start is not trapped by down-weighted pixels.
    const double level_loss_scale = linear.ran
                                        ? linear.loss_scale
                                        : o.loss_scale * std::pow(2.0, static_cast<double>(widths.size() - 1 - li));

    ceres::Problem::Options popts;
    popts.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    std::unique_ptr<RenderAtEvaluationPoint> callback;
    if (use_gpu) {
      callback = std::make_unique<RenderAtEvaluationPoint>(&state, &refs, &renderer, lw, lh, &rendered, &rendered_valid);
      popts.evaluation_callback = callback.get();
    }
    ceres::Problem problem(popts);
    long long residual_count = 0;

    SkyRowTerms rows;
    rows.refs = &refs;
    rows.levels = &levels;
    rows.total_weight = total_weight;
    rows.tied = tied;
    rows.loss = o.loss;
    rows.loss_scale = level_loss_scale;
    rows.numeric_derivatives = o.numeric_derivatives;
    rows.rendered = use_gpu ? &rendered : nullptr;
    rows.rendered_valid = &rendered_valid;
    rows.ring_scales = linear.ring_scales_per_reference.size() == refs.size()
                           ? linear.ring_scales_per_reference
                           : std::vector<RingLossScales>(refs.size(), linear.ring_scales.value_or(RingLossScales{}));
    rows.use_ring_scales = linear.ran;
    const AddedSkyRows added = AddSkyRowTerms(rows, &state, &problem);
    const std::set<double*>& texel_blocks = added.texel_blocks;
    residual_count += added.residuals;
    // Regularisation. Only LUT parameters some pixel reaches are in the problem; columns
    // no pixel reaches (the lowest, horizon-hugging ones at coarse sizes) are filled in
    // after the solve from their nearest observed column (see ExtrapolateColumns): as
    // free parameters held only by a weak prior they made the normal equations nearly
    // singular and Levenberg-Marquardt slow.
    // - free rows (a day): a second-difference prior along the sun zenith links each
    //   observed column's rows, which also fills rows between the references' sun angles;
    // - every parameter: a very weak pull toward the initial preset, for the blends of two
    //   rows that no combination of references separates.
    std::set<std::pair<int, int>> observed_columns;  // (table, column)
    for (double* b : texel_blocks) {
      const bool is_delta = tied;
      const size_t k = is_delta ? static_cast<size_t>(b - state.log_delta.data()) : static_cast<size_t>(b - state.log_lut.data());
      const int col = static_cast<int>((k / 3) % grid.n_gamma);
      const int table = is_delta ? static_cast<int>(k / (3 * grid.n_gamma)) : static_cast<int>(k / table_size);
      observed_columns.insert({table, col});
    }
    // The probe residuals (fit/src/probe_cost.h, weighting: fit/src/probe_terms.h). The sun
    // of each probed reference is decided here, at the current point: visible -> its
    // illuminance is a parameter (started at the linear solution the first time), occluded
    // -> held at 0 (a dark sun is not fitted).
    std::vector<std::vector<double*>> probe_blocks(refs.size());
    auto MakeProbeBlock = [&](const ProbeFrame& f, size_t r, std::vector<double*>* blocks) {
      std::vector<size_t> no_lut_parameters;
      auto cost = MakeProbeCost(f, refs[r], state, o, tied, levels[r].total_weight / total_weight, {}, level_loss_scale,
                                &probe_eval_ns, &no_lut_parameters);
      *blocks = {&state.g, &state.log_overcast_zenith, &state.log_exposure[r], state.sun_rgb[r].data(),
                 &state.ground_albedo};
      return cost;
    };
    {
      const ProbeTermCounts counts = AddProbeTerms(MakeProbeBlock, probed, li == 0, o.sun_visible_threshold, &frames,
                                                   &probe_blocks, &state, &problem);
      if (li == 0) probe_residuals += counts.residuals;
      residual_count += counts.residuals;
    }
    if (problem.HasParameterBlock(&state.ground_albedo)) {
      if (fit_ground) {
        problem.SetParameterLowerBound(&state.ground_albedo, 0, 0.0);
        problem.SetParameterUpperBound(&state.ground_albedo, 0, 1.0);
      } else {
        problem.SetParameterBlockConstant(&state.ground_albedo);
      }
    }

    AddLutPriorTerms(observed_columns, row_fitted, tied, o.prior_weight, o.smoothness, &state, &problem);
    last_observed_columns = observed_columns;
    for (double* p : linear.held) {
      if (problem.HasParameterBlock(p)) problem.SetParameterBlockConstant(p);
    }
    if (problem.HasParameterBlock(&state.g)) {
      if (o.fit_haziness) {
        problem.SetParameterLowerBound(&state.g, 0, 0.0);
        problem.SetParameterUpperBound(&state.g, 0, 0.999);
      } else {
        problem.SetParameterBlockConstant(&state.g);
      }
    }
    if (problem.HasParameterBlock(&state.log_overcast_zenith) && !fit_overcast) {
      problem.SetParameterBlockConstant(&state.log_overcast_zenith);
    }
    for (size_t r = 0; r < refs.size(); ++r) {
      // Gauge: exposure x LUT scale is one degree of freedom. The first reference's
      // exposure is held during the solve and the scale is moved to it afterwards.
      if (problem.HasParameterBlock(&state.log_exposure[r]) && (o.absolute || r == 0)) {
        problem.SetParameterBlockConstant(&state.log_exposure[r]);
      }
    }

    ceres::Solver::Options so;
    so.max_num_iterations = o.max_iterations_per_level;
    so.num_threads = 2;
    // The Jacobian has ~10^5 rows but each row block touches <= 15 parameters: a sparse
    // normal-equation Cholesky; dense solvers would materialise a ~0.5 GB dense Jacobian.
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.sparse_linear_algebra_library_type =
        ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SUITE_SPARSE : ceres::EIGEN_SPARSE;
    // Coarse levels only need to bring the start close; the finest level converges fully.
    const bool finest = li + 1 == widths.size();
    // After the linear start the polish only converts the relative-error optimum to the
    // robust log one: it stops once an iteration gains < 1e-4 of the cost (measured on
    // clean skies: the tail beyond that is ~40 iterations that gain 0.3% of the cost,
    // 0.15% of the rel RMSE, moving LUT entries the image barely sees).
    so.function_tolerance = !finest ? 1e-5 : o.linear_start ? 1e-4 : 1e-9;
    so.gradient_tolerance = finest ? 1e-12 : 1e-8;
    so.parameter_tolerance = finest ? 1e-7 : 1e-6;
    so.update_state_every_iteration = use_gpu;  // the callback reads the parameter memory
    so.logging_type = ceres::SILENT;
    const std::string level_name = std::to_string(lw) + "x" + std::to_string(lh);
    ProgressPrinter progress("level " + level_name, t_start);
    if (o.verbose) so.callbacks.push_back(&progress);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (summary.termination_type == ceres::FAILURE) {
      throw Error("fit: Ceres failed at level " + level_name + ": " + summary.message);
    }
    int probe_final_iterations = 0;
    if (finest && probed_count > 0) {
      probe_final_iterations =
          RefitProbesOnFinalSky(MakeProbeBlock, probed, fit_ground, o.sun_visible_threshold, &frames, &probe_blocks, &state);
    }
    result.iterations += static_cast<int>(summary.iterations.size()) - 1;
    result.termination = ceres::TerminationTypeToString(summary.termination_type);
    result.levels.push_back({{"size", {lw, lh}},
                             {"residuals", residual_count},
                             {"parameters", summary.num_effective_parameters},
                             {"iterations", static_cast<int>(summary.iterations.size()) - 1},
                             {"initial_cost", summary.initial_cost},
                             {"final_cost", summary.final_cost},
                             {"termination", ceres::TerminationTypeToString(summary.termination_type)},
                             {"renders", callback ? callback->renders() : 0},
                             {"probe_final_solve_iterations", probe_final_iterations},
                             {"time_s", Seconds(t_level, Clock::now())}});
  }

  if (widths.empty()) last_observed_columns = linear.observed_columns;  // no Ceres level ran
  state.ApplyTiedRows();
  // Columns no pixel reached: the change (log) of the nearest observed column, per row.
  const int extrapolated = ExtrapolateUnobservedColumns(last_observed_columns, row_fitted, &state);
  if (extrapolated > 0) {
    result.skipped.push_back({{"block", "LUT columns without observations"},
                              {"reason", std::to_string(extrapolated) +
                                             " (table, column) pairs no fitted pixel reaches (view elevations the reference "
                                             "does not sample, e.g. within ~0.1 deg of the horizon): given the change of "
                                             "the nearest observed column"}});
  }
  // Move the LUT scale gauge onto the exposures (fit/src/fit_finish.h).
  if (!o.absolute) {
    const double shift = MoveScaleGaugeToExposures(row_fitted, fit_overcast, &state);
    // The probe sees exposure * (sky + sun): the sun's model units move with the LUT.
    for (size_t r = 0; r < refs.size(); ++r) {
      for (int c = 0; c < 3; ++c) {
        state.sun_rgb[r][c] *= std::exp(-shift);
        frames[r].fitted_sun[c] *= std::exp(-shift);
      }
    }
  }

  result.preset = state.ToPreset();
  render::ValidatePreset(result.preset, "fitted preset");
  for (size_t r = 0; r < refs.size(); ++r) {
    ReferenceFit& rf = result.references[r];
    rf.exposure = std::exp(state.log_exposure[r]);
    render::RenderRequest req;
    req.sun_dir = refs[r].sun_dir;
    req.width = refs[r].radiance.width;
    req.height = refs[r].radiance.height;
    rf.rendered = renderer.Render(result.preset, req);
    for (float& v : rf.rendered.pixels) v = static_cast<float>(v * rf.exposure);
    rf.errors = CompareToReference(refs[r], rf.rendered);
    if (!probed[r]) continue;
    const ProbeFrame& f = frames[r];
    ProbeSun ps;
    ps.observable = f.sun_observable;
    ps.note = f.note;
    ps.visible = f.sun_observable && f.visible;
    for (int c = 0; c < 3; ++c) {
      ps.illuminance_model[c] = ps.visible ? state.sun_rgb[r][c] : 0.0;
      ps.illuminance_ref[c] = ps.illuminance_model[c] * rf.exposure;
      ps.fitted_model[c] = f.fitted_sun[c];
    }
    ps.lux = Rec709Luminance(ps.illuminance_model);
    ps.fraction = f.fraction;
    ps.residual = f.residual;
    ps.log_rmse = f.log_rmse;
    ps.samples = static_cast<int>(f.samples.size());
    ps.sun_facing_samples = f.sun_facing;
    ps.ground_facing_samples = f.ground_facing;
    rf.sun = ps;
  }
  if (probed_count > 0) {
    int dropped = 0;
    for (const auto& f : frames) dropped += f.dropped;
    result.probe = {{"references", probed_count},
                    {"weight", o.probe_weight},
                    {"quadrature_width", o.probe_quadrature_width},
                    {"residuals", probe_residuals},
                    {"dropped_samples", dropped},
                    {"evaluation_time_s", 1e-9 * static_cast<double>(probe_eval_ns.load())},
                    {"ground_albedo", {{"fitted", fit_ground},
                                       {"value", result.preset.ground_albedo},
                                       {"initial", init.ground_albedo}}}};
    if (!fit_ground) result.probe["ground_albedo"]["reason"] = ground_reason;
  }
  result.time_s = Seconds(t_start, Clock::now());
  return result;
}

}  // namespace skycal::fit
