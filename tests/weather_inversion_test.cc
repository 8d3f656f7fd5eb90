// The weather map inverted from a photo (cloudfit/weather_inversion.h): the links between
// texels and pixels follow the march's geometry (the map's tiling included), the carving caps
// the columns the clear sky crosses, the refinement moves the texels the march would show
// (and nothing when the render already matches), and the smoothing follows a pixel's footprint.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal {
namespace {

constexpr int kW = 128, kH = 64, kMap = 64;

// A texel at horizontal distance d is seen at the elevations of the layer over d (less the
// planet's drop d^2 / 2R, a few hundredths of a degree here) and at its azimuth. The map
// tiles as the march's sampler does: a link may go through any copy of the texel (offset by
// whole map extents) within the draw distance.
bool LinkFollowsTheGeometry(const clouds::CloudParams& p, int texel, int pix, bool* wrapped) {
  const double texel_m = p.weather_extent_m / kMap;
  const int i = texel % kMap, j = texel / kMap;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b) {
      const double x = ((i + 0.5) / kMap - 0.5 + a) * p.weather_extent_m;
      const double z = ((j + 0.5) / kMap - 0.5 + b) * p.weather_extent_m;
      const double d = std::hypot(x, z);
      if (d > p.draw_distance_m + 2.0 * texel_m) continue;
      const double el_pixel = latlong::Latitude(pix / kW, kH) * 180.0 / kPi;
      // Between the texel's bottom and top, give or take a texel and a pixel.
      const double lo = std::atan2(p.layer_bottom_m, d + texel_m) * 180.0 / kPi - 180.0 / (kH - 1);
      const double hi = std::atan2(p.layer_top_m, std::max(1.0, d - texel_m)) * 180.0 / kPi + 180.0 / (kH - 1);
      if (el_pixel < lo || el_pixel > hi) continue;
      // At the texel's azimuth (longitude 0 -> +Z, +90 -> +X: core/latlong.h), within its
      // angular size and a pixel: a mirrored or rotated map fails here.
      if (d > 3.0 * texel_m) {
        const double az_pixel = latlong::Longitude(pix % kW, kW) * 180.0 / kPi;
        double diff = std::fmod(std::abs(std::atan2(x, z) * 180.0 / kPi - az_pixel), 360.0);
        diff = std::min(diff, 360.0 - diff);
        if (diff > std::atan2(texel_m, d - texel_m) * 180.0 / kPi + 360.0 / (kW - 1)) continue;
      }
      *wrapped = (a != 0 || b != 0);
      return true;
    }
  return false;
}

TEST(WeatherInversion, LinksFollowTheMarchGeometry) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  ASSERT_GT(v.constrained, 0);
  int wrapped = 0;
  std::vector<char> linked(static_cast<size_t>(kMap) * kMap, 0);
  for (const auto& s : v.rays) {
    bool w = false;
    EXPECT_TRUE(LinkFollowsTheGeometry(p, s.texel, s.pixel, &w))
        << "texel " << s.texel % kMap << "," << s.texel / kMap << ", pixel " << s.pixel;
    wrapped += w;
    linked[static_cast<size_t>(s.texel)] = 1;
  }
  EXPECT_EQ(linked, v.linked);
  EXPECT_EQ(v.constrained, std::count(linked.begin(), linked.end(), 1));
  // The corners of a 60 km map lie beyond the 35 km draw distance: only their copies are seen.
  EXPECT_GT(std::hypot(0.5 * p.weather_extent_m, 0.5 * p.weather_extent_m), p.draw_distance_m);
  EXPECT_GT(wrapped, 0);
  // Every ray runs front to back: its samples' heights in the layer rise.
  for (size_t k = 1; k < v.rays.size(); ++k)
    if (v.rays[k].pixel == v.rays[k - 1].pixel) {
      EXPECT_GE(v.rays[k].fraction, v.rays[k - 1].fraction) << k;
    }
}

