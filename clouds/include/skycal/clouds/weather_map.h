// Weather maps for the cloudscape (cloud_textures.h's WeatherMap): uniform, procedural
// from noise, or painted by a user as an RGB EXR. Every map that leaves this module has
// passed ValidateWeatherMap.
//
// EXR orientation: EXR row 0 (the top of the image in a viewer, the data window's min y)
// is map row 0, which covers world z in [-extent/2, -extent/2 + texel), i.e. -z; columns
// run +x left to right. A map painted looking down with -z at the top reads as drawn.
#pragma once
#include <cstdint>
#include <string>

#include "skycal/clouds/cloud_textures.h"

namespace skycal::clouds {

// Accepted map sizes: square, a power of two from 4 to 4096 texels a side. Square and a
// power of two so a texel is extent / 2^k metres on both axes and GPU workgroups divide the
// map evenly; 4 is the smallest map with a distinct texel on each side of any texel for
// bilinear wrap; 4096 texels over the 70 km the clouds are drawn across (35 km each way) is
// 17 m a texel, far finer than the base noise shapes, and 192 MiB of floats: a bigger file
// is a mistake (a photograph, a wrong export), not a weather map.
inline constexpr int kMinWeatherMapSize = 4, kMaxWeatherMapSize = 4096;
// Extent: positive and at most 1,000 km (the clouds are drawn to 35 km; a larger number is
// a unit mistake, e.g. millimetres).
inline constexpr double kMaxWeatherExtentM = 1.0e6;

// Throws skycal::Error starting with `origin` (a file name or "uniform weather map") and
// naming what is wrong: size (not square / not a power of two / out of range), the rgb
// array's length, the extent, or the first texel that is NaN, infinite, negative or above
// 1 (its x, y and channel).
void ValidateWeatherMap(const WeatherMap& map, const std::string& origin);
// The size part of it alone (LoadWeatherMap runs it on the EXR header, before the pixels).
void CheckWeatherMapSize(int width, int height, const std::string& origin);

// A 4x4 map of one coverage, precipitation and type (each in [0, 1]) over `extent_m`.
WeatherMap UniformWeatherMap(double coverage, double precipitation, double type, double extent_m);

// Procedural weather: each field is tileable noise remapped to the requested mean (exactly,
// up to 1e-4, by solving for the offset under the [0, 1] clamp) and contrast.
struct WeatherNoiseOptions {
  double mean_coverage = 0.5;        // mean of R over the map, [0, 1]
  double coverage_contrast = 1.5;    // deviations from the mean are scaled by this, [0, 16]
  int coverage_cells = 4;            // noise cells across the map (base frequency), [1, 1024]
  double mean_precipitation = 0.1;   // mean of G, [0, 1]
  double precipitation_contrast = 1.0;  // [0, 16]
  double mean_type = 0.5;            // mean of B (0 stratus, 0.5 cumulus, 1 cumulonimbus), [0, 1]
  double type_contrast = 1.0;        // [0, 16]
  int octaves = 4;                   // fBm octaves, [1, 8]; octaves finer than 2 texels are dropped
  // False with `why` naming the field, its value and the bound it breaks.
  bool IsValid(std::string* why) const;
};

// Coverage is Perlin fBm dilated by Worley fBm (the Horizon Zero Dawn Perlin-Worley, for
// billowy patches); precipitation and type are Perlin fBm of their own. `size` must be an
// accepted size (above) and at least 2 * coverage_cells; throws skycal::Error otherwise.
WeatherMap NoiseWeatherMap(uint64_t seed, int size, double extent_m, const WeatherNoiseOptions& options);

// `map` on a size x size grid over the same extent: each new texel centre samples the old
// map bilinearly with wrap, as the march does (cloud_textures.glsl.h sample_image). Throws
// skycal::Error for a size that CheckWeatherMapSize refuses.
WeatherMap ResampleWeatherMap(const WeatherMap& map, int size);

// Reads an RGB EXR (R coverage, G precipitation, B type; an A channel is ignored, any other
// channel is refused) and validates it. Throws skycal::Error naming the file and what was
// expected: missing or unreadable file, wrong channels, wrong size, a bad texel, a bad extent.
WeatherMap LoadWeatherMap(const std::string& exr_path, double extent_m);

// Validates, then writes a float RGB EXR atomically (no partial file on failure).
void SaveWeatherMap(const WeatherMap& map, const std::string& exr_path);

}  // namespace skycal::clouds
