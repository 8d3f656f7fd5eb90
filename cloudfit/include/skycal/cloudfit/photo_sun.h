// The sun's illuminance as a photograph records it: the disc (and the lens' blur around it)
// integrated over solid angle above the surrounding sky. It tests what a sky fit without the
// disc cannot pin: the model's sun against the photo's, both in the same units (the photo
// divided by the fit's exposure), for the clouds' direct light (`fit --clouds stats`).
#pragma once
#include <array>

#include "skycal/core/image.h"

namespace skycal::cloudfit {

struct PhotoSunOptions {
  double disc_deg = 3.0;       // deg: radius integrated around the sun direction (disc + blur)
  double ring_inner_deg = 4.0; // deg: the background ring's radii (its median, per channel,
  double ring_outer_deg = 6.0; //      is subtracted from every disc pixel)
  // Saturation by energy (PhotoSun::saturated): a disc at least this many times its ring's
  // median (a clean disc, not one veiled by cloud) ...
  double clean_peak_over_background = 100.0;
  // ... that gives the ground less direct light than this fraction of the sky's diffuse light
  // was cut off by the camera or the HDR merge: an unveiled sun gives the ground several times
  // more direct than diffuse light (our rule: 0.5 leaves a wide margin under that).
  double saturated_direct_to_diffuse = 0.5;
  bool IsValid(std::string* why) const;
};

struct PhotoSun {
  std::array<double, 3> illuminance{};  // image units x sr (lux when the image is cd/m^2)
  std::array<double, 3> background{};   // the ring's median radiance, image units
  double peak = 0.0;                    // the brightest disc pixel's largest channel
  int disc_pixels = 0;
  int peak_pixels = 0;  // disc pixels within 0.1% of the peak: > 2 means a clipped plateau
  // Green channel, image units x sr: the disc's illuminance on a horizontal surface
  // (illuminance x sin(sun elevation)) and the sky's outside the disc (radiance x cos(zenith)
  // x solid angle over every pixel above the horizon).
  double direct_horizontal = 0.0, diffuse_horizontal = 0.0;
  double clean_peak_over_background = 100.0, saturated_direct_to_diffuse = 0.5;  // the options'
  // A plateau of equal values at the image's own resolution. A sun disc (0.53 deg) smaller
  // than a pixel (0.70 deg at 512 wide) shows none even when it was clipped: see saturated().
  bool clipped() const { return peak_pixels > 2; }
  double direct_to_diffuse() const { return diffuse_horizontal > 0.0 ? direct_horizontal / diffuse_horizontal : 0.0; }
  bool clean_disc() const { return peak >= clean_peak_over_background * background[1]; }
  // The measured disc is a lower bound of the sun: a plateau, or a clean disc too weak for
  // the sky it lights (direct / diffuse below the options' fraction).
  bool saturated() const { return clipped() || (clean_disc() && direct_to_diffuse() < saturated_direct_to_diffuse); }
};

// `latlong` is a full-sphere lat-long; `sun_dir` toward the sun (unit). Throws
// skycal::Error when the disc or the ring holds no pixel (too small an image).
PhotoSun MeasurePhotoSun(const ImageRGB& latlong, const std::array<double, 3>& sun_dir, const PhotoSunOptions& o = {});

}  // namespace skycal::cloudfit