TEST(WeatherInversion, NoSkyConstrainsNothing) {
  clouds::CloudParams p;
  const std::vector<float> none(static_cast<size_t>(kW) * kH, 0.0f);
  EXPECT_EQ(cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, none).constrained, 0);
  EXPECT_THROW(cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, std::vector<float>(7, 1.0f)), Error);
}

// The texel under camera-relative (x, 0) of a map `size` texels across.
int TexelAtX(const clouds::CloudParams& p, int size, double x) {
  return (size / 2) * size + static_cast<int>(std::floor((x / p.weather_extent_m + 0.5) * size));
}

// A photo cloudy below 25 degrees and clear above: a texel whose column the clear pixels
// cross only above ~45% of the layer keeps its coverage as stratus; one they cross only above
// ~70%, as cumulus; one whose base they cross, nothing. Distances for a 234 m texel at the
// default layer (1.5-4 km): at 25 deg (+-1.4 deg, a pixel) the ray is at 36-54% of the layer
// over 5.63 km, 68-92% over 7.5 km, and below 10% beyond 2 km only under 41 deg.
TEST(WeatherInversion, CarvingCapsTheColumnsTheClearSkyCrosses) {
  clouds::CloudParams p;
  const int size = 256;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, size, size, kW, kH, {});
  std::vector<float> photo(static_cast<size_t>(kW) * kH, 0.0f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      if (latlong::Latitude(y, kH) * 180.0 / kPi < 25.0) photo[static_cast<size_t>(y) * kW + x] = 1.0f;
  clouds::WeatherMap map = clouds::NoiseWeatherMap(1, size, p.weather_extent_m, {});
  const clouds::WeatherMap statistical = map;
  cloudfit::CarveCoverage(v, photo, {}, &map);
  const int stratus = TexelAtX(p, size, 5630.0), cumulus = TexelAtX(p, size, 7500.0), clear = TexelAtX(p, size, 2000.0);
  EXPECT_FLOAT_EQ(map.rgb[3 * stratus], 1.0f);
  EXPECT_FLOAT_EQ(map.rgb[3 * stratus + 2], 0.0f);
  EXPECT_FLOAT_EQ(map.rgb[3 * cumulus], 1.0f);
  EXPECT_FLOAT_EQ(map.rgb[3 * cumulus + 2], 0.5f);
  EXPECT_FLOAT_EQ(map.rgb[3 * clear], 0.0f);
  std::vector<char> seen(map.rgb.size() / 3, 0);
  for (const auto& s : v.rays) seen[static_cast<size_t>(s.texel)] = 1;
  ASSERT_GT(std::count(seen.begin(), seen.end(), 0), 0);  // the corners beyond the draw distance
  for (size_t t = 0; t < seen.size(); ++t) {
    if (seen[t]) {
      EXPECT_EQ(map.rgb[3 * t + 1], 0.0f) << t;  // no rain where the photo sees the layer
    } else {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(map.rgb[3 * t + c], statistical.rgb[3 * t + c]) << t;  // unseen: unchanged
    }
  }
  EXPECT_EQ(cloudfit::CloudTypeForTop(0.59), 0.0);
  EXPECT_EQ(cloudfit::CloudTypeForTop(0.6), 0.5);
}

