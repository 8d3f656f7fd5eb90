// `skycal weather`: a procedural weather map for the cloudscape (clouds/weather_map.h:
// R coverage, G precipitation, B type), written as the RGB EXR that a preset's
// `clouds.weather_map` names and `render --weather-map` reads — the starting point a
// lighting artist paints over. Same generator (clouds::NoiseWeatherMap) as the bundled
// default_cloudy.weather.exr, which predates this verb (docs/file-formats.md "Bundled data").
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/clouds/weather_map.h"

namespace skycal::cli {

struct WeatherOptions {
  int seed = 1;                   // noise seed, [0, 2^31)
  int size = 256;                 // texels a side (a power of two, 4..4096)
  double extent_m = 60000.0;      // world metres the map covers along x and z
  clouds::WeatherNoiseOptions noise;
  std::string out;                // the EXR, written atomically
  bool IsValid(std::string* why) const;  // names the option at fault
};

nlohmann::json RunWeatherImpl(const WeatherOptions& options);
WeatherOptions ParseWeatherArgs(int argc, char** argv);
int RunWeather(int argc, char** argv);

}  // namespace skycal::cli
