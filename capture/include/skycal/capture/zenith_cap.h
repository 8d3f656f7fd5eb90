// The sky's cap around the zenith in a polar (azimuthal equidistant) projection, for
// optical flow. A lat-long stretches the rows near the zenith into full turns: a cloud
// drifting straight across the zenith sweeps tens of pixels sideways and swirls, which no
// patch-based flow (DIS's 8-pixel patches) can follow. In the polar view the same drift is
// a translation. The view keeps the lat-long's angular resolution: one polar pixel spans
// the angle of one lat-long row (pi / (H - 1) radians), so its flow is in the same pixels.
#pragma once
#include <array>

#include "skycal/core/latlong.h"

namespace skycal::capture {

struct ZenithCap {
  // `frame_width` x `frame_height`: the lat-long frames; `radius_deg`: zenith angle of the
  // polar image's inscribed circle (its corners reach sqrt(2) times as far); `oversample`:
  // polar pixels per lat-long row's angle (1: the same pixels).
  ZenithCap(int frame_width, int frame_height, double radius_deg, double oversample = 1.0);

  int frame_width, frame_height;
  double px_per_rad;  // polar pixels per radian of zenith angle = oversample x lat-long rows per radian
  int size;           // the polar image is size x size, the zenith at its centre
  double centre;      // (size - 1) / 2

  // Polar pixel position of a unit direction (+Y up; azimuth as the lat-long's longitude:
  // 0 toward +Z, +90 deg toward +X). x grows toward +X, y toward +Z.
  std::array<double, 2> PolarPosition(const latlong::Vec3d& unit_dir) const;
  // Its inverse: the unit direction at a continuous polar position.
  latlong::Vec3d PolarDirection(double x, double y) const;
};

// The unit direction at a continuous lat-long position (x, y) in pixels (the inverse of
// latlong::PixelPosition; x need not lie in [0, W-1]: longitude is periodic).
latlong::Vec3d LatLongDirection(double x, double y, int width, int height);

}  // namespace skycal::capture