// Refinement: a render that matches moves nothing; one too opaque (or too clear) everywhere
// thins (thickens) every texel a ray crosses below its cloud top by gain x the error; where
// the rays crossing a texel disagree it moves by gain x their mean, so clear rays hold down a
// texel that cloudy rays behind it ask for.
TEST(WeatherInversion, RefinementMovesTheTexelsBelowTheirTopsByTheMeanOfTheirRays) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  clouds::WeatherMap map = clouds::NoiseWeatherMap(1, kMap, p.weather_extent_m, {});
  for (size_t t = 0; t < map.rgb.size() / 3; ++t) {
    map.rgb[3 * t] = 0.5f;
    map.rgb[3 * t + 2] = (t % 3 == 0) ? 0.0f : 0.5f;  // some stratus (top 0.3), the rest cumulus (top 0.6)
  }
  const clouds::WeatherMap start = map;
  std::vector<float> photo(static_cast<size_t>(kW) * kH, 0.5f);
  EXPECT_EQ(cloudfit::RefineCoverage(v, photo, photo, 0.5, &map), 0.0);
  EXPECT_EQ(map.rgb, start.rgb);
  // Per texel, the links below its top, and the mean of a checkerboard of errors over them.
  std::vector<double> links(map.rgb.size() / 3, 0.0), checker(map.rgb.size() / 3, 0.0);
  for (const auto& s : v.rays) {
    const size_t t = static_cast<size_t>(s.texel);
    if (s.fraction > (start.rgb[3 * t + 2] > 0.25f ? 0.6f : 0.3f)) continue;
    links[t] += 1.0;
    checker[t] += (s.pixel % 2 == 0) ? 0.2 : -0.2;
  }
  std::vector<float> thicker(photo), thinner(photo), mixed(photo);
  for (float& o : thicker) o += 0.2f;
  for (float& o : thinner) o -= 0.2f;
  for (size_t i = 0; i < mixed.size(); ++i) mixed[i] += (i % 2 == 0) ? 0.2f : -0.2f;
  EXPECT_NEAR(cloudfit::RefineCoverage(v, photo, thicker, 0.5, &map), 0.2, 1e-6);
  int reached = 0;
  for (size_t t = 0; t < links.size(); ++t) EXPECT_NEAR(map.rgb[3 * t], links[t] > 0 ? 0.4f : 0.5f, 1e-6) << t;
  for (double l : links) reached += l > 0;
  EXPECT_GT(reached, 1000);
  map = start;
  EXPECT_NEAR(cloudfit::RefineCoverage(v, photo, thinner, 0.5, &map), 0.2, 1e-6);
  for (size_t t = 0; t < links.size(); ++t) EXPECT_NEAR(map.rgb[3 * t], links[t] > 0 ? 0.6f : 0.5f, 1e-6) << t;
  map = start;
  EXPECT_NEAR(cloudfit::RefineCoverage(v, photo, mixed, 0.5, &map), 0.2, 1e-6);
  int disagreeing = 0;
  for (size_t t = 0; t < links.size(); ++t) {
    const double want = links[t] > 0 ? 0.5 - 0.5 * checker[t] / links[t] : 0.5;
    EXPECT_NEAR(map.rgb[3 * t], want, 1e-6) << t;
    disagreeing += links[t] > 0 && std::abs(want - 0.5) < 0.099;  // crossed by clear and cloudy rays
  }
  EXPECT_GT(disagreeing, 100);
}

