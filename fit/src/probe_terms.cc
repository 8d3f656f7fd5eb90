#include "probe_terms.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"
#include "skycal/core/math_constants.h"
#include "fit_decisions.h"
#include "sun_from_probe.h"

namespace skycal::fit {
namespace {
double Dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Predicted ball radiance (reference units) of sample i for illuminance `sun`.
std::array<double, 3> Predict(const ProbeIrradianceParts& parts, size_t i, const std::array<double, 3>& sun, double k,
                              double albedo) {
  std::array<double, 3> p{};
  for (int c = 0; c < 3; ++c) p[c] = k * albedo / kPi * (parts.ambient[i][c] + sun[c] * parts.sun_factor[i]);
  return p;
}
}  // namespace

std::vector<ProbeFrame> PrepareProbeFrames(const std::vector<Reference>& refs,
                                           const std::vector<const ProbeSamples*>& probes) {
  std::vector<ProbeFrame> frames(refs.size());
  if (probes.empty()) return frames;
  if (probes.size() != refs.size()) {
    throw Error("fit: " + std::to_string(probes.size()) + " probe entries for " + std::to_string(refs.size()) +
                " references (need one per reference, null for none)");
  }
  for (size_t r = 0; r < refs.size(); ++r) {
    if (!probes[r]) continue;
    ProbeFrame& f = frames[r];
    f.probe = probes[r];
    const auto& s = refs[r].sun_dir;
    double pixels = 0.0;
    for (const capture::ProbeSample& smp : probes[r]->samples) {
      bool ok = smp.pixels > 0;
      for (int c = 0; c < 3; ++c) ok = ok && std::isfinite(smp.radiance[c]) && smp.radiance[c] > 0.0 && std::isfinite(smp.normal[c]);
      const double len = std::sqrt(Dot(smp.normal, smp.normal));
      if (!ok || !(len > 0.5)) {
        ++f.dropped;
        continue;
      }
      capture::ProbeSample unit = smp;
      for (double& v : unit.normal) v /= len;
      f.samples.push_back(unit);
      pixels += smp.pixels;
      if (Dot(unit.normal, s) > 0.05) ++f.sun_facing;
      if (unit.normal[1] < -0.1) ++f.ground_facing;
    }
    if (f.samples.empty()) {
      throw Error(probes[r]->path + ": no usable probe sample (every sample has a channel <= 0 or not finite)");
    }
    for (const auto& smp : f.samples) f.pixel_share.push_back(smp.pixels / pixels);
    if (!(s[1] > 0.0)) {
      f.note = "the sun is below the horizon: it does not light the ball";
    } else if (f.sun_facing < 3) {
      f.note = "only " + std::to_string(f.sun_facing) +
               " probe samples face the sun (need 3): the sun lights the ball's far side, not observable from this view";
    } else {
      f.sun_observable = true;
    }
  }
  return frames;
}

std::unique_ptr<ProbeCost> MakeProbeCost(const ProbeFrame& frame, const Reference& ref, const FitState& state,
                                         const FitOptions& o, bool tied_rows, double sky_share,
                                         const std::set<std::pair<int, int>>& parameter_columns, double loss_scale,
                                         std::atomic<long long>* evaluation_ns, std::vector<size_t>* texel_index) {
  ProbeCostSetup setup;
  setup.state = &state;
  setup.tied_rows = tied_rows;
  setup.initial_log_lut = &state.initial_log_lut;
  setup.sun_dir = ref.sun_dir;
  setup.albedo = frame.probe->albedo;
  setup.loss = o.loss;
  setup.loss_scale = loss_scale;
  setup.quadrature_width = o.probe_quadrature_width;
  setup.parameter_columns = parameter_columns;
  setup.evaluation_ns = evaluation_ns;
  for (size_t i = 0; i < frame.samples.size(); ++i) {
    ProbeResidualSample s;
    s.normal = frame.samples[i].normal;
    for (int c = 0; c < 3; ++c) s.log_radiance[c] = std::log(frame.samples[i].radiance[c]);
    s.sqrt_weight = std::sqrt(o.probe_weight * sky_share * frame.pixel_share[i]);
    setup.samples.push_back(s);
  }
  return std::make_unique<ProbeCost>(std::move(setup), texel_index);
}

LinearSun SolveLinearSun(const ProbeIrradianceParts& parts, const ProbeFrame& frame, double log_exposure) {
  LinearSun out;
  if (parts.ambient.size() != frame.samples.size()) return out;  // outside the model's domain
  const double k = std::exp(log_exposure), a = frame.probe->albedo;
  for (int c = 0; c < 3; ++c) {
    double fy = 0.0, ff = 0.0;
    for (size_t i = 0; i < frame.samples.size(); ++i) {
      const double f = parts.sun_factor[i], w = frame.pixel_share[i];
      const double y = kPi * frame.samples[i].radiance[c] / (a * k) - parts.ambient[i][c];
      fy += w * f * y;
      ff += w * f * f;
    }
    out.illuminance[c] = ff > 0.0 ? std::max(0.0, fy / ff) : 0.0;
  }
  out.fraction = SunShare(parts, frame, out.illuminance, log_exposure);
  return out;
}

double SunShare(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                double log_exposure) {
  if (parts.ambient.size() != frame.samples.size()) return 0.0;
  const double k = std::exp(log_exposure), a = frame.probe->albedo;
  std::vector<std::array<double, 3>> sun_radiance(frame.samples.size());
  for (size_t i = 0; i < frame.samples.size(); ++i)
    for (int c = 0; c < 3; ++c) sun_radiance[i][c] = k * a / kPi * sun[c] * parts.sun_direct[i];
  return capture::SunShareOfBrightest(frame.samples, sun_radiance, parts.sun_direct, 0.1);
}

void ProbeFitErrors(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                    double log_exposure, double* residual, double* log_rmse) {
  *residual = *log_rmse = 0.0;
  if (parts.ambient.size() != frame.samples.size()) return;
  double d2 = 0.0, m2 = 0.0, l2 = 0.0;
  for (size_t i = 0; i < frame.samples.size(); ++i) {
    const auto p = Predict(parts, i, sun, std::exp(log_exposure), frame.probe->albedo);
    for (int c = 0; c < 3; ++c) {
      const double m = frame.samples[i].radiance[c];
      d2 += (p[c] - m) * (p[c] - m);
      m2 += m * m;
      const double l = p[c] > 0.0 ? std::log(p[c] / m) : 50.0;
      l2 += l * l;
    }
  }
  *residual = m2 > 0.0 ? std::sqrt(d2 / m2) : 0.0;
  *log_rmse = std::sqrt(l2 / (3.0 * frame.samples.size()));
}

ProbeTermCounts AddProbeTerms(const ProbeBlockMaker& make_block, const std::vector<bool>& probed, bool first_level,
                              double sun_visible_threshold, std::vector<ProbeFrame>* frames,
                              std::vector<std::vector<double*>>* probe_blocks, FitState* state, ceres::Problem* problem) {
  ProbeTermCounts counts;
  const size_t n = frames->size();
  for (size_t r = 0; r < n; ++r) {
    if (!probed[r]) continue;
    ProbeFrame& f = (*frames)[r];
    std::vector<double*>& blocks = (*probe_blocks)[r];
    // The LUT is held for the probe at this level's starting values: see "what the probe
    // steers" in fit/src/probe_terms.h.
    auto cost = make_block(f, r, &blocks);
    if (f.sun_observable) {
      const LinearSun lin = SolveLinearSun(cost->Parts(blocks.data()), f, state->log_exposure[r]);
      const bool was_visible = !first_level && f.visible;
      f.visible = lin.fraction >= sun_visible_threshold;
      f.fraction = lin.fraction;
      if (f.visible && !was_visible) state->sun_rgb[r] = lin.illuminance;
      if (!f.visible) state->sun_rgb[r] = {0.0, 0.0, 0.0};
    }
    counts.residuals += 3LL * cost->num_samples();
    problem->AddResidualBlock(cost.release(), nullptr, blocks);
    if (f.sun_observable && f.visible) {
      for (int c = 0; c < 3; ++c) problem->SetParameterLowerBound(state->sun_rgb[r].data(), c, 0.0);
    } else {
      problem->SetParameterBlockConstant(state->sun_rgb[r].data());
    }
  }
  return counts;
}

int RefitProbesOnFinalSky(const ProbeBlockMaker& make_block, const std::vector<bool>& probed, bool fit_ground,
                          double sun_visible_threshold, std::vector<ProbeFrame>* frames,
                          std::vector<std::vector<double*>>* probe_blocks, FitState* state) {
  int iterations = 0;
  const size_t n = frames->size();
  // The probe on the final sky: the solve above held the LUT at this level's start, so
  // the sun and the ground albedo are refitted once with the final LUT, g and exposure
  // (a small problem: these blocks only), then the decisions are checked.
  ceres::Problem::Options polish_options;
  polish_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem polish(polish_options);
  std::vector<ProbeCost*> final_costs(n, nullptr);
  bool any_free = fit_ground;
  for (size_t r = 0; r < n; ++r) {
    if (!probed[r]) continue;
    auto cost = make_block((*frames)[r], r, &(*probe_blocks)[r]);
    final_costs[r] = cost.get();
    polish.AddResidualBlock(cost.release(), nullptr, (*probe_blocks)[r]);
    for (double* b : {&state->g, &state->log_overcast_zenith, &state->log_exposure[r]}) polish.SetParameterBlockConstant(b);
    if ((*frames)[r].sun_observable && (*frames)[r].visible) {
      for (int c = 0; c < 3; ++c) polish.SetParameterLowerBound(state->sun_rgb[r].data(), c, 0.0);
      any_free = true;
    } else {
      polish.SetParameterBlockConstant(state->sun_rgb[r].data());
    }
  }
  if (fit_ground) {
    polish.SetParameterLowerBound(&state->ground_albedo, 0, 0.0);
    polish.SetParameterUpperBound(&state->ground_albedo, 0, 1.0);
  } else {
    polish.SetParameterBlockConstant(&state->ground_albedo);
  }
  ceres::Solver::Options po;
  po.max_num_iterations = 50;
  po.linear_solver_type = ceres::DENSE_QR;
  po.logging_type = ceres::SILENT;
  if (any_free) {  // else nothing to refit (every sun occluded or unobservable, ground held)
    ceres::Solver::Summary polish_summary;
    ceres::Solve(po, &polish, &polish_summary);
    iterations = static_cast<int>(polish_summary.iterations.size()) - 1;
  }
  for (size_t r = 0; r < n; ++r) {
    if (!final_costs[r]) continue;
    ProbeFrame& f = (*frames)[r];
    const ProbeIrradianceParts parts = final_costs[r]->Parts((*probe_blocks)[r].data());
    ProbeFitErrors(parts, f, state->sun_rgb[r], state->log_exposure[r], &f.residual, &f.log_rmse);
    if (!f.sun_observable) continue;
    if (f.visible) {
      f.fitted_sun = state->sun_rgb[r];
      f.fraction = SunShare(parts, f, state->sun_rgb[r], state->log_exposure[r]);
      if (f.fraction < sun_visible_threshold) {
        f.visible = false;
        f.note = "the jointly fitted sun explains only " + std::to_string(f.fraction) +
                 " of the brightest sun-facing samples: occluded";
        state->sun_rgb[r] = {0.0, 0.0, 0.0};
      }
    } else {
      const LinearSun lin = SolveLinearSun(parts, f, state->log_exposure[r]);
      f.fitted_sun = lin.illuminance;
      f.fraction = lin.fraction;
      f.note = "the probe sits at the ambient level (the sun's share of its brightest sun-facing samples is " +
               std::to_string(lin.fraction) + "): sun occluded, held at 0";
    }
  }
  return iterations;
}

ProbeTerm::ProbeTerm(const std::vector<Reference>& refs, const std::vector<const ProbeSamples*>& probes,
                     const FitOptions& options, bool tied, double initial_ground_albedo)
    : refs_(refs), o_(options), tied_(tied), initial_ground_albedo_(initial_ground_albedo),
      frames_(PrepareProbeFrames(refs, probes)), probed_(refs.size(), false), blocks_(refs.size()) {
  for (size_t r = 0; r < refs.size(); ++r) {
    probed_[r] = frames_[r].probe != nullptr;
    probed_count_ += probed_[r] ? 1 : 0;
    ground_facing_ += frames_[r].ground_facing;
  }
  fit_ground_ = probed_count_ > 0 && o_.fit_ground_albedo && ground_facing_ >= 3;
  if (probed_count_ > 0 && !fit_ground_) {
    ground_reason_ = o_.fit_ground_albedo ? "only " + std::to_string(ground_facing_) +
                                                " probe samples face the ground (normal y < -0.1; need 3): not observable"
                                          : "disabled by option";
  }
}

std::unique_ptr<ProbeCost> ProbeTerm::MakeBlock(const ProbeFrame& f, size_t r, FitState& state,
                                                const LevelContext& level, std::vector<double*>* blocks) {
  std::vector<size_t> no_lut_parameters;
  auto cost = MakeProbeCost(f, refs_[r], state, o_, tied_, (*level.levels)[r].total_weight / level.total_weight, {},
                            level.loss_scale, &eval_ns_, &no_lut_parameters);
  *blocks = {&state.g, &state.log_overcast_zenith, &state.log_exposure[r], state.sun_rgb[r].data(),
             &state.ground_albedo};
  return cost;
}

long long ProbeTerm::AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) {
  if (probed_count_ == 0) return 0;
  auto make = [&](const ProbeFrame& f, size_t r, std::vector<double*>* blocks) {
    return MakeBlock(f, r, state, level, blocks);
  };
  const ProbeTermCounts counts =
      AddProbeTerms(make, probed_, level.first, o_.sun_visible_threshold, &frames_, &blocks_, &state, &problem);
  if (level.first) residuals_ += counts.residuals;
  if (problem.HasParameterBlock(&state.ground_albedo)) {
    if (fit_ground_) {
      problem.SetParameterLowerBound(&state.ground_albedo, 0, 0.0);
      problem.SetParameterUpperBound(&state.ground_albedo, 0, 1.0);
    } else {
      problem.SetParameterBlockConstant(&state.ground_albedo);
    }
  }
  return counts.residuals;
}

