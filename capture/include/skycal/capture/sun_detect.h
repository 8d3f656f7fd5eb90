// Finding the sun in a lat-long frame: the centroid of the brightest region of the upper
// hemisphere, with clipping detected.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"
#include "skycal/core/luminance.h"

namespace skycal::capture {

struct SunDetection {
  std::array<double, 3> direction{};  // unit vector toward the region's centroid
  double peak_luminance = 0.0;        // cd/m^2 (Rec.709 luminance of the brightest pixel)
  double contrast = 0.0;              // peak / median luminance of the upper hemisphere
  int region_pixels = 0;              // pixels in the region (>= half the peak, within 5 deg)
  bool clipped = false;               // the peak is a plateau of equal values (sensor/encoder clamp)
};

// Returns nothing (and says why in *why) when the upper hemisphere has no distinct sun:
// peak under `min_contrast` times the median, or no finite positive pixel.
std::optional<SunDetection> DetectSun(const ImageRGB& latlong, std::string* why, double min_contrast = 20.0);

// Where the sky is brightest, as a deck hiding the sun shows it: the peak of the sky pixels'
// luminance (`sky`: one weight per pixel, >= 0.5 sky) above `min_elevation_deg`, smoothed by a
// Gaussian of `sigma_deg` (normalised over the sky pixels, so the mask's edges do not darken
// the sky beside them; wrapping in longitude), to the pixel. Only a sky pixel at least half of
// whose neighbourhood is sky qualifies; nothing when none does. Unit vector.
std::optional<std::array<double, 3>> BrightestSkyPatch(const ImageRGB& latlong, const std::vector<float>& sky,
                                                       double sigma_deg, double min_elevation_deg);

// Rec.709 / sRGB luminance weights (ITU-R BT.709).
inline double Luminance(const float* rgb) { return Rec709Luminance<double>(rgb[0], rgb[1], rgb[2]); }

}  // namespace skycal::capture