// The light's step (RefineByLight): with every pixel's log luminance 0.3 above the photo's and
// the raised render 0.6 below it (a response of -2 per unit precipitation), each pixel asks
// -(J r) / (J^2 + damping) = 0.6 / 4.001; the texels below their tops move by exactly that, the
// rest not at all. A photo brighter than the render lowers the channel (clamped at 0); the
// step is capped at max_step; pixels without a log luminance leave it to the opacity, which
// here asks nothing. The coverage is never touched. (A uniform photo: the steps' averaging over
// neighbouring pixels changes nothing; it is checked on stripes below.)
TEST(WeatherInversion, TheLightsStepMovesTheChannelByEachPixelsGaussNewtonStep) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  clouds::WeatherMap map = clouds::UniformWeatherMap(0.8, 0.2, 0.5, p.weather_extent_m);
  map = clouds::ResampleWeatherMap(map, kMap);
  const clouds::WeatherMap start = map;
  const size_t n = static_cast<size_t>(kW) * kH;
  const auto lit = [&](float ln_y) { return cloudfit::LitPixels{std::vector<float>(n, 0.9f), std::vector<float>(n, ln_y)}; };
  const cloudfit::LightRefineOptions o;  // precipitation, delta 0.3, max_step 0.5
  std::vector<double> links(map.rgb.size() / 3, 0.0);
  for (const auto& s : v.rays)
    if (s.fraction <= 0.6f) links[static_cast<size_t>(s.texel)] += 1.0;
  const auto expect_moved_by = [&](double step, int moved, const char* what) {
    int reached = 0;
    for (size_t t = 0; t < links.size(); ++t) {
      EXPECT_EQ(map.rgb[3 * t], start.rgb[3 * t]) << what << t;
      EXPECT_EQ(map.rgb[3 * t + 2], start.rgb[3 * t + 2]) << what << t;
      const double want = links[t] > 0 ? std::clamp(0.2 + step, 0.0, 1.0) : 0.2;
      EXPECT_NEAR(map.rgb[3 * t + 1], want, 1e-6) << what << t;
      reached += links[t] > 0;
    }
    EXPECT_EQ(moved, step == 0.0 ? 0 : reached) << what;
    EXPECT_GT(reached, 1000) << what;
  };
  cloudfit::LightRefineStep r = cloudfit::RefineByLight(v, lit(0.0f), lit(0.3f), lit(-0.3f), o, &map);
  EXPECT_NEAR(r.log_rms, 0.3, 1e-6);
  int linked_pixels = 0;
  for (size_t i = 0; i < v.rays.size(); ++i) linked_pixels += i == 0 || v.rays[i].pixel != v.rays[i - 1].pixel;
  EXPECT_EQ(r.pixels, linked_pixels);
  expect_moved_by(0.6 / 4.001, r.texels_moved, "darker photo: ");
  map = start;
  r = cloudfit::RefineByLight(v, lit(0.6f), lit(0.3f), lit(-0.3f), o, &map);
  expect_moved_by(-0.6 / 4.001, r.texels_moved, "brighter photo: ");
  map = start;
  r = cloudfit::RefineByLight(v, lit(-3.0f), lit(0.3f), lit(-0.3f), o, &map);
  expect_moved_by(0.5, r.texels_moved, "capped: ");
  map = start;
  r = cloudfit::RefineByLight(v, lit(std::nanf("")), lit(0.3f), lit(-0.3f), o, &map);
  EXPECT_EQ(r.pixels, 0);
  expect_moved_by(0.0, r.texels_moved, "no light: ");
  // A photo whose light alternates from column to column (+-0.3 about the render): each pixel
  // alone asks +-0.15, and the texels follow their few rays; the steps averaged over
  // neighbouring pixels (pixel_radius 1, the default) leave a third of that spread.
  std::vector<float> stripes(n);
  for (size_t i = 0; i < n; ++i) stripes[i] = (i % kW) % 2 == 0 ? 0.0f : 0.6f;
  const auto spread = [&](int radius) {
    cloudfit::LightRefineOptions ro;
    ro.pixel_radius = radius;
    map = start;
    cloudfit::RefineByLight(v, cloudfit::LitPixels{std::vector<float>(n, 0.9f), stripes}, lit(0.3f), lit(-0.3f), ro, &map);
    float lo = 1.0f, hi = 0.0f;
    for (size_t t = 0; t < links.size(); ++t)
      if (links[t] > 0) lo = std::min(lo, map.rgb[3 * t + 1]), hi = std::max(hi, map.rgb[3 * t + 1]);
    return hi - lo;
  };
  const float raw = spread(0), smoothed = spread(1);
  EXPECT_GT(raw, 0.2f);
  EXPECT_LT(smoothed, 0.5f * raw);
  // Bad input, named.
  cloudfit::LightRefineOptions bad;
  bad.channel = 2;
  try {
    cloudfit::RefineByLight(v, lit(0.0f), lit(0.3f), lit(-0.3f), bad, &map);
    ADD_FAILURE() << "channel 2 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("LightRefineOptions::channel"), std::string::npos) << e.what();
  }
  cloudfit::LitPixels short_photo = lit(0.0f);
  short_photo.log_luminance.pop_back();
  try {
    cloudfit::RefineByLight(v, short_photo, lit(0.3f), lit(-0.3f), o, &map);
    ADD_FAILURE() << "a short photo accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("photo"), std::string::npos) << e.what();
  }
  // The raised map: the channel of the constrained texels only, at most 1.
  const clouds::WeatherMap raised = cloudfit::RaisedMap(v, start, o);
  for (size_t t = 0; t < links.size(); ++t)
    EXPECT_NEAR(raised.rgb[3 * t + 1], v.linked[t] ? 0.5f : 0.2f, 1e-6) << t;
}

