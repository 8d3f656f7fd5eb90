// The day's wind from consecutive frames' weather maps (cloudfit/weather_wind.h): a map
// moved by a known shift is measured back to a tenth of a texel, with the sign convention
// of the weather map (the second map is the first moved by dx, dz); unrelated maps are told
// apart by the correlation peak; the day's wind is the least-squares velocity over pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "skycal/cloudfit/weather_wind.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"

namespace skycal {
namespace {

constexpr double kExtent = 60000.0;

clouds::WeatherMap Noise(uint64_t seed) {
  clouds::WeatherNoiseOptions o;
  o.mean_coverage = 0.3;
  o.coverage_contrast = 3.0;
  o.coverage_cells = 8;
  return clouds::NoiseWeatherMap(seed, 128, kExtent, o);
}

// The map moved by (dx, dz) texels, bilinearly, through its tiling: moved(x) = map(x - d).
clouds::WeatherMap Moved(const clouds::WeatherMap& m, double dx, double dz) {
  clouds::WeatherMap r = m;
  const int w = m.width, h = m.height;
  const auto at = [&](int x, int y, int c) { return m.rgb[3 * (((y % h + h) % h) * w + (x % w + w) % w) + c]; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double sx = x - dx, sy = y - dz;
      const int x0 = static_cast<int>(std::floor(sx)), y0 = static_cast<int>(std::floor(sy));
      const double fx = sx - x0, fy = sy - y0;
      for (int c = 0; c < 3; ++c)
        r.rgb[3 * (static_cast<size_t>(y) * w + x) + c] = static_cast<float>(
            (1 - fy) * ((1 - fx) * at(x0, y0, c) + fx * at(x0 + 1, y0, c)) +
            fy * ((1 - fx) * at(x0, y0 + 1, c) + fx * at(x0 + 1, y0 + 1, c)));
    }
  return r;
}

TEST(WeatherWind, AMovedMapIsMeasuredBackWithItsSign) {
  const clouds::WeatherMap a = Noise(3);
  const double texel = kExtent / a.width;
  for (const auto& d : std::vector<std::pair<double, double>>{{2.0, 0.0}, {0.0, -3.0}, {1.3, 2.6}, {-4.4, 0.7}}) {
    const clouds::WeatherMap b = Moved(a, d.first, d.second);
    const cloudfit::MapShift s = cloudfit::MeasureMapShift({&a, nullptr, 0.0}, {&b, nullptr, 30.0});
    EXPECT_NEAR(s.dx_m / texel, d.first, 0.1) << d.first << "," << d.second;
    EXPECT_NEAR(s.dz_m / texel, d.second, 0.1) << d.first << "," << d.second;
    EXPECT_GT(s.response, 0.5);
    EXPECT_EQ(s.dt_s, 30.0);
  }
  // The control: two unrelated maps correlate weakly.
  const clouds::WeatherMap other = Noise(4);
  EXPECT_LT(cloudfit::MeasureMapShift({&a, nullptr, 0.0}, {&other, nullptr, 30.0}).response, 0.2);
}

// Only what the photo constrained correlates: unconstrained texels of the second map replaced
// by other clouds do not move the measured shift.
TEST(WeatherWind, UnconstrainedTexelsDoNotCount) {
  const clouds::WeatherMap a = Noise(3), other = Noise(9);
  clouds::WeatherMap b = Moved(a, 3.0, 1.0);
  std::vector<float> seen(static_cast<size_t>(a.width) * a.height, 0.0f);
  for (int y = 32; y < 96; ++y)
    for (int x = 32; x < 96; ++x) seen[static_cast<size_t>(y) * a.width + x] = 1.0f;
  for (size_t i = 0; i < seen.size(); ++i)
    if (seen[i] < 0.5f)
      for (int c = 0; c < 3; ++c) b.rgb[3 * i + c] = other.rgb[3 * i + c];
  const cloudfit::MapShift s = cloudfit::MeasureMapShift({&a, &seen, 0.0}, {&b, &seen, 60.0});
  const double texel = kExtent / a.width;
  EXPECT_NEAR(s.dx_m / texel, 3.0, 0.1);
  EXPECT_NEAR(s.dz_m / texel, 1.0, 0.1);
}

// Three frames of a wind of 12 m/s toward azimuth 60 deg (+x = sin 60, +z = cos 60), 30 s and
// 90 s apart, given out of order: the day's wind back to 2% and 1 degree.
TEST(WeatherWind, TheDaysWindFromThreeFrames) {
  const clouds::WeatherMap a = Noise(5);
  const double texel = kExtent / a.width, speed = 12.0, az = 60.0 * M_PI / 180.0;
  const auto at = [&](double t) {
    return Moved(a, speed * t * std::sin(az) / texel, speed * t * std::cos(az) / texel);
  };
  const clouds::WeatherMap b = at(30.0), c = at(120.0);
  const cloudfit::DayWind d = cloudfit::FitDayWind({{&c, nullptr, 120.0}, {&a, nullptr, 0.0}, {&b, nullptr, 30.0}});
  EXPECT_NEAR(d.speed_m_s, speed, 0.02 * speed);
  EXPECT_NEAR(d.direction_deg, 60.0, 1.0);
  ASSERT_EQ(d.pairs.size(), 2u);
  EXPECT_EQ(d.pairs[0].dt_s, 30.0);
  EXPECT_EQ(d.pairs[1].dt_s, 90.0);
  EXPECT_THROW(cloudfit::FitDayWind({{&a, nullptr, 0.0}}), Error);
  EXPECT_THROW(cloudfit::FitDayWind({{&a, nullptr, 0.0}, {&b, nullptr, 0.0}}), Error);
  const clouds::WeatherMap small = clouds::UniformWeatherMap(0.5, 0.0, 0.5, kExtent);
  EXPECT_THROW(cloudfit::MeasureMapShift({&a, nullptr, 0.0}, {&small, nullptr, 1.0}), Error);
}

}  // namespace
}  // namespace skycal
