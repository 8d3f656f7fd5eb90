#include "skycal/core/latlong.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "skycal/core/error.h"
#include "skycal/core/math_constants.h"

namespace skycal::latlong {

double Latitude(int y, int height) {
  if (height <= 1) return 0.0;
  return -kPi * (static_cast<double>(y) / (height - 1) - 0.5);
}

double Longitude(int x, int width) {
  if (width <= 1) return 0.0;
  return -2.0 * kPi * (static_cast<double>(x) / (width - 1) - 0.5);
}

Vec3d PixelDirection(int x, int y, int width, int height) {
  const double lat = Latitude(y, height), lon = Longitude(x, width);
  return {std::sin(lon) * std::cos(lat), std::sin(lat), std::cos(lon) * std::cos(lat)};
}

Vec3d DirectionFromElevationAzimuthDeg(double elevation_deg, double azimuth_deg) {
  const double lat = elevation_deg * kPi / 180.0, lon = azimuth_deg * kPi / 180.0;
  return {std::sin(lon) * std::cos(lat), std::sin(lat), std::cos(lon) * std::cos(lat)};
}

double ElevationDeg(const Vec3d& d) {
  return std::atan2(d[1], std::hypot(d[0], d[2])) * 180.0 / kPi;
}

double AzimuthDeg(const Vec3d& d) { return std::atan2(d[0], d[2]) * 180.0 / kPi; }

std::array<double, 2> PixelPosition(const Vec3d& d, int width, int height) {
  const double lat = std::atan2(d[1], std::hypot(d[0], d[2]));
  const double lon = std::atan2(d[0], d[2]);
  return {(0.5 - lon / (2.0 * kPi)) * (width - 1), (0.5 - lat / kPi) * (height - 1)};
}

double PixelSolidAngle(int x, int y, int width, int height) {
  const double dlon = 2.0 * kPi / (width - 1);
  const double dlat = kPi / (height - 1);
  // Latitude band of the row: half a row either side, clipped at the poles.
  const double lat = Latitude(y, height);
  const double top = std::min(lat + 0.5 * dlat, kPi / 2);
  const double bottom = std::max(lat - 0.5 * dlat, -kPi / 2);
  const double band = std::sin(top) - std::sin(bottom);
  const double column = (x == 0 || x == width - 1) ? 0.5 * dlon : dlon;
  return band * column;
}

Vec3d Normalized(const Vec3d& v, const char* what) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!std::isfinite(n) || n < 1e-12) {
    throw Error(std::string(what) + ": expected a finite, non-zero direction vector");
  }
  return {v[0] / n, v[1] / n, v[2] / n};
}

}  // namespace skycal::latlong
