#include "cloud_lighting_cost.h"

#include <cmath>

namespace skycal::cloudfit {

CloudLightingCost::CloudLightingCost(CloudSampleModel* model) : model_(model) {
  set_num_residuals(static_cast<int>(model_->residuals()));
  mutable_parameter_block_sizes()->push_back(kCloudLightingParameters);
  for (const CloudSample& s : model_->samples()) {
    for (int c = 0; c < 3; ++c) {
      scale_.push_back(std::sqrt(s.weight / 3.0));
      log_reference_.push_back(std::log(s.reference[c]));
    }
  }
}

bool CloudLightingCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  double* jac = jacobians ? jacobians[0] : nullptr;
  if (!model_->Evaluate(parameters[0], residuals, jac)) return false;
  for (size_t i = 0; i < scale_.size(); ++i) {
    residuals[i] = scale_[i] * (residuals[i] - log_reference_[i]);
    if (jac) {
      for (int j = 0; j < kCloudLightingParameters; ++j) jac[i * kCloudLightingParameters + j] *= scale_[i];
    }
  }
  return true;
}

}  // namespace skycal::cloudfit
