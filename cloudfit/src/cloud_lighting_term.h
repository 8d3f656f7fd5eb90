// The known-shapes cloud term as a FitTerm (fit/src/fit_term.h): it joins the finest level
// of the sky fit's Ceres problem with one parameter block (the 14 lighting parameters) and
// the sampled cloud pixels' residuals. The sky under the clouds and the light the clouds
// receive (sun, SH-9 ambient, ground) come from the sky state when the level starts. In
// that joint polish the cloud block is linearised at the level's start (one Jet march per
// sample, no render per iteration: CloudSampleModel::FreezeJacobianAt);
// FitSkyAndClouds then finishes the block through the renderer with exact Jacobians on
// the final sky, after the fit's gauge move (the sun's illuminance is not scaled with the LUT, so
// the clouds' sun-to-ambient balance is only final after it). Coarse levels: no cloud
// residuals (the clouds' pixels are fitted at the reference's own size).
#pragma once
#include <string>
#include <vector>

#include "cloud_lighting_solve.h"
#include "fit_term.h"

namespace skycal::cloudfit {

class CloudLightingTerm final : public fit::FitTerm {
 public:
  // `model` (not owned) holds the samples of reference 0.
  CloudLightingTerm(CloudSampleModel* model, const CloudLighting& initial, const CloudLightingOptions& options);
  std::string name() const override { return "cloud lighting (known shapes)"; }
  long long AddTo(ceres::Problem& problem, fit::FitState& state, const fit::LevelContext& level) override;
  int AfterSolve(fit::FitState& state, const fit::LevelContext& level) override;
  void ReportSkips(std::vector<fit::SkipNote>* skipped, std::vector<fit::FitDecision>* decisions) const override;

  CloudLighting& lighting() { return theta_; }
  const CloudLighting& initial() const { return initial_; }
  const Conditioning& conditioning() const { return conditioning_; }
  // The final exact-Jacobian solve's summary (run by FitSkyAndClouds).
  void Finish(const ceres::Solver::Summary& s);
  int iterations() const { return iterations_; }
  double conditioning_time_s() const { return conditioning_time_s_; }
  std::string termination() const { return termination_; }

 private:
  void RefreshSky(const fit::FitState& state, const fit::Reference& ref);

  CloudSampleModel* model_;
  CloudLighting initial_, theta_;
  CloudLightingOptions options_;
  Conditioning conditioning_;
  bool conditioned_ = false;
  int iterations_ = 0;
  double conditioning_time_s_ = 0.0;
  std::string termination_ = "not run";
};

}  // namespace skycal::cloudfit
