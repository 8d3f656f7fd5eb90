#include "skycal/core/latlong.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "skycal/core/error.h"
#include "skycal/core/math_constants.h"
#include "../../render/model/glsl_compat.h"

namespace skycal::latlong {
namespace {

// The shared model source's lat-long functions compiled in double: one formula for the
// shaders' model, the renderers and everything that reads a lat-long frame.
struct SharedLatLong {
  using Scalar = double;
  using vec3 = glsl::Vec3<double>;
  SC_CONST(SC_PI, kPi)
#include "../../render/model/latlong.glsl.h"
};

}  // namespace

double Latitude(double y, int height) {
  if (height <= 1) return 0.0;
  return SharedLatLong().latlong_latitude(y, height);
}

double Longitude(double x, int width) {
  if (width <= 1) return 0.0;
  return SharedLatLong().latlong_longitude(x, width);
}

double RowOfLatitude(double latitude, int height) { return (0.5 - latitude / kPi) * (height - 1); }

double ColumnOfLongitude(double longitude, int width) { return (0.5 - longitude / (2.0 * kPi)) * (width - 1); }

Vec3d Direction(double lat, double lon) {
  const auto d = SharedLatLong().latlong_direction_from_trig(std::sin(lat), std::cos(lat), std::sin(lon), std::cos(lon));
  return {d.x, d.y, d.z};
}

Vec3d PixelDirection(int x, int y, int width, int height) { return Direction(Latitude(y, height), Longitude(x, width)); }

Vec3d DirectionFromElevationAzimuthDeg(double elevation_deg, double azimuth_deg) {
  return Direction(elevation_deg * kPi / 180.0, azimuth_deg * kPi / 180.0);
}

double ElevationDeg(const Vec3d& d) {
  return std::atan2(d[1], std::hypot(d[0], d[2])) * 180.0 / kPi;
}

double AzimuthDeg(const Vec3d& d) { return std::atan2(d[0], d[2]) * 180.0 / kPi; }

std::array<double, 2> PixelPosition(const Vec3d& d, int width, int height) {
  const double lat = std::atan2(d[1], std::hypot(d[0], d[2]));
  const double lon = std::atan2(d[0], d[2]);
  return {ColumnOfLongitude(lon, width), RowOfLatitude(lat, height)};
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
