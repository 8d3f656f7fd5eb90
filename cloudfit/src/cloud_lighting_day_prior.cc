#include "cloud_lighting_day_prior.h"

#include <cmath>

#include "skycal/core/error.h"

namespace skycal::cloudfit {

DaySmoothnessPrior::DaySmoothnessPrior(double lambda, double t_before, double t, double t_after,
                                       const CloudLighting& scale) {
  if (!(t_before < t && t < t_after)) throw Error("cloud lighting day prior: times not strictly increasing");
  const double w = std::sqrt(lambda), span = 2.0 / (t_after - t_before);
  const double a = 1.0 / (t - t_before), b = 1.0 / (t_after - t);
  c_ = {w * span * a, -w * span * (a + b), w * span * b};
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    if (!(scale[k] > 0.0)) throw Error("cloud lighting day prior: a parameter scale is not positive");
    inv_scale_[k] = 1.0 / scale[k];
  }
}

bool DaySmoothnessPrior::Evaluate(double const* const* p, double* residuals, double** jacobians) const {
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    residuals[k] = (c_[0] * p[0][k] + c_[1] * p[1][k] + c_[2] * p[2][k]) * inv_scale_[k];
  }
  if (!jacobians) return true;
  for (int b = 0; b < 3; ++b) {
    if (!jacobians[b]) continue;
    for (int i = 0; i < kCloudLightingParameters; ++i) {
      for (int k = 0; k < kCloudLightingParameters; ++k) {
        jacobians[b][i * kCloudLightingParameters + k] = i == k ? c_[b] * inv_scale_[k] : 0.0;
      }
    }
  }
  return true;
}

}  // namespace skycal::cloudfit
