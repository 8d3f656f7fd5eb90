// A reference sky for fitting: a lat-long frame, its sun direction, and the per-pixel
// classes that decide which pixels the fit uses (each class counted in the summary).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "skycal/core/image.h"
#include "skycal/core/row_mapping.h"
#include "skycal/fit/fit_options.h"

namespace skycal::fit {

enum class PixelClass : uint8_t {
  kSky = 0,          // used by the fit
  kBelowHorizon = 1, // latitude <= 0: ground, not sky
  kSunCone = 2,      // within sun_cone_deg of the sun (disc, aureole, flare)
  kInvalid = 3,      // NaN, Inf, zero or negative in any channel (e.g. DWAB ringing)
  kClipped = 4,      // at the sensor/encoder clamp: the true value is unknown
  kUserMasked = 5,   // excluded by the user mask
};

struct MaskCounts {
  long long sky = 0, below_horizon = 0, sun_cone = 0, invalid = 0, clipped = 0, user_masked = 0;
  bool operator==(const MaskCounts&) const = default;
};

// The counts of a pixel-class map.
MaskCounts CountPixelClasses(const std::vector<PixelClass>& classes);

struct Reference {
  std::string path, name, sha256;
  ImageRGB radiance;
  std::array<double, 3> sun_dir{};
  std::string sun_source;              // "option", "attribute" or "detected"
  std::vector<std::string> warnings;
  std::vector<PixelClass> pixel_class; // width * height
  MaskCounts counts;
  double clip_level = 0.0;             // 0: no clipping plateau found
  std::optional<double> time_of_day_h; // from the `skycalTimeOfDay` attribute (hours)
  // Horizon-biased rows (`skycal resample`, core/row_mapping.h): each row's elevation and
  // solid angle come from the mapping; absent: core/latlong.h's uniform 2:1 rows.
  std::optional<RowMapping> row_mapping;

  double Latitude(int y) const;                             // radians
  double PixelSolidAngle(int x, int y) const;               // sr
  std::array<double, 3> PixelDirection(int x, int y) const;  // unit vector
};

// Loads and classifies. Throws skycal::Error naming the file when it is unreadable, not a
// 2:1 lat-long (or one with a valid row mapping; such a frame needs its sun direction as
// an option or attribute: detection assumes uniform rows), has no valid sky pixel, or has no sun direction and none can be detected.
Reference LoadReference(const std::string& path, const FitOptions& options);

nlohmann::json MaskCountsToJson(const MaskCounts& c);

}  // namespace skycal::fit