// Resolution by distance: a map of one value stays one value; a lone far texel spreads over
// its neighbours; a texel overhead (wider than a pixel) keeps its value.
TEST(WeatherInversion, SmoothingFollowsThePixelFootprint) {
  clouds::CloudParams p;
  const int size = 256;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, size, size, kW, kH, {});
  clouds::WeatherMap map = clouds::NoiseWeatherMap(1, size, p.weather_extent_m, {});
  for (size_t t = 0; t < map.rgb.size() / 3; ++t) map.rgb[3 * t] = 0.25f;
  clouds::WeatherMap smoothed = map;
  cloudfit::SmoothCoverageByFootprint(v, p.weather_extent_m, &smoothed);
  for (size_t t = 0; t < map.rgb.size(); ++t) EXPECT_FLOAT_EQ(smoothed.rgb[t], map.rgb[t]) << t;
  // A pixel of a 128-wide lat-long spans 2.8 deg: 1 km across at 20 km, half of it 2 texels.
  const int far = TexelAtX(p, size, 20000.0), zenith = TexelAtX(p, size, 100.0);
  map.rgb[3 * far] = 1.0f;
  map.rgb[3 * zenith] = 1.0f;
  cloudfit::SmoothCoverageByFootprint(v, p.weather_extent_m, &map);
  EXPECT_FLOAT_EQ(map.rgb[3 * zenith], 1.0f);
  EXPECT_NEAR(map.rgb[3 * far], 0.25f + 0.75f / 25.0f, 1e-6);  // a 5 x 5 box
  EXPECT_NEAR(map.rgb[3 * (far + 1)], 0.25f + 0.75f / 25.0f, 1e-6);
}


// A frame later in the wind sees the same sky through the map moved under it: with the wind
// blowing toward +x (azimuth 90), the march samples camera-relative x at x - speed x time
// (clouds/src/resolved_clouds.cc), so each ray meets the texels of the frame at time 0 moved
// by whole texels (speed x time a multiple of the texel here), and the camera stands there on
// the map. Control: the opposite shift matches almost none of the samples.
TEST(WeatherInversion, ALaterFrameSeesTheMapMovedByTheWind) {
  clouds::CloudParams p;
  p.wind_direction_deg = 90.0;
  p.wind_speed_m_s = 10.0;
  const double texel_m = p.weather_extent_m / kMap, t = 3.0 * texel_m / p.wind_speed_m_s;  // 3 texels
  const cloudfit::WeatherTexelView v0 = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  const cloudfit::WeatherTexelView v1 = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {}, t);
  ASSERT_EQ(v1.cameras.size(), 1u);
  EXPECT_NEAR(v1.cameras[0][0], -3.0 * texel_m, 1e-6);
  EXPECT_NEAR(v1.cameras[0][1], 0.0, 1e-6);
  const auto moved = [](int texel, int columns) { return texel / kMap * kMap + ((texel % kMap + columns) % kMap + kMap) % kMap; };
  // Rays and centre links alike (a texel's centre moves with it); a sample on a texel's edge may
  // round to its neighbour.
  std::vector<std::pair<int, int>> a, b;
  for (const auto& s : v0.rays) a.push_back({s.pixel, s.texel});
  for (const auto& s : v1.rays) b.push_back({s.pixel, s.texel});
  std::sort(b.begin(), b.end());
  const double samples = static_cast<double>(a.size());
  int along = 0, against = 0;
  for (const auto& [pix, texel] : a) {
    along += std::binary_search(b.begin(), b.end(), std::pair(pix, moved(texel, -3)));
    against += std::binary_search(b.begin(), b.end(), std::pair(pix, moved(texel, 3)));
  }
  EXPECT_GE(along, 0.99 * samples);
  EXPECT_LT(against, 0.5 * samples);
}

