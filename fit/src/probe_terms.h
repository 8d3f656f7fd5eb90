// The probe's part of the joint fit, per probed reference: which samples enter, what is
// observable (the sun needs samples facing it and a sun above the horizon; the ground
// albedo needs samples facing the ground), the linear start and visibility decision for
// the sun, and the report. The residual block itself is fit/src/probe_cost.h.
//
// What the probe steers. Its block holds the sun's RGB illuminance (only the probe sees
// it), the ground albedo (likewise), and shares g, log L_z and the exposure with the sky
// rows. The LUT entries are held for the probe: it reads their current values from the
// state (Ceres writes each accepted iterate there) but has no Jacobian on them, so the sky
// pixels alone set the LUT. Why: a ball's few dozen samples see the LUT only through
// hemispherical integrals, and what they could add is exactly what the sky pixels cannot
// see (differences between neighbouring LUT columns one pixel row blends, the masked and
// clipped aureole, which on the ball is indistinguishable from the sun). With LUT entries
// in its block, the synthetic scene of tests/probe_fit_test.cc with the ground albedo held
// 60% too low drove those combinations to 370% sky rel RMSE (probe weight 0.1; a per-entry
// information cap still reached 4000% at weight 1); held, the sky stays at the noise
// level (1.99%) for weights 0.01 .. 1.
//
// Weighting against the sky pixels. The sky rows of reference r carry weights summing to
// S_r = (its fitted solid angle) / (all references' fitted solid angle) per channel, so
// the sky term is S_r times a solid-angle mean of squared log errors. Its probe residuals
// carry weights summing to probe_weight * S_r, each sample in proportion to the ball
// pixels it averages: the probe term is probe_weight times the pixel mean of squared log
// errors over the ball. Both are relative errors of the same frame under the same
// exposure. The weight decides nothing about the parameters only the probe sees (the sun,
// the ground albedo); it trades the probe against the sky only for what both see: g, the
// overcast zenith luminance and (uncalibrated references) the exposure. Default 0.1: the
// sky's tens of thousands of pixels measure those directly, the ball's bins through
// integrals carrying the ball's own systematic errors (albedo known to a few percent,
// sheen, flare, a non-uniform ground); at 0.1 the probe cannot move them beyond what the
// sky allows, and at 10 it drags g to its bound (bench/results/probe_weight.md).
#pragma once
#include <ceres/ceres.h>

#include <array>
#include <atomic>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit_state.h"
#include "probe_cost.h"
#include "skycal/fit/sky_fit.h"

namespace skycal::fit {

struct ProbeFrame {
  const ProbeSamples* probe = nullptr;
  std::vector<capture::ProbeSample> samples;  // those that enter (finite, every channel > 0)
  std::vector<double> pixel_share;            // per sample: its pixels / all used samples' pixels
  int dropped = 0;                            // samples with a non-positive or non-finite channel
  int sun_facing = 0, ground_facing = 0;
  bool sun_observable = false;
  std::string note;                           // why the sun is not observable
  bool visible = false;                       // current decision (re-made before each level)
  double fraction = 0.0;                      // the sun's share behind that decision
  double residual = 0.0, log_rmse = 0.0;      // at the end of the last level
  std::array<double, 3> fitted_sun{};         // model units: the joint value, or the linear one when held at 0
};

// One frame per reference (probe nullptr: not probed). Throws skycal::Error naming the file
// when a probe has no usable sample.
std::vector<ProbeFrame> PrepareProbeFrames(const std::vector<Reference>& refs,
                                           const std::vector<const ProbeSamples*>& probes);

// The cost of one probed reference at one level; `texel_index` as ProbeCost.
std::unique_ptr<ProbeCost> MakeProbeCost(const ProbeFrame& frame, const Reference& ref, const FitState& state,
                                         const FitOptions& options, bool tied_rows, double sky_share,
                                         const std::set<std::pair<int, int>>& parameter_columns, double loss_scale,
                                         std::atomic<long long>* evaluation_ns, std::vector<size_t>* texel_index);

struct LinearSun {
  std::array<double, 3> illuminance{};  // model units, >= 0
  double fraction = 0.0;                // the sun's share of the brightest sun-facing samples
};
// Least squares of the sun illuminance with everything else at `parameters` (the cost's
// blocks), exposure exp(log_exposure): E_c = sum w f y / sum w f^2, y = pi R / (a k) - ambient.
LinearSun SolveLinearSun(const ProbeCost& cost, double const* const* parameters, const ProbeFrame& frame,
                         double log_exposure);

// The sun's share of the brightest sun-facing samples for illuminance `sun` (model units).
double SunShare(const ProbeCost& cost, double const* const* parameters, const ProbeFrame& frame,
                const std::array<double, 3>& sun, double log_exposure);

// RMS(R - P) / RMS(R) and RMS log(P / R) over samples and channels at `parameters`.
void ProbeFitErrors(const ProbeCost& cost, double const* const* parameters, const ProbeFrame& frame,
                    double log_exposure, double* residual, double* log_rmse);

}  // namespace skycal::fit
