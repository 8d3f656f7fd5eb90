// The lat-long (equirectangular) convention of the whole project. It is OpenEXR's
// envmap LatLong convention (OpenEXR ImfEnvmap.h), reproduced here in double precision:
//   - pixel centres sit at integer coordinates (x, y), x in [0, W-1], y in [0, H-1];
//   - latitude  = +pi/2 at y = 0 (top row) down to -pi/2 at y = H-1 (bottom row);
//   - longitude = +pi at x = 0 down to -pi at x = W-1 (so column 0 and column W-1 both
//     look along -Z: the seam is stored twice);
//   - direction = (sin(lon) cos(lat), sin(lat), cos(lon) cos(lat)), +Y up,
//     longitude 0 -> +Z, longitude +pi/2 -> +X.
// "Azimuth" on the command line is this longitude in degrees, "elevation" the latitude.
#pragma once
#include <array>

namespace skycal::latlong {

using Vec3d = std::array<double, 3>;

// Radians at pixel coordinates (centres at integers; continuous positions in between). The
// formulas are the shared model source's (render/model/latlong.glsl.h), the shaders' too.
double Latitude(double y, int height);
double Longitude(double x, int width);
// Their inverses: the continuous row of a latitude and the column of a longitude (radians).
double RowOfLatitude(double latitude, int height);
double ColumnOfLongitude(double longitude, int width);
// Unit vector of latitude and longitude (radians), the convention above.
Vec3d Direction(double latitude, double longitude);
Vec3d PixelDirection(int x, int y, int width, int height);
// Unit vector from elevation and azimuth (longitude), both in degrees.
Vec3d DirectionFromElevationAzimuthDeg(double elevation_deg, double azimuth_deg);
double ElevationDeg(const Vec3d& unit_dir);
double AzimuthDeg(const Vec3d& unit_dir);
// Continuous pixel position of a direction (inverse of PixelDirection); x in [0, W-1].
std::array<double, 2> PixelPosition(const Vec3d& unit_dir, int width, int height);
// Solid angle (steradians) a pixel stands for under trapezoidal quadrature on the
// node-centred grid: the two seam columns share one column's weight, the pole rows get
// the half-row cap. Sums to 4*pi over the image.
double PixelSolidAngle(int x, int y, int width, int height);
// Returns the unit vector, or throws skycal::Error naming `what` if it has no length or
// a non-finite component.
Vec3d Normalized(const Vec3d& v, const char* what);

}  // namespace skycal::latlong
