// Cloud textures filled by hand for tests (independent of the noise generator): constant
// volumes (a uniform slab: what the analytic tests need) and tileable sinusoid products
// (structure for the parity sweep), plus small weather maps.
#pragma once
#include <cmath>
#include <numbers>

#include "skycal/clouds/cloud_textures.h"

namespace skycal::testing {

inline clouds::CloudNoise ConstantCloudNoise(float base, float detail) {
  clouds::CloudNoise n;
  const size_t b = clouds::CloudNoise::kBaseSize, d = clouds::CloudNoise::kDetailSize, c = clouds::CloudNoise::kCurlSize;
  n.base.assign(b * b * b * 4, base);
  n.detail.assign(d * d * d * 3, detail);
  n.curl.assign(c * c * 3, 0.0f);
  return n;
}

// Every channel a different product of whole-period sinusoids (so every volume tiles).
inline clouds::CloudNoise SinusoidCloudNoise() {
  clouds::CloudNoise n = ConstantCloudNoise(0.0f, 0.0f);
  constexpr double k2pi = 2.0 * std::numbers::pi;
  auto wave = [&](int size, int x, int y, int z, int c) {
    const double u = k2pi * x / size, v = k2pi * y / size, w = k2pi * z / size;
    const double f = 1.0 + c;
    const double s = std::sin(f * u + 0.7 * c) * std::sin(2.0 * w + c) * std::cos(f * v) + 0.5 * std::sin(3.0 * (u + w) + c);
    return static_cast<float>(std::clamp(0.5 + 0.4 * s, 0.0, 1.0));
  };
  const int b = clouds::CloudNoise::kBaseSize, d = clouds::CloudNoise::kDetailSize, cs = clouds::CloudNoise::kCurlSize;
  for (int z = 0; z < b; ++z)
    for (int y = 0; y < b; ++y)
      for (int x = 0; x < b; ++x)
        for (int c = 0; c < 4; ++c) n.base[((static_cast<size_t>(z) * b + y) * b + x) * 4 + c] = wave(b, x, y, z, c);
  for (int z = 0; z < d; ++z)
    for (int y = 0; y < d; ++y)
      for (int x = 0; x < d; ++x)
        for (int c = 0; c < 3; ++c) n.detail[((static_cast<size_t>(z) * d + y) * d + x) * 3 + c] = wave(d, x, y, z, c);
  for (int y = 0; y < cs; ++y)
    for (int x = 0; x < cs; ++x)
      for (int c = 0; c < 3; ++c) n.curl[(static_cast<size_t>(y) * cs + x) * 3 + c] = 2.0f * wave(cs, x, 0, y, c) - 1.0f;
  return n;
}

inline clouds::WeatherMap UniformWeather(float coverage, float precipitation, float type, double extent_m = 60000.0) {
  clouds::WeatherMap m;
  m.width = m.height = 4;
  m.extent_m = extent_m;
  for (int i = 0; i < 16; ++i) m.rgb.insert(m.rgb.end(), {coverage, precipitation, type});
  return m;
}

// Coverage varying smoothly around `mean` (amplitude up to 0.5, clamped), one type.
inline clouds::WeatherMap PatchyWeather(float mean, float type, double extent_m = 60000.0) {
  clouds::WeatherMap m;
  m.width = m.height = 16;
  m.extent_m = extent_m;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const double s = std::sin(2.0 * std::numbers::pi * x / 16 * 3) * std::cos(2.0 * std::numbers::pi * y / 16 * 2);
      const float c = static_cast<float>(std::clamp(mean + 0.5 * s * std::min(mean, 1.0f - mean) * 2.0, 0.0, 1.0));
      m.rgb.insert(m.rgb.end(), {c, 0.0f, type});
    }
  }
  return m;
}

}  // namespace skycal::testing