int ProbeTerm::AfterSolve(FitState& state, const LevelContext& level) {
  if (!level.finest || probed_count_ == 0) return 0;
  auto make = [&](const ProbeFrame& f, size_t r, std::vector<double*>* blocks) {
    return MakeBlock(f, r, state, level, blocks);
  };
  return RefitProbesOnFinalSky(make, probed_, fit_ground_, o_.sun_visible_threshold, &frames_, &blocks_, &state);
}

void ProbeTerm::ReportSkips(std::vector<SkipNote>* skipped, std::vector<FitDecision>* decisions) const {
  if (probed_count_ == 0) {
    skipped->push_back({"sun illuminance, ground albedo", "no reference has probe samples: only the probe observes them"});
  } else {
    for (size_t r = 0; r < refs_.size(); ++r) {
      if (!probed_[r]) {
        skipped->push_back({"sun illuminance of " + refs_[r].name, "no probe samples"});
      } else if (!frames_[r].sun_observable) {
        skipped->push_back({"sun illuminance of " + refs_[r].name, frames_[r].note});
      }
    }
    if (!fit_ground_) skipped->push_back({"ground_albedo", ground_reason_});
  }
  const int unprobed = static_cast<int>(refs_.size()) - probed_count_;
  if (unprobed > 0) {
    decisions->push_back(NoCostDecision(
        "probe blocks of " + std::to_string(unprobed) + " of " + std::to_string(refs_.size()) + " references not built",
        "no probe samples for them: a block would have no residuals, and their sun illuminance is unobservable",
        "none: there is nothing to evaluate without samples (what a probe costs when present, with the Ceres polish it "
        "forces, is in bench/results/probe_fit.json)"));
  }
}

