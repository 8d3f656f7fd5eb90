// The probe's part of the joint fit, per probed reference: which samples enter, what is
// observable (the sun needs samples facing it and a sun above the horizon; the ground
// albedo needs samples facing the ground), the linear start and visibility decision for
// the sun, and the report. The residual block itself is fit/src/probe_cost.h.
//
// What the probe steers. Its block holds the sun's RGB illuminance (only the probe sees
// it), the ground albedo (likewise), and shares g, log L_z and the exposure with the sky
// rows. The LUT entries are not in it: each level's probe blocks are built with the LUT as
// it stands at the level's start (constants), and after the last level the sun and ground
// albedo are solved once more on the final sky. So the sky pixels alone set the LUT. Why:
// a ball's few dozen samples see the LUT only through hemispherical integrals, and what
// they could add is what the sky pixels cannot see (differences between neighbouring LUT
// columns that one pixel row blends, the masked and clipped aureole, which on the ball is
// indistinguishable from the sun). Measured on the synthetic scene of
// tests/probe_fit_test.cc with the ground albedo held at 0.1 where it is 0.25 (a probe the
// model cannot match): with LUT entries in the probe block the sky went to 370% rel RMSE
// (weight 0.1), and a per-entry information cap (probe <= 0.25 x sky on the diagonal of
// J^T J) still let it reach 4000% at weight 1, through column combinations the diagonal
// does not see. Reading the LUT's current values instead of level-start constants cost 34
// instead of 26 iterations (the probe then changed in ways its Jacobian did not predict).
//
// Weighting against the sky pixels. The sky rows of reference r carry weights summing to
// S_r = (its fitted solid angle) / (all references' fitted solid angle) per channel, so
// the sky term is S_r times a solid-angle mean of squared log errors. Its probe residuals
// carry weights summing to probe_weight * S_r, each sample in proportion to the ball
// pixels it averages: the probe term is probe_weight times the pixel mean of squared log
// errors over the ball. Both are relative errors of the same frame under the same
// exposure. The weight decides nothing about the parameters only the probe sees (the sun,
// the ground albedo); it trades the probe against the sky for what both see: g, the
// overcast zenith luminance and (several uncalibrated references) the exposures. Default
// 0.1: the sky's tens of thousands of pixels measure those directly, the ball's bins
// through integrals that carry the ball's own systematic errors (albedo known to a few
// percent, sheen, flare, a non-uniform ground). bench/results/probe_weight.md: with the
// mismatched ground above (with the linear start), g and the sky error (0.233% vs truth)
// do not move at 0.1; g moves by 0.007 at 1 and by 0.085 at 10 (sky error 1.19%).
#pragma once
#include <ceres/ceres.h>

#include <array>
#include <functional>
#include <atomic>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "fit_state.h"
#include "fit_term.h"
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
// The functions below take the irradiance parts of one probe block at the current point
// (ProbeCost::Parts, computed once by the caller); empty parts (outside the model's
// domain) give zeros.

// Least squares of the sun illuminance with everything else fixed, exposure
// exp(log_exposure): E_c = sum w f y / sum w f^2, y = pi R / (a k) - ambient.
LinearSun SolveLinearSun(const ProbeIrradianceParts& parts, const ProbeFrame& frame, double log_exposure);

// The sun's share of the brightest sun-facing samples for illuminance `sun` (model units).
double SunShare(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                double log_exposure);

// RMS(R - P) / RMS(R) and RMS log(P / R) over samples and channels for illuminance `sun`.
void ProbeFitErrors(const ProbeIrradianceParts& parts, const ProbeFrame& frame, const std::array<double, 3>& sun,
                    double log_exposure, double* residual, double* log_rmse);

// Builds one probed reference's residual block (MakeProbeCost with the level's weights)
// and fills its parameter blocks.
using ProbeBlockMaker =
    std::function<std::unique_ptr<ProbeCost>(const ProbeFrame&, size_t, std::vector<double*>*)>;

struct ProbeTermCounts {
  long long residuals = 0;
};

// The probe's term of a level's problem: per probed reference its block, the sun decided
// at the current point (visible: a parameter >= 0, started at the linear solution the
// first time; occluded: held at 0).
ProbeTermCounts AddProbeTerms(const ProbeBlockMaker& make_block, const std::vector<bool>& probed, bool first_level,
                              double sun_visible_threshold, std::vector<ProbeFrame>* frames,
                              std::vector<std::vector<double*>>* probe_blocks, FitState* state, ceres::Problem* problem);

// After the finest level: the sun and the ground albedo refitted on the final sky (a small
// problem of these blocks only), then each sun's visibility checked. Returns the solve's
// iterations (0 when nothing was free).
int RefitProbesOnFinalSky(const ProbeBlockMaker& make_block, const std::vector<bool>& probed, bool fit_ground,
                          double sun_visible_threshold, std::vector<ProbeFrame>* frames,
                          std::vector<std::vector<double*>>* probe_blocks, FitState* state);

// The probe as one term of the fit (fit_term.h): per probed reference its block, the sun
// decided at each level's start; after the finest level the sun and the ground albedo
// refitted on the final sky. It lists what it skipped (unprobed references, a sun it
// cannot observe, the ground albedo) and writes fit.json's `probe` and each reference's
// `sun`. References without samples get no block at all.
class ProbeTerm final : public FitTerm {
 public:
  ProbeTerm(const std::vector<Reference>& refs, const std::vector<const ProbeSamples*>& probes,
            const FitOptions& options, bool tied, double initial_ground_albedo);
  std::string name() const override { return "probe"; }
  long long AddTo(ceres::Problem& problem, FitState& state, const LevelContext& level) override;
  int AfterSolve(FitState& state, const LevelContext& level) override;
  void ReportSkips(std::vector<SkipNote>* skipped, std::vector<FitDecision>* decisions) const override;
  // Needs the references' exposures (FitResult::references[r].exposure) already set.
  void Summarise(const FitState& state, FitResult* result) const override;
  // The LUT scale gauge moved by exp(shift) onto the exposures: the sun's model units move.
  void MoveScaleGauge(double shift, FitState* state);
  bool any() const { return probed_count_ > 0; }

 private:
  std::unique_ptr<ProbeCost> MakeBlock(const ProbeFrame& f, size_t r, FitState& state, const LevelContext& level,
                                       std::vector<double*>* blocks);
  const std::vector<Reference>& refs_;
  const FitOptions& o_;
  bool tied_;
  double initial_ground_albedo_;
  std::vector<ProbeFrame> frames_;
  std::vector<bool> probed_;
  std::vector<std::vector<double*>> blocks_;
  int probed_count_ = 0, ground_facing_ = 0;
  bool fit_ground_ = false;
  std::string ground_reason_;
  std::atomic<long long> eval_ns_{0};
  long long residuals_ = 0;  // of the first level
};

}  // namespace skycal::fit
