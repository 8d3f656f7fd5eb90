#include "sun_choice.h"

#include <cmath>

#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"

namespace skycal::cli {

bool ValidSunChoice(const std::optional<double>& el, const std::optional<double>& az,
                    const std::optional<std::array<double, 3>>& dir, std::string* why) {
  const bool have_angles = el || az;
  if (have_angles && dir) {
    *why = "give either --sun-elevation/--sun-azimuth or --sun-dir, not both";
    return false;
  }
  if (!have_angles && !dir) {
    *why = "the sun direction is required: --sun-elevation DEG --sun-azimuth DEG or --sun-dir X,Y,Z";
    return false;
  }
  if (have_angles && (!el || !az)) {
    *why = "--sun-elevation and --sun-azimuth go together";
    return false;
  }
  if (el && !(*el >= -90.0 && *el <= 90.0)) {
    *why = "--sun-elevation " + FormatNumber(*el) + ": expected degrees in [-90, 90]";
    return false;
  }
  if (az && !(std::abs(*az) <= 360.0)) {
    *why = "--sun-azimuth " + FormatNumber(*az) + ": expected degrees in [-360, 360]";
    return false;
  }
  if (dir) {
    const auto& d = *dir;
    if (!(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 1e-9)) {
      *why = "--sun-dir: expected a non-zero vector";
      return false;
    }
  }
  return true;
}

std::array<double, 3> SunDirectionFromChoice(const std::optional<double>& el, const std::optional<double>& az,
                                             const std::optional<std::array<double, 3>>& dir) {
  if (dir) return latlong::Normalized(*dir, "--sun-dir");
  return latlong::DirectionFromElevationAzimuthDeg(*el, *az);
}

}  // namespace skycal::cli