void ProbeTerm::MoveScaleGauge(double shift, FitState* state) {
  // The probe sees exposure * (sky + sun): the sun's model units move with the LUT.
  for (size_t r = 0; r < refs_.size(); ++r) {
    for (int c = 0; c < 3; ++c) {
      state->sun_rgb[r][c] *= std::exp(-shift);
      frames_[r].fitted_sun[c] *= std::exp(-shift);
    }
  }
}

void ProbeTerm::Summarise(const FitState& state, FitResult* result) const {
  for (size_t r = 0; r < refs_.size(); ++r) {
    if (!probed_[r]) continue;
    const ProbeFrame& f = frames_[r];
    const double exposure = result->references[r].exposure;
    ProbeSun ps;
    ps.observable = f.sun_observable;
    ps.note = f.note;
    ps.visible = f.sun_observable && f.visible;
    for (int c = 0; c < 3; ++c) {
      ps.illuminance_model[c] = ps.visible ? state.sun_rgb[r][c] : 0.0;
      ps.illuminance_ref[c] = ps.illuminance_model[c] * exposure;
      ps.fitted_model[c] = f.fitted_sun[c];
    }
    ps.lux = Rec709Luminance(ps.illuminance_model);
    ps.fraction = f.fraction;
    ps.residual = f.residual;
    ps.log_rmse = f.log_rmse;
    ps.samples = static_cast<int>(f.samples.size());
    ps.sun_facing_samples = f.sun_facing;
    ps.ground_facing_samples = f.ground_facing;
    result->references[r].sun = ps;
  }
  if (probed_count_ == 0) return;
  ProbeReport p;
  p.references = probed_count_;
  p.weight = o_.probe_weight;
  p.quadrature_width = o_.probe_quadrature_width;
  p.residuals = residuals_;
  for (const auto& f : frames_) p.dropped_samples += f.dropped;
  p.evaluation_time_s = 1e-9 * static_cast<double>(eval_ns_.load());
  p.ground_albedo_fitted = fit_ground_;
  p.ground_albedo_value = result->preset.ground_albedo;
  p.ground_albedo_initial = initial_ground_albedo_;
  p.ground_albedo_reason = ground_reason_;
  result->probe = p;
}

}  // namespace skycal::fit
