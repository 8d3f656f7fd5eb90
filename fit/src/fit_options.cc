#include "skycal/fit/fit_options.h"

#include <cmath>

namespace skycal::fit {

bool FitOptions::IsValid(std::string* why) const {
  auto bad = [&](const std::string& w) {
    *why = w;
    return false;
  };
  if (!(sun_cone_deg >= 0.0 && sun_cone_deg <= 45.0)) return bad("--sun-cone: expected degrees in [0, 45]");
  if (!(clip_fraction > 0.0 && clip_fraction <= 1.0)) return bad("--clip-fraction: expected a value in (0, 1]");
  if (!(loss_scale > 0.0 && loss_scale <= 10.0)) return bad("--loss-scale: expected natural-log units in (0, 10]");
  if (linear_width < 16 || linear_width > 16384 || linear_width % 2) {
    return bad("--linear-width: expected an even width in [16, 16384], got " + std::to_string(linear_width));
  }
  if (max_iterations_per_level < 1 || max_iterations_per_level > 10000) return bad("--max-iterations: expected 1..10000");
  for (double w : {smoothness, prior_weight}) {
    if (!(w >= 0.0 && w <= 1e6)) return bad("--smoothness/--prior-weight: expected a weight in [0, 1e6]");
  }
  int last = 0;
  for (int w : pyramid_widths) {
    if (w < 16 || w > 16384 || w % 2 || w <= last) {
      return bad("--pyramid: expected increasing even widths in [16, 16384], got " + std::to_string(w));
    }
    last = w;
  }
  if (sun_dir) {
    const auto& d = *sun_dir;
    if (!(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 1e-9)) return bad("--sun-dir: expected a non-zero vector");
  }
  if (!(probe_weight > 0.0 && probe_weight <= 1e3)) return bad("--probe-weight: expected a weight in (0, 1000]");
  if (probe_quadrature_width < 16 || probe_quadrature_width > 2048 || probe_quadrature_width % 4) {
    return bad("--probe-quadrature: expected a lat-long width in [16, 2048], a multiple of 4");
  }
  if (!(sun_visible_threshold >= 0.0 && sun_visible_threshold <= 1.0)) {
    return bad("--sun-visible-threshold: expected a fraction in [0, 1]");
  }
  if (time_of_day_h && !(*time_of_day_h >= 0.0 && *time_of_day_h < 24.0)) return bad("--time: expected hours in [0, 24)");
  return true;
}

}  // namespace skycal::fit
