// The robust, weighted residual shared by the sky rows and the probe (fit/src/sky_row_cost.h,
// fit/src/probe_cost.h). For an error e (natural-log units), weight w and loss scale s:
//   r = sqrt(w) * s * sign(e) * sqrt(rho((e / s)^2)),
// so that 1/2 r^2 = 1/2 w s^2 rho((e/s)^2), the robust cost, with rho the Cauchy or Huber
// loss of scale s (identity for RobustLoss::kNone).
#pragma once
#include <cmath>

#include "skycal/fit/fit_options.h"

namespace skycal::fit {

// rho(z) and rho'(z) at z = (e/s)^2.
inline void RobustRho(RobustLoss loss, double z, double* rho, double* drho) {
  switch (loss) {
    case RobustLoss::kNone: *rho = z; *drho = 1.0; return;
    case RobustLoss::kCauchy: *rho = std::log1p(z); *drho = 1.0 / (1.0 + z); return;
    case RobustLoss::kHuber:
      if (z <= 1.0) { *rho = z; *drho = 1.0; }
      else { const double r = std::sqrt(z); *rho = 2.0 * r - 1.0; *drho = 1.0 / r; }
      return;
  }
}

struct RobustResidual {
  double r = 0.0;      // the residual
  double dr_de = 0.0;  // its derivative with respect to e
};

inline RobustResidual MakeRobustResidual(RobustLoss loss, double scale, double sqrt_weight, double e) {
  const double z = (e / scale) * (e / scale);
  double rho = z, drho = 1.0;
  RobustRho(loss, z, &rho, &drho);
  const double root = std::sqrt(rho);
  RobustResidual out;
  out.r = sqrt_weight * scale * (e >= 0.0 ? root : -root);
  // dr/de = sqrt(w) rho'(z) |e| / (s sqrt(rho)), which tends to sqrt(w) as e -> 0.
  out.dr_de = z < 1e-16 ? sqrt_weight : sqrt_weight * drho * std::abs(e) / (scale * root);
  return out;
}

}  // namespace skycal::fit
