// Weather maps on disk: float RGB EXRs (orientation in weather_map.h).
#include <algorithm>

#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"

namespace skycal::clouds {

WeatherMap LoadWeatherMap(const std::string& exr_path, double extent_m) {
  const std::string origin = "weather map " + exr_path;
  ExrRGB exr;
  bool size_refused = false;
  try {
    // The size rule runs on the header: an 8192^2 file is refused before 800 MB is read.
    exr = ReadExrRGB(exr_path, [&](int w, int h) {
      size_refused = true;
      CheckWeatherMapSize(w, h, origin);
      size_refused = false;
    });
  } catch (const Error& e) {
    if (size_refused) throw;  // already says what a weather map must be
    throw Error(std::string(e.what()) + " [weather map: expected an RGB EXR, R coverage, G precipitation, B cloud type]");
  }
  for (const std::string& c : exr.channels)
    if (c != "R" && c != "G" && c != "B" && c != "A") {
      std::string all;
      for (const std::string& n : exr.channels) all += (all.empty() ? "" : ",") + n;
      throw Error(origin + ": has channels " + all + ": expected R, G, B (and optionally A, ignored)");
    }
  WeatherMap map;
  map.width = exr.image.width;
  map.height = exr.image.height;
  map.extent_m = extent_m;
  map.rgb = std::move(exr.image.pixels);
  ValidateWeatherMap(map, origin);
  return map;
}

void SaveWeatherMap(const WeatherMap& map, const std::string& exr_path) {
  ValidateWeatherMap(map, "weather map to write to " + exr_path);
  ImageRGB image(map.width, map.height);
  image.pixels = map.rgb;
  WriteExrRGB(exr_path, image, {});
}

}  // namespace skycal::clouds
