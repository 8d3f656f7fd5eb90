#include "skycal/fit/fit_options.h"

#include <cmath>

#include "skycal/core/format_number.h"

namespace skycal::fit {

bool FitOptions::IsValid(std::string* why) const {
  // Ceres style: the field, its value, what was expected.
  auto bad = [&](const std::string& field, const std::string& value, const std::string& expected) {
    *why = "FitOptions::" + field + " = " + value + " (expected " + expected + ")";
    return false;
  };
  auto num = [](double v) { return FormatNumber(v); };
  if (!(sun_cone_deg >= 0.0 && sun_cone_deg <= 45.0)) return bad("sun_cone_deg", num(sun_cone_deg), "degrees in [0, 45]");
  if (!(clip_fraction > 0.0 && clip_fraction <= 1.0)) return bad("clip_fraction", num(clip_fraction), "a fraction in (0, 1]");
  if (!(loss_scale > 0.0 && loss_scale <= 10.0)) return bad("loss_scale", num(loss_scale), "natural-log units in (0, 10]");
  if (linear_width < 16 || linear_width > 16384 || linear_width % 2)
    return bad("linear_width", std::to_string(linear_width), "an even width in [16, 16384] pixels");
  if (max_iterations_per_level < 1 || max_iterations_per_level > 10000)
    return bad("max_iterations_per_level", std::to_string(max_iterations_per_level), "an integer in [1, 10000]");
  if (!(smoothness >= 0.0 && smoothness <= 1e6)) return bad("smoothness", num(smoothness), "a weight in [0, 1e6]");
  if (!(prior_weight >= 0.0 && prior_weight <= 1e6)) return bad("prior_weight", num(prior_weight), "a weight in [0, 1e6]");
  if (!(unseen_profile >= 0.0 && unseen_profile <= 1e6))
    return bad("unseen_profile", num(unseen_profile), "a weight in [0, 1e6]");
  std::string widths;
  for (int w : pyramid_widths) widths += (widths.empty() ? "" : ",") + std::to_string(w);
  int last = 0;
  for (int w : pyramid_widths) {
    if (w < 16 || w > 16384 || w % 2 || w <= last)
      return bad("pyramid_widths", widths, "increasing even widths in [16, 16384] pixels; " + std::to_string(w) + " is not");
    last = w;
  }
  if (sun_dir) {
    const auto& d = *sun_dir;
    if (!(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 1e-9))
      return bad("sun_dir", num(d[0]) + "," + num(d[1]) + "," + num(d[2]), "a non-zero direction");
  }
  if (!(probe_weight > 0.0 && probe_weight <= 1e3)) return bad("probe_weight", num(probe_weight), "a weight in (0, 1000]");
  if (probe_quadrature_width < 16 || probe_quadrature_width > 2048 || probe_quadrature_width % 4)
    return bad("probe_quadrature_width", std::to_string(probe_quadrature_width),
               "a lat-long width in [16, 2048] pixels, a multiple of 4");
  if (!(sun_visible_threshold >= 0.0 && sun_visible_threshold <= 1.0))
    return bad("sun_visible_threshold", num(sun_visible_threshold), "a fraction in [0, 1]");
  if (!mask_paths.empty() && !mask_path.empty())
    return bad("mask_paths", std::to_string(mask_paths.size()) + " masks", "none when mask_path = '" + mask_path + "' is set (one or the other)");
  for (const std::string& m : mask_paths)
    if (m.empty()) return bad("mask_paths", "an empty path", "one mask EXR per reference");
  if (time_of_day_h && !(*time_of_day_h >= 0.0 && *time_of_day_h < 24.0))
    return bad("time_of_day_h", num(*time_of_day_h), "hours in [0, 24)");
  return true;
}

}  // namespace skycal::fit
