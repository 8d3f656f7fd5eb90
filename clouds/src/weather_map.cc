// Weather maps in memory: validation, the uniform map and the procedural one.
#include "skycal/clouds/weather_map.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>
#include <vector>

#include "noise_primitives.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/parallel_chunks.h"

namespace skycal::clouds {
namespace {

constexpr const char* kChannelNames[3] = {"R (coverage)", "G (precipitation)", "B (cloud type)"};
constexpr uint32_t kSaltCoverage = 0x1000, kSaltCoverageWorley = 0x1100, kSaltPrecipitation = 0x1200,
                   kSaltType = 0x1300;

bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

void CheckExtent(double extent_m, const std::string& origin) {
  if (!(extent_m > 0.0) || !(extent_m <= kMaxWeatherExtentM))
    throw Error(origin + ": weather map extent " + FormatNumber(extent_m) +
                " m: expected more than 0 and at most 1e+06 m (1000 km)");
}

bool InUnit(double v) { return v >= 0.0 && v <= 1.0; }  // false for NaN

// Options check shared by IsValid: `name` = `value` must lie in [lo, hi].
bool InRange(const char* name, double value, double lo, double hi, std::string* why) {
  if (value >= lo && value <= hi) return true;
  if (why) *why = std::string("WeatherNoiseOptions.") + name + " = " + FormatNumber(value) + ": expected a value in [" +
                  FormatNumber(lo) + ", " + FormatNumber(hi) + "]";
  return false;
}

// Tileable noise in [0, 1] on a size^2 grid at texel centres; `billows` dilates Perlin fBm
// by Worley fBm into Perlin-Worley, as the base volume's R channel (cloud_noise.cc).
std::vector<float> NoiseField(uint64_t seed, uint32_t salt, int size, int cells, int octaves, bool billows) {
  int usable = 1;  // octaves finer than 2 texels a cell would alias
  while (usable < octaves && (cells << usable) * 2 <= size) ++usable;
  std::vector<noise::WorleyGrid> grids;
  if (billows)
    for (int k = 0; k < std::min(usable, 3); ++k) grids.emplace_back(cells << k, seed, kSaltCoverageWorley + k, 1);  // planar: depth 1
  std::vector<float> field(static_cast<size_t>(size) * size);
  // Rows on the machine's threads: each texel is a pure function of its position (the
  // statistics fit draws a dozen of these fields before its first render).
  ParallelChunks(size, ResolveThreads(0), [&](int begin, int end, int) {
    for (int y = begin; y < end; ++y)
      for (int x = 0; x < size; ++x) {
        const double u = (x + 0.5) * cells / size, v = (y + 0.5) * cells / size;
        float value = noise::PerlinTo01(noise::PeriodicPerlinFbm(u, v, 0.5, cells, usable, seed, salt));
        if (billows) {
          float w[3];
          for (size_t k = 0; k < grids.size(); ++k) w[k] = grids[k].Inverted(u * (1 << k), v * (1 << k), 0.5);
          value = noise::PerlinWorley(value, noise::WorleyFbm(w, static_cast<int>(grids.size())));
        }
        field[static_cast<size_t>(y) * size + x] = value;
      }
  });
  return field;
}

// NoiseField, kept for the process: a statistics fit draws the same few seeds at each
// coverage it tries (only RemapToMean differs), and a calibration draws them again for the
// game's image. A field is size^2 floats (256 KB at 256); at most kKeptFields are kept.
std::vector<float> KeptNoiseField(uint64_t seed, uint32_t salt, int size, int cells, int octaves, bool billows) {
  constexpr size_t kKeptFields = 64;
  using Key = std::tuple<uint64_t, uint32_t, int, int, int, bool>;
  static std::mutex mutex;
  static std::map<Key, std::vector<float>> kept;
  const Key key{seed, salt, size, cells, octaves, billows};
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = kept.find(key);
    if (it != kept.end()) return it->second;
  }
  std::vector<float> field = NoiseField(seed, salt, size, cells, octaves, billows);
  std::lock_guard<std::mutex> lock(mutex);
  if (kept.size() >= kKeptFields) kept.erase(kept.begin());
  kept.emplace(key, field);
  return field;
}

// clamp(offset + contrast * (v - mean(v)), 0, 1) with the offset found by bisection so the
// clamped field's mean is `target`: the mean is monotone in the offset.
void RemapToMean(std::vector<float>& field, double target, double contrast) {
  double mean = 0.0;
  for (float v : field) mean += v;
  mean /= static_cast<double>(field.size());
  auto remapped_mean = [&](double offset) {
    double s = 0.0;
    for (float v : field) s += std::clamp(offset + contrast * (v - mean), 0.0, 1.0);
    return s / static_cast<double>(field.size());
  };
  double lo = -1.0 - contrast, hi = 1.0 + contrast;  // all 0 at lo, all 1 at hi
  for (int i = 0; i < 40 && hi - lo > 1e-7; ++i) {
    const double mid = 0.5 * (lo + hi);
    (remapped_mean(mid) < target ? lo : hi) = mid;
  }
  const double offset = 0.5 * (lo + hi);
  for (float& v : field) v = static_cast<float>(std::clamp(offset + contrast * (v - mean), 0.0, 1.0));
}

}  // namespace

void CheckWeatherMapSize(int width, int height, const std::string& origin) {
  const std::string size = std::to_string(width) + " x " + std::to_string(height);
  if (width != height || !IsPowerOfTwo(width) || width < kMinWeatherMapSize || width > kMaxWeatherMapSize)
    throw Error(origin + ": weather map is " + size + " texels: expected a square power of two from " +
                std::to_string(kMinWeatherMapSize) + " to " + std::to_string(kMaxWeatherMapSize) + " a side");
}

