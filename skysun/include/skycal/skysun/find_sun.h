// The sun of a photograph wherever it is: its disc when one is seen (capture::DetectSun),
// else placed from the sky's luminance pattern (sky_sun.h) over the automatic sky mask
// (capture::EstimateSkyMask: buildings, trees and terrain left out), with an uncertainty.
#pragma once
#include <array>
#include <optional>
#include <string>

#include "skycal/core/image.h"
#include "skycal/skysun/sky_sun.h"

namespace skycal::skysun {

struct FoundSun {
  std::array<double, 3> direction{};  // unit vector toward the sun (core/latlong.h)
  std::string source;                 // "disc" or "sky"
  double uncertainty_deg = 0.0;       // "sky": SkySunEstimate::uncertainty_deg; "disc": 0
  std::string disc_refusal;           // "sky": why no disc was taken (DetectSun's reason)
  // The disc's measurements ("disc") or the sky fit ("sky").
  double disc_contrast = 0.0, disc_peak_luminance = 0.0;
  int disc_region_pixels = 0;
  bool disc_clipped = false;
  std::optional<SkySunEstimate> sky;
};

// The disc first (its peak at least `min_disc_contrast` times the median sky), else the sky
// pattern (refused above SkySunOptions::max_uncertainty_deg). Nothing when neither places
// the sun, with both reasons in *why ("no sun disc (...); the sky does not place the sun: ...").
std::optional<FoundSun> FindSun(const ImageRGB& latlong, double min_disc_contrast, const SkySunOptions& options,
                                std::string* why);

}  // namespace skycal::skysun