// Frames stacked: frame k's pixels follow frame k-1's, a texel is linked when any frame links
// it, the cameras are kept in order; frames of another size are refused by name.
TEST(WeatherInversion, StackedFramesKeepEachFramesRays) {
  clouds::CloudParams p;
  const std::vector<float> east = [] {
    std::vector<float> s(static_cast<size_t>(kW) * kH, 0.0f);
    for (int y = 0; y < kH; ++y)
      for (int x = kW / 2; x < kW; ++x) s[static_cast<size_t>(y) * kW + x] = 1.0f;
    return s;
  }();
  std::vector<float> west(east.size());
  for (size_t i = 0; i < east.size(); ++i) west[i] = 1.0f - east[i];
  const cloudfit::WeatherTexelView a = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, east);
  const cloudfit::WeatherTexelView b = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, west, 60.0);
  const cloudfit::WeatherTexelView s = cloudfit::StackWeatherViews({a, b});
  EXPECT_EQ(s.width, kW);
  EXPECT_EQ(s.height, 2 * kH);
  ASSERT_EQ(s.rays.size(), a.rays.size() + b.rays.size());
  for (size_t k = 0; k < a.rays.size(); ++k) EXPECT_EQ(s.rays[k].pixel, a.rays[k].pixel);
  for (size_t k = 0; k < b.rays.size(); ++k) {
    EXPECT_EQ(s.rays[a.rays.size() + k].pixel, b.rays[k].pixel + kW * kH);
    EXPECT_EQ(s.rays[a.rays.size() + k].texel, b.rays[k].texel);
  }
  int either = 0;
  for (size_t t = 0; t < s.linked.size(); ++t) {
    EXPECT_EQ(s.linked[t], a.linked[t] | b.linked[t]) << t;
    either += a.linked[t] | b.linked[t];
  }
  EXPECT_EQ(s.constrained, either);
  EXPECT_GT(s.constrained, std::max(a.constrained, b.constrained));
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.cameras[1], b.cameras[0]);
  EXPECT_THROW(cloudfit::StackWeatherViews({a, cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW / 2, kH / 2, {})}), Error);
  EXPECT_THROW(cloudfit::StackWeatherViews({}), Error);
}

