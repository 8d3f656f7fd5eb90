// The smoothness prior of a day's cloud lighting over time of day: for each reference
// between two others (in time order) and each lighting parameter, the second divided
// difference of the parameter's relative value over the three references' times,
//   r = sqrt(lambda) x 2 / (t+ - t-) x [(x+ - x) / (t+ - t) - (x - x-) / (t - t-)],
// x = theta / scale (scale: the start's |theta|, or 1% of the parameter's range near 0, the
// conditioning's unit), t in hours: r is a curvature in relative units per h^2. A lighting
// that changes linearly over the day costs nothing; one that bends by 1% per h^2 costs
// lambda x 1e-4 / 2 per parameter, against the cloud pixels' cost of ~(log residual)^2 / 2
// per reference (their weights sum to 1). The LUT rows' prior along sun zenith is the same
// kind (fit/src/sky_terms.cc, --smoothness). Linear in the parameters: analytic Jacobian.
#pragma once
#include <ceres/ceres.h>

#include "skycal/cloudfit/cloud_lighting_params.h"

namespace skycal::cloudfit {

class DaySmoothnessPrior final : public ceres::SizedCostFunction<kCloudLightingParameters, kCloudLightingParameters,
                                                                 kCloudLightingParameters, kCloudLightingParameters> {
 public:
  // Times in hours, strictly increasing; `scale` per parameter (> 0).
  DaySmoothnessPrior(double lambda, double t_before, double t, double t_after, const CloudLighting& scale);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  // The three coefficients of (x-, x, x+) in the divided difference (1/h^2), times sqrt(lambda).
  const std::array<double, 3>& coefficients() const { return c_; }

 private:
  std::array<double, 3> c_{};
  CloudLighting inv_scale_{};
};

}  // namespace skycal::cloudfit
