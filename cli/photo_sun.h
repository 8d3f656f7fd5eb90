// The sun's illuminance as a photograph records it: the disc (and the lens' blur around it)
// integrated over solid angle above the surrounding sky. It tests what a sky fit without the
// disc cannot pin: the model's sun against the photo's, both in the same units (the photo
// divided by the fit's exposure), for the clouds' direct light (`fit --clouds stats`).
#pragma once
#include <array>

#include "skycal/core/image.h"

namespace skycal::cli {

struct PhotoSunOptions {
  double disc_deg = 3.0;       // deg: radius integrated around the sun direction (disc + blur)
  double ring_inner_deg = 4.0; // deg: the background ring's radii (its median, per channel,
  double ring_outer_deg = 6.0; //      is subtracted from every disc pixel)
  bool IsValid(std::string* why) const;
};

struct PhotoSun {
  std::array<double, 3> illuminance{};  // image units x sr (lux when the image is cd/m^2)
  std::array<double, 3> background{};   // the ring's median radiance, image units
  double peak = 0.0;                    // the brightest disc pixel's largest channel
  int disc_pixels = 0;
  int peak_pixels = 0;  // disc pixels within 0.1% of the peak: > 2 means a clipped plateau
  bool clipped() const { return peak_pixels > 2; }
};

// `latlong` is a full-sphere lat-long; `sun_dir` toward the sun (unit). Throws
// skycal::Error when the disc or the ring holds no pixel (too small an image).
PhotoSun MeasurePhotoSun(const ImageRGB& latlong, const std::array<double, 3>& sun_dir, const PhotoSunOptions& o = {});

}  // namespace skycal::cli