// Coverage read from the light (RefineCoverageByLight) on a toy forward model with a known
// answer: a pixel's ln Y is the coverage of the texels its ray crosses, each weighing half the
// one before it (as a march's transmittance falls), less 1.5 times that of the texels two
// columns east of them (the shadow they sit in: 0.8), and every pixel is
// opaque whatever the coverage (the opacity says nothing). From the truth with each texel
// 0.15 off (the sign at random), the random perturbations tell a texel's own effect from its
// shadow on others: the light's RMS falls below 0.75 of the start's in 8 steps (0.60 here) and
// below half in 30 (0.35). Control: the step from one render with every texel raised at once
// (RefineByLight on coverage) sees only the sum, 1 - 0.8, steps five times too far and moves
// the light away (0.092 -> 0.221).
TEST(WeatherInversion, CoverageIsReadFromTheLightTexelByTexel) {
  clouds::CloudParams p;
  const cloudfit::WeatherTexelView v = cloudfit::ProjectWeatherTexels(p, kMap, kMap, kW, kH, {});
  const size_t n = static_cast<size_t>(kW) * kH;
  const auto east = [](int t) { return t / kMap * kMap + (t % kMap + 2) % kMap; };
  constexpr double kShadow = 0.8;
  const auto render = [&](const clouds::WeatherMap& m) {
    cloudfit::LitPixels out{std::vector<float>(n, 0.0f), std::vector<float>(n, std::nanf(""))};
    for (size_t b = 0; b < v.rays.size();) {
      size_t e = b;
      double own = 0.0, shadow = 0.0, w = 1.0, sum = 0.0;
      for (; e < v.rays.size() && v.rays[e].pixel == v.rays[b].pixel; ++e, w *= 0.5) {
        own += w * m.rgb[3 * static_cast<size_t>(v.rays[e].texel)];
        shadow += w * m.rgb[3 * static_cast<size_t>(east(v.rays[e].texel))];
        sum += w;
      }
      const size_t pix = static_cast<size_t>(v.rays[b].pixel);
      out.opacity[pix] = 1.0f;
      out.log_luminance[pix] = static_cast<float>((own - kShadow * shadow) / sum);
      b = e;
    }
    return out;
  };
  clouds::WeatherMap truth = clouds::ResampleWeatherMap(clouds::UniformWeatherMap(0.5, 0.0, 0.5, p.weather_extent_m), kMap);
  for (int j = 0; j < kMap; ++j)
    for (int i = 0; i < kMap; ++i) truth.rgb[3 * (static_cast<size_t>(j) * kMap + i)] = static_cast<float>(0.5 + 0.2 * std::sin(0.3 * i) * std::cos(0.2 * j));
  clouds::WeatherMap start = truth;
  std::mt19937 rng(7);
  for (size_t t = 0; t < start.rgb.size() / 3; ++t) start.rgb[3 * t] += (rng() & 1u) ? 0.15f : -0.15f;
  const cloudfit::LitPixels photo = render(truth);
  clouds::WeatherMap map = start;
  cloudfit::CoverageLightOptions o;
  o.iterations = 30;
  const cloudfit::CoverageLightResult r = cloudfit::RefineCoverageByLight(v, photo, render, o, &map);
  ASSERT_EQ(r.log_rms.size(), 31u);
  std::cout << "[coverage by light] ln Y RMS " << r.log_rms.front() << " -> " << r.log_rms[8] << " (8 steps) -> "
            << r.log_rms.back() << ", " << r.kept << " of 30 steps kept\n";
  EXPECT_GT(r.log_rms.front(), 0.05);
  EXPECT_LT(r.log_rms[8], 0.75 * r.log_rms.front());
  EXPECT_LT(r.log_rms.back(), 0.5 * r.log_rms.front());
  for (size_t k = 1; k < r.log_rms.size(); ++k) EXPECT_LE(r.log_rms[k], r.log_rms[k - 1] + 1e-12) << k;  // kept only when it falls
  for (size_t t = 0; t < map.rgb.size() / 3; ++t)
    if (!v.linked[t]) {
      EXPECT_EQ(map.rgb[3 * t], start.rgb[3 * t]) << t;
    }
  // The control: every texel raised at once.
  clouds::WeatherMap global = start;
  cloudfit::LightRefineOptions g;
  g.channel = 0;
  g.pixel_radius = 0;
  const cloudfit::LitPixels at = render(global);
  cloudfit::RefineByLight(v, photo, at, render(cloudfit::RaisedMap(v, global, g)), g, &global);
  const double before = r.log_rms.front(), after = cloudfit::RefineCoverageByLight(v, photo, render, [] {
    cloudfit::CoverageLightOptions none;
    none.iterations = 0;
    return none;
  }(), &global).log_rms.front();
  std::cout << "[coverage by light] control, every texel raised at once: ln Y RMS " << before << " -> " << after << "\n";
  EXPECT_GT(after, before);
  // Bad options and sizes are named.
  cloudfit::CoverageLightOptions bad;
  bad.delta = 0.0;
  try {
    cloudfit::RefineCoverageByLight(v, photo, render, bad, &map);
    ADD_FAILURE() << "delta 0 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("CoverageLightOptions::delta"), std::string::npos) << e.what();
  }
  cloudfit::LitPixels short_photo = photo;
  short_photo.opacity.pop_back();
  EXPECT_THROW(cloudfit::RefineCoverageByLight(v, short_photo, render, {}, &map), Error);
}

}  // namespace
}  // namespace skycal