void ValidateWeatherMap(const WeatherMap& map, const std::string& origin) {
  CheckWeatherMapSize(map.width, map.height, origin);
  CheckExtent(map.extent_m, origin);
  const size_t expected = static_cast<size_t>(map.width) * map.height * 3;
  if (map.rgb.size() != expected)
    throw Error(origin + ": weather map has " + std::to_string(map.rgb.size()) + " values, expected " +
                std::to_string(expected) + " (width x height x 3)");
  for (size_t i = 0; i < expected; ++i) {
    if (InUnit(map.rgb[i])) continue;
    const size_t texel = i / 3;
    const float v = map.rgb[i];
    const std::string what = std::isnan(v) ? "NaN" : std::isinf(v) ? "infinite" : FormatNumber(v);
    throw Error(origin + ": weather map pixel (x " + std::to_string(texel % map.width) + ", y " +
                std::to_string(texel / map.width) + ") channel " + kChannelNames[i % 3] + " is " + what +
                ": expected a value in [0, 1]");
  }
}

WeatherMap UniformWeatherMap(double coverage, double precipitation, double type, double extent_m) {
  WeatherMap map;
  map.width = map.height = kMinWeatherMapSize;
  map.extent_m = extent_m;
  for (int i = 0; i < map.width * map.height; ++i)
    for (double v : {coverage, precipitation, type}) map.rgb.push_back(static_cast<float>(v));
  ValidateWeatherMap(map, "uniform weather map");
  return map;
}

bool WeatherNoiseOptions::IsValid(std::string* why) const {
  return InRange("mean_coverage", mean_coverage, 0, 1, why) && InRange("coverage_contrast", coverage_contrast, 0, 16, why) &&
         InRange("coverage_cells", coverage_cells, 1, 1024, why) &&
         InRange("mean_precipitation", mean_precipitation, 0, 1, why) &&
         InRange("precipitation_contrast", precipitation_contrast, 0, 16, why) &&
         InRange("mean_type", mean_type, 0, 1, why) && InRange("type_contrast", type_contrast, 0, 16, why) &&
         InRange("octaves", octaves, 1, 8, why);
}

WeatherMap NoiseWeatherMap(uint64_t seed, int size, double extent_m, const WeatherNoiseOptions& options) {
  const std::string origin = "noise weather map";
  std::string why;
  if (!options.IsValid(&why)) throw Error(origin + ": " + why);
  CheckWeatherMapSize(size, size, origin);
  if (size < 2 * options.coverage_cells)
    throw Error(origin + ": WeatherNoiseOptions.coverage_cells = " + std::to_string(options.coverage_cells) +
                " is too fine for a " + std::to_string(size) + "-texel map: expected at most size / 2");
  std::vector<float> fields[3] = {
      KeptNoiseField(seed, kSaltCoverage, size, options.coverage_cells, options.octaves, true),
      KeptNoiseField(seed, kSaltPrecipitation, size, options.coverage_cells, options.octaves, false),
      KeptNoiseField(seed, kSaltType, size, options.coverage_cells, options.octaves, false)};
  RemapToMean(fields[0], options.mean_coverage, options.coverage_contrast);
  RemapToMean(fields[1], options.mean_precipitation, options.precipitation_contrast);
  RemapToMean(fields[2], options.mean_type, options.type_contrast);
  WeatherMap map;
  map.width = map.height = size;
  map.extent_m = extent_m;
  map.rgb.resize(static_cast<size_t>(size) * size * 3);
  for (size_t i = 0; i < fields[0].size(); ++i)
    for (int c = 0; c < 3; ++c) map.rgb[i * 3 + c] = fields[c][i];
  ValidateWeatherMap(map, origin);
  return map;
}

WeatherMap ResampleWeatherMap(const WeatherMap& map, int size) {
  CheckWeatherMapSize(size, size, "resampled weather map");
  WeatherMap out;
  out.width = out.height = size;
  out.extent_m = map.extent_m;
  out.rgb.resize(static_cast<size_t>(size) * size * 3);
  const auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
  for (int y = 0; y < size; ++y) {
    const double v = (y + 0.5) * map.height / size - 0.5;  // in the old map's texels, centre at i
    const int y0 = static_cast<int>(std::floor(v));
    const double fy = v - y0;
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) * map.width / size - 0.5;
      const int x0 = static_cast<int>(std::floor(u));
      const double fx = u - x0;
      const size_t i00 = (static_cast<size_t>(wrap(y0, map.height)) * map.width + wrap(x0, map.width)) * 3;
      const size_t i01 = (static_cast<size_t>(wrap(y0, map.height)) * map.width + wrap(x0 + 1, map.width)) * 3;
      const size_t i10 = (static_cast<size_t>(wrap(y0 + 1, map.height)) * map.width + wrap(x0, map.width)) * 3;
      const size_t i11 = (static_cast<size_t>(wrap(y0 + 1, map.height)) * map.width + wrap(x0 + 1, map.width)) * 3;
      for (int c = 0; c < 3; ++c) {
        const double top = (1.0 - fx) * map.rgb[i00 + c] + fx * map.rgb[i01 + c];
        const double bottom = (1.0 - fx) * map.rgb[i10 + c] + fx * map.rgb[i11 + c];
        out.rgb[(static_cast<size_t>(y) * size + x) * 3 + c] = static_cast<float>((1.0 - fy) * top + fy * bottom);
      }
    }
  }
  ValidateWeatherMap(out, "resampled weather map");
  return out;
}

}  // namespace skycal::clouds
