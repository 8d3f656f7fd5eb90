// The unknown-shapes cloud objective (cloud_stats.h) as Ceres pieces: a cost function with
// central-difference derivatives through the cloud renderer, and a FitTerm that adds it to
// the joint fit (fit_term.h).
//
// Why central differences, not Jets: the statistics are quantiles over the pixels of a
// whole render, with bin membership by opacity class; the march takes data-dependent
// decisions (cheap steps, opacity stop) that depend on the extinction. A Jet through the CPU
// reference gives the derivative along one frozen branch path, blind to pixels moving
// between opacity classes and to decisions that flip; a finite step of 0.2% of each
// parameter's range sees both, and its values come from the Vulkan render the game runs
// (the same backend as every other evaluation). Cost: 2 renders per free parameter per
// Jacobian (each of them options.model_renders renders), measured in
// bench/results/cloud_stats_seed_pairs.md.
#pragma once
#include <memory>
#include <vector>

#include <ceres/cost_function.h>

#include "fit_term.h"
#include "skycal/cloudfit/cloud_stats_objective.h"

namespace skycal::cloudfit {

class CloudStatsCost final : public ceres::CostFunction {
 public:
  explicit CloudStatsCost(const CloudStatsObjective* objective);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const CloudStatsObjective* objective_;
  mutable std::vector<double> last_x_, last_residuals_, last_jacobian_;
};

// The term for FitSkyWithTerms: on the finest level it adds one parameter block (the free
// lighting fields, scaled) and the statistics' residuals; the caller reads the fitted
// parameters from result() after the fit. The references and the scene must outlive it.
class CloudStatsTerm final : public fit::FitTerm {
 public:
  CloudStatsTerm(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                 clouds::CloudRenderer& renderer, const CloudStatsOptions& options);
  std::string name() const override { return "cloud_stats"; }
  long long AddTo(ceres::Problem& problem, fit::FitState& state, const fit::LevelContext& level) override;
  void ReportSkips(std::vector<fit::SkipNote>* skipped, std::vector<fit::FitDecision>* decisions) const override;
  // The fitted parameters and statistics at the block's current value.
  CloudStatsResult result() const;

 private:
  CloudStatsObjective objective_;
  std::vector<double> x_;
  CloudStatsOptions options_;
  clouds::CloudParams initial_;
};

// Builds the term a caller plugs into FitSkyWithTerms (the merger's `skycal fit --clouds`).
std::unique_ptr<CloudStatsTerm> MakeCloudStatsTerm(const std::vector<CloudStatsReference>& refs,
                                                   const CloudStatsScene& scene, clouds::CloudRenderer& renderer,
                                                   const CloudStatsOptions& options);

// Every lighting field of CloudParameterSpecs with its initial and fitted value, held or
// not and why (shared by FitCloudStats and the term).
std::vector<CloudStatsParameter> DescribeCloudStatsParameters(const clouds::CloudParams& initial,
                                                              const clouds::CloudParams& fitted,
                                                              const std::vector<std::string>& fitted_names);

}  // namespace skycal::cloudfit
