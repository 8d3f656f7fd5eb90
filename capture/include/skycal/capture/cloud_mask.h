// Per-pixel cloud probability of a lat-long sky from its colour: clear sky is blue, cloud
// is white or grey, so the red/blue ratio rises over a cloud. The expectation for a clear
// sky comes from the sky model at the frame's sun (the caller renders it, e.g. the bundled
// preset), which also carries the whitening toward the horizon and around the sun; the
// photo's own clear-sky colour offset is estimated per frame.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::capture {

struct CloudMaskOptions {
  // Probability rises from 0 to 1 as the excess of ln(R/B) over the clear-sky expectation
  // goes from `excess_clear` to `excess_cloud` (natural-log units; a white cloud in a blue
  // sky is ~0.8 above it).
  double excess_clear = 0.25;
  double excess_cloud = 0.55;
  // Forward-scattering haze whitens the sky around the sun beyond what the model shows:
  // the thresholds rise by `sun_boost` at the sun, falling linearly to 0 at `sun_radius_deg`.
  double sun_radius_deg = 20.0;
  double sun_boost = 0.35;
  // Quantile of the excess (over sky pixels away from the sun) taken as the frame's clear-sky
  // colour offset, clamped to +-max_offset (a colour-balance difference, not cloud).
  double offset_quantile = 0.2;
  double max_offset = 0.35;
  bool IsValid(std::string* why) const;
};

struct CloudMask {
  std::vector<float> probability;  // per pixel in [0, 1]; 0 below the horizon and where undefined
  double clear_offset = 0.0;       // the estimated colour offset (ln R/B)
  long long cloudy_pixels = 0;     // probability >= 0.5, above the horizon
};

// `frame` and `clear_sky` are lat-longs of the same size (project convention). Throws
// skycal::Error on a size mismatch or invalid options.
CloudMask EstimateCloudProbability(const ImageRGB& frame, const ImageRGB& clear_sky,
                                   const std::optional<std::array<double, 3>>& sun_dir, const CloudMaskOptions& options);

}  // namespace skycal::capture
