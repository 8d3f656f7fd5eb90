// The sky model's parameters (SkyParams of render/model/sky_model.glsl.h) from a preset:
// every field the preset fixes, in the parameters' scalar type (double for the renderers,
// any scalar of a SkyModel instantiation). The sun's direction, its disc radiance and the
// ground radiance depend on the render request and are left zero (ResolveSkyParams in
// render/src/resolved_sky.cc sets them); a fit overrides the fields it fits.
#pragma once
#include <cmath>

#include "skycal/core/math_constants.h"
#include "skycal/render/preset.h"

namespace skycal::render {

template <typename Params>
Params SkyParamsFromPreset(const Preset& preset) {
  using S = decltype(Params::haziness_g);
  Params p{};
  p.haziness_g = S(preset.haziness_g);
  p.isotropic_weight = S(preset.variant == ModelVariant::kFfxvIso ? 1.0 : 0.0);
  p.overcast_weight = S(preset.overcast_weight);
  p.overcast_zenith = S(preset.overcast_zenith_cd_m2);
  const double radius = preset.sun_angular_radius_deg * kPi / 180.0;  // R, radians
  p.sun_radius = S(radius);
  p.sun_one_minus_cos_radius = S(2.0 * std::sin(0.5 * radius) * std::sin(0.5 * radius));  // 1 - cos R, no cancellation
  p.sun_limb_u = S(preset.sun_limb_darkening);
  p.lut_one_minus_cos_theta_max = S(LutOneMinusCosThetaMax(preset.luts.grid));
  p.lut_n_theta = preset.luts.grid.n_theta;
  p.lut_n_gamma = preset.luts.grid.n_gamma;
  return p;
}

}  // namespace skycal::render
