// How much of the sky behind a photo's clouds they hide: per-pixel cloud opacity, by unmixing
// each pixel's colour into the clear sky behind it and the clouds' own light.
//
// The game composites its clouds as L = T S + C (clouds/composite.h: the sky times the
// clouds' transmittance plus their in-scattered radiance). With S the clear sky at the pixel
// (a fitted sky, in the frame's units) and C = b w, w the clouds' colour, the three channels
// give T and b by least squares (T in [0, 1], b >= 0); the opacity is 1 - T. The clouds'
// colour is the median chromaticity of the pixels the colour ramp (cloud_mask.h) is surest
// are cloud. Where the sky's colour and the clouds' are too alike to separate (a white
// horizon, the glare by the sun), the ramp's probability stands in.
//
// Why not the ramp's probability itself: it says where cloud is, not how much. A thin cloud
// lit by the sun whitens the sky as much as a thick one, and a far, hazy one barely changes
// its colour; on game-rendered skies with a known transmittance the unmixed opacity is
// nearer the truth (bench/results/weather_inversion.md, "The photo's opacity"). Like the
// probability it cannot tell a grey cloud lit by the blue sky from a thin white one over it.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::capture {

struct CloudOpacityOptions {
  double sure_cloud = 0.9;        // probability at and above which a pixel shows the clouds' colour
  int min_cloud_pixels = 16;      // fewer sure pixels: the clouds' colour is taken as grey
  // sin of the angle between the sky's and the clouds' RGB below which a pixel cannot be
  // unmixed (the 2x2 system's determinant over |S|^2 |w|^2 is its square).
  double min_separation = 0.05;
  bool IsValid(std::string* why) const;
};

struct CloudOpacity {
  std::vector<float> opacity;            // per pixel in [0, 1]; 0 outside the sky and below the horizon
  std::array<double, 3> cloud_colour{};  // w, chromaticity (sums to 1)
  long long colour_pixels = 0;           // the sure cloud pixels w is the median of (0: grey)
  long long unmixed = 0;                 // sky pixels unmixed
  long long from_probability = 0;        // sky pixels the probability stood in for
};

// `frame` and `clear_sky` (the clear sky in the frame's units: a fitted sky times its
// exposure) are lat-longs of the same size; `probability` (cloud_mask.h) and `sky` (>= 0.5
// sky; empty: every pixel above the horizon) one value per pixel. Throws skycal::Error naming
// the sizes when they differ, or the option when invalid.
CloudOpacity EstimateCloudOpacity(const ImageRGB& frame, const ImageRGB& clear_sky, const std::vector<float>& probability,
                                  const std::vector<float>& sky, const CloudOpacityOptions& options);

}  // namespace skycal::capture
