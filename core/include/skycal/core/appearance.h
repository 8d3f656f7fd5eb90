// How far the game's image of a sky is from the photograph it was calibrated on, in the two
// numbers a lighting artist can act on (docs/fitting.md "Judging a calibration"):
//
//   per-pixel log RMSE  the solid-angle-weighted RMS of ln(game / photo) over the sky pixels
//                       and the three channels: it counts a cloud drawn one degree away from
//                       the photo's as wrong twice (where it is, and where it is not);
//   appearance error    independent of where the clouds sit: in bands of elevation (10 deg by
//                       default) the 10/50/90% quantiles of ln(luminance) and the medians of
//                       ln(R/G) and ln(B/G), each a solid-angle-weighted statistic of the band;
//                       the RMS of the game-minus-photo differences over every band both
//                       images cover and those five statistics.
//
// Both take lat-long images of one size (the project's convention, core/latlong.h), luminance
// by the one Rec.709 weighting (core/luminance.h). Only pixels at or above
// Options::min_elevation_deg and, where a sky weight is given, with weight > 0.5 count.
// Values at or below Options::floor_fraction times the photo's median sky luminance are
// clamped to it before the logarithm (a black sensor pixel or a zero render has no logarithm;
// the floor keeps them finite and heavily penalised without one pixel ruling the RMS).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::appearance {

struct Options {
  double band_deg = 10.0;           // elevation band width, degrees, in (0, 90]
  double min_elevation_deg = 0.0;   // pixels below are left out (ground, horizon), in [-90, 90)
  double floor_fraction = 1e-4;     // log floor as a fraction of the photo's median, in (0, 1)
  int min_band_pixels = 16;         // a band with fewer sky pixels in either image is skipped
  // "" when valid, else "Options::<field> = <value>: <expectation>".
  std::string IsValid() const;
};

// The five statistics of one elevation band; natural logarithms.
struct BandStats {
  double elevation_lo_deg = 0.0, elevation_hi_deg = 0.0;
  int pixels = 0;
  double ln_y_q10 = 0.0, ln_y_q50 = 0.0, ln_y_q90 = 0.0;  // quantiles of ln(luminance)
  double ln_r_over_g = 0.0, ln_b_over_g = 0.0;             // medians of the log ratios
};

struct Comparison {
  int sky_pixels = 0;             // pixels that counted
  double per_pixel_log_rmse = 0.0;
  double appearance_error = 0.0;  // RMS over bands x 5 statistics
  int bands_compared = 0;
  std::vector<BandStats> photo, game;  // the bands compared, low to high
};

// The bands of one image (what both comparisons are made of). `sky` is empty (every pixel at
// or above the minimum elevation counts) or one weight per pixel. `floor` is the luminance
// clamp (absolute units of the image).
std::vector<BandStats> BandStatistics(const ImageRGB& image, const std::vector<float>& sky,
                                      double floor, const Options& options);

// Throws skycal::Error naming `photo_name` / `game_name` when sizes differ, the sky weights do
// not match the size, the options are invalid, or no pixel counts.
Comparison Compare(const ImageRGB& photo, const ImageRGB& game, const std::vector<float>& sky,
                   const Options& options, const std::string& photo_name = "photo",
                   const std::string& game_name = "game");

// The sky weights less the pixels within `cone_deg` of the unit vector `sun` (their weight 0):
// calibrate judges the game's image without the sun's disc (docs/calibrate.md), and `skycal
// compare --sun-cone` repeats it. `sky` empty: every pixel weighs 1 first.
std::vector<float> WithoutSunCone(std::vector<float> sky, int width, int height, const std::array<double, 3>& sun,
                                  double cone_deg);

// Where the clouds are, when both images carry their clouds' transmittance T (a synthetic
// photo's truth, the game's render): over the pixels Compare counts, solid-angle weighted, the
// RMS of the opacity (1 - T) difference and the IoU of the cloud masks (T < 0.5; none when
// neither image has cloud there). The appearance error does not say where the clouds sit and
// the per-pixel error mixes it with their light: this is the shapes alone.
struct CloudLayerAgreement {
  int pixels = 0;
  double opacity_rms = 0.0;
  std::optional<double> iou;
};
// Throws skycal::Error naming `game_name` when the sizes differ from width x height.
CloudLayerAgreement CompareCloudLayers(const std::vector<float>& photo_transmittance,
                                       const std::vector<float>& game_transmittance, int width, int height,
                                       const std::vector<float>& sky, const Options& options,
                                       const std::string& game_name = "game");

}  // namespace skycal::appearance
