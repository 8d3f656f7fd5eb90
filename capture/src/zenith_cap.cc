#include "skycal/capture/zenith_cap.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/math_constants.h"

namespace skycal::capture {

ZenithCap::ZenithCap(int w, int h, double radius_deg, double oversample)
    : frame_width(w), frame_height(h), px_per_rad(oversample * (h - 1) / kPi) {
  const int half = static_cast<int>(std::ceil(radius_deg * kPi / 180.0 * px_per_rad));
  size = 2 * half + 1;
  centre = half;
}

std::array<double, 2> ZenithCap::PolarPosition(const latlong::Vec3d& d) const {
  const double horizontal = std::hypot(d[0], d[2]);
  const double zenith_angle = std::atan2(horizontal, d[1]);
  if (horizontal <= 0.0) return {centre, centre};
  const double r = zenith_angle * px_per_rad / horizontal;
  return {centre + r * d[0], centre + r * d[2]};
}

latlong::Vec3d ZenithCap::PolarDirection(double x, double y) const {
  const double dx = x - centre, dy = y - centre, r = std::hypot(dx, dy);
  if (r <= 0.0) return {0.0, 1.0, 0.0};
  const double zenith_angle = r / px_per_rad, s = std::sin(zenith_angle) / r;
  return {s * dx, std::cos(zenith_angle), s * dy};
}

latlong::Vec3d LatLongDirection(double x, double y, int width, int height) {
  return latlong::Direction(latlong::Latitude(y, height), latlong::Longitude(x, width));
}

}  // namespace skycal::capture
