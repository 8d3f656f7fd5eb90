// The unknown-shapes cloud objective as a plain function of the fitted parameters:
// x (the free lighting fields, each divided by its scale) -> renders -> statistics ->
// residuals. The Ceres cost (cloud_stats_term.h) and FitCloudStats share it.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "skycal/cloudfit/cloud_stats.h"

namespace skycal::cloudfit {

class CovarianceWhitener;  // shape_noise_covariance.h

class CloudStatsObjective {
 public:
  // Throws skycal::Error naming an unknown or non-lighting field in options.fitted, a
  // reference whose sizes disagree, or a reference with no bin above options.min_bin_sr.
  CloudStatsObjective(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                      clouds::CloudRenderer& renderer, const CloudStatsOptions& options);

  int num_parameters() const { return static_cast<int>(free_.size()); }
  int num_residuals() const { return num_residuals_; }
  // The starting point, bounds and scale of each free parameter (x = value / scale).
  std::vector<double> InitialX() const;
  double LowerX(int i) const { return free_[i].min / free_[i].scale; }
  double UpperX(int i) const { return free_[i].max / free_[i].scale; }
  const std::string& Name(int i) const { return free_[i].name; }
  double Scale(int i) const { return free_[i].scale; }
  // Central-difference step in x for parameter i.
  double StepX(int i, double x) const;

  clouds::CloudParams ParamsAt(const double* x) const;
  // Renders every reference at x; fills `residuals` (num_residuals()) and, when given, the
  // model's statistics per reference. Returns false when a render fails (Ceres then tries
  // a shorter step).
  bool Evaluate(const double* x, double* residuals, std::vector<CloudStatistics>* stats = nullptr) const;

  // The statistics the residuals compare, unweighted, in the residual layout (per reference:
  // active bins x channel x quantile in log radiance, then the thick shares); NaN where the
  // render leaves a bin empty. ModelStatistics pools the model's renders at x; DrawStatistics
  // is one shape draw d (CloudStatsScene::shape_draw_maps); ReferenceStatistics the references'.
  bool ModelStatistics(const double* x, double* values, std::vector<CloudStatistics>* stats = nullptr) const;
  bool DrawStatistics(const double* x, int draw, double* values) const;
  const std::vector<double>& ReferenceStatistics() const { return ref_values_; }
  // Residual k = weight(k) (model - reference); weights from the bins' shares, or 1 / sd of
  // the shape noise once SetNoiseSd (or options.noise_draws) whitened them.
  double Weight(int k) const { return weights_[k]; }
  // Per statistic shape-noise sd (num_residuals() values, each floored at
  // options.noise_sd_floor); the residuals become (model - reference) / (sd sqrt(1 + 1/M)).
  void SetNoiseSd(const std::vector<double>& sd);
  // The sd over `draws` shape draws at x (a statistic some draw leaves empty gets 1e3 x the
  // floor: it then counts for nothing). Throws when a render fails.
  std::vector<double> EstimateNoiseSd(const double* x, int draws) const;
  const std::vector<double>& noise_sd() const { return noise_sd_; }
  // The statistics of draws 0..draws-1 at x ([draw][statistic], NaN where a draw leaves a
  // bin empty; throws when a render fails), and their sd per statistic as EstimateNoiseSd.
  std::vector<std::vector<double>> NoiseDraws(const double* x, int draws) const;
  std::vector<double> NoiseSd(const std::vector<std::vector<double>>& draws) const;
  // The full GLS (options.noise_covariance "full"): Σ, the covariance of the statistics over
  // `draws`, shrunk toward its diagonal by `shrinkage` (< 0: estimated, Schäfer-Strimmer;
  // shape_noise_covariance.h), each variance floored at options.noise_sd_floor²; a statistic
  // some draw leaves empty is uncorrelated with variance (1e3 floor)². From then on Evaluate
  // returns r' = L^-1 (model - reference) with Σ (1 + 1/M) = L Lᵀ. Returns the λ used.
  double SetNoiseCovariance(const std::vector<std::vector<double>>& draws, double shrinkage);
  bool full_whitening() const { return whitener_ != nullptr; }
  double noise_shrinkage() const { return shrinkage_; }

  const std::vector<CloudStatistics>& reference_stats() const { return ref_stats_; }
  long long renders() const { return renders_; }

 private:
  struct Free {
    std::string name;
    double* (*field)(clouds::CloudParams&);
    double min, max, scale;
  };
  // A copy (a few images): a caller's temporary {ref} would otherwise dangle.
  std::vector<CloudStatsReference> refs_;
  CloudStatsScene scene_;
  clouds::CloudRenderer& renderer_;
  CloudStatsOptions options_;
  std::vector<Free> free_;
  std::vector<CloudStatistics> ref_stats_;
  std::vector<std::vector<int>> active_bins_;  // per reference: bins with enough reference weight
  std::vector<std::vector<int>> active_shares_;  // per reference: (sun, elevation) bins with a thick-share residual
  int num_residuals_ = 0;
  std::vector<double> ref_values_, weights_, noise_sd_;
  std::vector<int> offsets_;  // per reference: its first residual
  std::shared_ptr<const CovarianceWhitener> whitener_;  // the full GLS's L^-1 (null: diagonal weights)
  double shrinkage_ = 0.0;
  static constexpr double kAbsentSdFactor = 1e3;  // x noise_sd_floor: a statistic some draw leaves empty
  mutable long long renders_ = 0;
  // Flattens statistics of reference r pooled over `images` renders into the residual layout.
  void Flatten(int r, const CloudStatistics& s, int images, double* values) const;
};

}  // namespace skycal::cloudfit
