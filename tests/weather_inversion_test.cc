// The weather map inverted from a photo (cloudfit/weather_inversion.h): the links between
// texels and pixels follow the march's geometry, and the seed and refinement steps move the
// coverage the way the photo asks (and not at all when the render already matches).
#include <gtest/gtest.h>

#include <cmath>

#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal {
namespace {

constexpr int kW = 128, kH = 64, kMap = 64;

// The texel straight above the camera is seen at the top row; a texel at horizontal distance
// d is seen at the elevation of the layer's mid altitude over d, less the planet's drop
// d^2 / 2R (small angles: a few hundredths of a degree here).
TEST(WeatherInversion, LinksFollowTheMarchGeometry) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  ASSERT_GT(v.constrained, 0);
  const double texel_m = p.weather_extent_m / kMap, mid = 0.5 * (p.layer_bottom_m + p.layer_top_m);
  int checked = 0;
  for (const auto& [texel, pix] : v.links) {
    const int i = texel % kMap, j = texel / kMap;
    const double x = ((i + 0.5) / kMap - 0.5) * p.weather_extent_m, z = ((j + 0.5) / kMap - 0.5) * p.weather_extent_m;
    const double d = std::hypot(x, z);
    const double el_texel = std::atan2(mid - d * d / (2.0 * p.planet_radius_m), d) * 180.0 / kPi;
    const double el_pixel = latlong::Latitude(pix / kW, kH) * 180.0 / kPi;
    // A link is the centre's pixel or a ray through the layer (bottom to top, within a texel):
    // its elevation lies between the texel's bottom and top, give or take a texel and a pixel.
    const double lo = std::atan2(p.layer_bottom_m, d + texel_m) * 180.0 / kPi - 180.0 / (kH - 1);
    const double hi = std::atan2(p.layer_top_m, std::max(1.0, d - texel_m)) * 180.0 / kPi + 180.0 / (kH - 1);
    EXPECT_GE(el_pixel, lo) << "texel " << i << "," << j << " (el " << el_texel << ")";
    EXPECT_LE(el_pixel, hi) << "texel " << i << "," << j << " (el " << el_texel << ")";
    // And at the texel's azimuth (longitude 0 -> +Z, +90 -> +X: core/latlong.h), within the
    // texel's angular size and a pixel: a mirrored or rotated map fails here.
    if (d > 3.0 * texel_m) {
      const double az_texel = std::atan2(x, z) * 180.0 / kPi;
      const double az_pixel = latlong::Longitude(pix % kW, kW) * 180.0 / kPi;
      double diff = std::fmod(std::abs(az_texel - az_pixel), 360.0);
      diff = std::min(diff, 360.0 - diff);
      EXPECT_LE(diff, std::atan2(texel_m, d - texel_m) * 180.0 / kPi + 360.0 / (kW - 1)) << "texel " << i << "," << j;
    }
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(v.links.size()));
  // Nothing beyond the draw distance, and the corners of a map wider than it are unseen.
  EXPECT_LT(v.constrained, kMap * kMap);
  const double reach = p.draw_distance_m;  // horizontal reach <= draw distance
  const int corner = 0;                    // texel (0, 0): ~42 km away
  EXPECT_GT(std::hypot(0.5 * p.weather_extent_m, 0.5 * p.weather_extent_m), reach);
  for (const auto& l : v.links) EXPECT_NE(l.first, corner);
}

TEST(WeatherInversion, NoSkyConstrainsNothing) {
  clouds::CloudParams p;
  const std::vector<float> none(static_cast<size_t>(kW) * kH, 0.0f);
  EXPECT_EQ(cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, none).constrained, 0);
  EXPECT_THROW(cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, std::vector<float>(7, 1.0f)), Error);
}

TEST(WeatherInversion, SeedAndRefineMoveCoverageTowardThePhoto) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  clouds::WeatherMap map = clouds::UniformWeatherMap(0.3, 0.0, 0.5, p.weather_extent_m);
  map = clouds::NoiseWeatherMap(1, kMap, p.weather_extent_m, {});  // any statistical map
  const clouds::WeatherMap statistical = map;
  std::vector<float> photo(static_cast<size_t>(kW) * kH, 0.0f);
  for (int y = 0; y < kH / 4; ++y)  // cloud overhead only (above ~45 deg)
    for (int x = 0; x < kW; ++x) photo[static_cast<size_t>(y) * kW + x] = 1.0f;
  cloudfit::SeedCoverage(v, photo, 0.5, &map);
  std::vector<char> linked(static_cast<size_t>(kMap) * kMap, 0);
  for (const auto& l : v.links) linked[static_cast<size_t>(l.first)] = 1;
  const int zenith = (kMap / 2) * kMap + kMap / 2;
  EXPECT_FLOAT_EQ(map.rgb[3 * zenith], 0.5f);  // all its pixels cloud: gain x 1
  for (size_t t = 0; t < linked.size(); ++t)
    if (!linked[t]) EXPECT_EQ(map.rgb[3 * t], statistical.rgb[3 * t]) << t;  // unseen: the statistics' coverage
  // The render matches the photo: nothing moves and the RMS is 0.
  const clouds::WeatherMap seeded = map;
  EXPECT_EQ(cloudfit::RefineCoverage(v, photo, photo, 0.5, &map), 0.0);
  EXPECT_EQ(map.rgb, seeded.rgb);
  // Rendered everywhere 0.2 more opaque than the photo: every constrained texel 0.1 thinner
  // (clamped at 0), the RMS 0.2.
  std::vector<float> thicker(photo);
  for (float& o : thicker) o += 0.2f;
  EXPECT_NEAR(cloudfit::RefineCoverage(v, photo, thicker, 0.5, &map), 0.2, 1e-6);
  EXPECT_NEAR(map.rgb[3 * zenith], 0.4f, 1e-6);
  for (size_t t = 0; t < linked.size(); ++t)
    if (linked[t]) EXPECT_NEAR(map.rgb[3 * t], std::max(0.0f, seeded.rgb[3 * t] - 0.1f), 1e-6) << t;
}

TEST(WeatherInversion, DownsampleAveragesBlocks) {
  std::vector<float> v(8 * 4);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i);
  const auto d = cloudfit::DownsampleLatLong(v, 8, 4, 4, 2);
  ASSERT_EQ(d.size(), 8u);
  EXPECT_FLOAT_EQ(d[0], (0.0f + 1 + 8 + 9) / 4);
  EXPECT_FLOAT_EQ(d[7], (22.0f + 23 + 30 + 31) / 4);
  EXPECT_THROW(cloudfit::DownsampleLatLong(v, 8, 4, 3, 2), Error);
}

}  // namespace
}  // namespace skycal
