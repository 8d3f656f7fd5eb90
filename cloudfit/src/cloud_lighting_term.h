// The known-shapes cloud term as a FitTerm (fit/src/fit_term.h): it joins the finest level
// of the sky fit's Ceres problem with one parameter block (the 14 lighting parameters) and
// the sampled cloud pixels' residuals. The sky under the clouds and the light the clouds
// receive (sun, SH-9 ambient, ground) come from the sky state when the level starts and
// again after its solve, when the term finishes its block alone to the recovery
// tolerances with the sky held (the joint solve stops at the sky polish's looser
// tolerance). Coarse levels: no cloud residuals (the clouds' pixels are fitted at the
// reference's own size, the sky's coarse levels only place the LUT).
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

  const CloudLighting& lighting() const { return theta_; }
  const CloudLighting& initial() const { return initial_; }
  const Conditioning& conditioning() const { return conditioning_; }
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
