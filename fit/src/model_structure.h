// The pieces of the sky model's linear structure that the fit's three readers of it share
// (LinearSky, the linear stage's solves; SkyRowCost, the Ceres sky rows; ProbeCost, the
// probe's irradiance), taken from the shared model source (render/model/sky_model.glsl.h)
// or stated once here where the source has them inline:
//   M = (1 - w_o) sum_t LUT_t phase_t(mu) + w_o L_z OvercastShape(elevation),
//   phase_R(mu), phase_M(mu, g) from the source, phase_I = 1 / (4 pi).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "skycal/render/sky_model.h"

namespace skycal::fit {

// A LUT source that reads nothing: the shared model for its coordinate and phase
// functions only.
struct NoLut {
  template <typename S>
  glsl::Vec3<S> texel(int, int, int) const {
    return glsl::Vec3<S>(S(0.0));
  }
};
template <typename S>
using StructureModel = model::SkyModel<S, NoLut>;

// The isotropic table's phase: uniform over the sphere (sky_model.glsl.h, LutI / 4 pi).
constexpr double kIsotropicPhase = 1.0 / (4.0 * M_PI);

// The CIE standard overcast shape (1 + 2 sin(elevation)) / 3 of a view with height
// view_y = sin(elevation), 0 below the horizon's level (sky_model.glsl.h).
inline double OvercastShape(double view_y) { return (1.0 + 2.0 * std::max(view_y, 0.0)) / 3.0; }

// 1 - cos(view, sun) as the shared source evaluates it: |v - s|^2 / 2, without the
// cancellation of 1 - dot near the sun.
inline double OneMinusMu(const std::array<double, 3>& v, const std::array<double, 3>& s) {
  const double d[3] = {v[0] - s[0], v[1] - s[1], v[2] - s[2]};
  return 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

// The Cornette-Shanks phase and its derivative in g, from the shared source instantiated
// with a one-dimensional ceres::Jet (model_structure.cc).
struct MiePhase {
  double value = 0.0, d_dg = 0.0;
};
MiePhase MiePhaseWithDerivative(double mu, double one_minus_mu, double g);

}  // namespace skycal::fit
