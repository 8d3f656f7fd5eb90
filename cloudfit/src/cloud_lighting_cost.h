// The cloud-lighting residuals as one Ceres cost function: per sampled cloud pixel and
// channel, sqrt(weight / 3) x (log composite - log reference), over one parameter block
// of the 15 lighting parameters (CloudLightingNames order). Log residuals: the composite
// spans orders of magnitude between sunlit tops and dark bases, and a relative error is
// what the eye and the sky fit (log rows) measure. Values and Jacobian from
// CloudSampleModel (the render and the Jet march). Kept out of public headers (Ceres).
#pragma once
#include <ceres/ceres.h>

#include <vector>

#include "cloud_lighting_samples.h"

namespace skycal::cloudfit {

class CloudLightingCost final : public ceres::CostFunction {
 public:
  // `model` is not owned and must outlive the cost function.
  explicit CloudLightingCost(CloudSampleModel* model);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  CloudSampleModel* model_;
  std::vector<double> scale_, log_reference_;  // per residual
};

}  // namespace skycal::cloudfit
