// The weather-map loader on a fuzzed OpenEXR file: clouds::LoadWeatherMap (core::ReadExrRGB,
// then the channel set, the square power-of-two size and every texel in [0, 1]).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "skycal/clouds/weather_map.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skycal;
  const std::string path = fuzz::WriteInput("weather.exr", data, size);
  fuzz::ExpectOnlySkycalErrors([&] { clouds::LoadWeatherMap(path, 30000.0); });
  return 0;
}
