// The photo's cloud opacity by unmixing (capture/cloud_opacity.h):
//   - exact on the compositing model it inverts (L = T S + b w), where the colour ramp's
//     probability is not (the control);
//   - on a sky the game's own march draws (CPU model, the bundled cloudy preset, a noise
//     weather map), nearer the true opacity 1 - T than the probability, by a stated margin;
//   - the probability standing in where the sky and the clouds have one colour; sizes and
//     options refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/cloud_opacity.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/composite.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal {
namespace {

constexpr int kW = 128, kH = 64;

// RMS of a - b over the pixels above the horizon.
double RmsAboveHorizon(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0.0, n = 0.0;
  for (int y = 0; y < kH; ++y) {
    if (latlong::Latitude(y, kH) <= 0.0) continue;
    for (int x = 0; x < kW; ++x) {
      const size_t i = static_cast<size_t>(y) * kW + x;
      s += (a[i] - b[i]) * (a[i] - b[i]);
      n += 1.0;
    }
  }
  return std::sqrt(s / n);
}

TEST(CloudOpacity, ExactOnTheCompositingModelWhereTheProbabilityIsNot) {
  ImageRGB sky(kW, kH), frame(kW, kH);
  std::vector<float> truth(static_cast<size_t>(kW) * kH, 0.0f), probability(truth.size(), 0.0f);
  const double w[3] = {0.36, 0.33, 0.31};  // the clouds' colour (sums to 1)
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = static_cast<size_t>(y) * kW + x;
      const double up = std::max(0.0, std::sin(latlong::Latitude(y, kH)));
      const double s[3] = {0.2 + 0.3 * (1.0 - up), 0.4 + 0.2 * (1.0 - up), 1.0};  // blue overhead, paler below
      const double t = std::clamp(0.5 + 0.8 * std::sin(0.2 * x) * std::cos(0.3 * y), 0.0, 1.0);  // 0 in the cores
      const double b = 2.0 * (1.0 - t) * (0.5 + 0.5 * std::cos(0.1 * x));       // the clouds' light, >= 0
      for (int c = 0; c < 3; ++c) {
        sky.at(x, y, c) = static_cast<float>(s[c]);
        frame.at(x, y, c) = static_cast<float>(t * s[c] + b * w[c]);
      }
      truth[i] = latlong::Latitude(y, kH) > 0.0 ? static_cast<float>(1.0 - t) : 0.0f;
      probability[i] = t == 0.0 ? 1.0f : 0.0f;  // a ramp: sure where opaque, blind to the rest
    }
  const capture::CloudOpacity o = capture::EstimateCloudOpacity(frame, sky, probability, {}, {});
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(o.cloud_colour[c], w[c], 1e-6);
  EXPECT_GT(o.colour_pixels, 16);
  EXPECT_EQ(o.from_probability, 0);
  EXPECT_LT(RmsAboveHorizon(o.opacity, truth), 1e-5);
  EXPECT_GT(RmsAboveHorizon(probability, truth), 0.2);  // control
}

TEST(CloudOpacity, NearerTheGamesTrueOpacityThanTheProbability) {
  const std::string presets = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/";
  const render::Preset cloudy = render::LoadPreset(presets + "default_cloudy.json");
  const clouds::CloudNoise noise = clouds::LoadOrGenerateCloudNoise(1, clouds::UsableCloudNoiseCacheDir());
  clouds::CloudParams params;
  const clouds::WeatherMap map = clouds::NoiseWeatherMap(3, 128, params.weather_extent_m, {});
  for (const double elevation : {25.0, 55.0}) {
    render::RenderRequest sr;
    sr.sun_dir = latlong::DirectionFromElevationAzimuthDeg(elevation, 60.0);
    sr.width = kW;
    sr.height = kH;
    sr.sun_disc = false;
    const ImageRGB sky = render::CreateRenderer(render::Backend::kCpu)->Render(cloudy, sr);
    clouds::CloudRenderRequest cr;
    cr.width = kW;
    cr.height = kH;
    cr.sun_dir = sr.sun_dir;
    const clouds::CloudImage image =
        clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2)->Render({&cloudy, &params, &noise, &map}, cr);
    const ImageRGB frame = clouds::CompositeClouds(sky, image);
    std::vector<float> truth(image.transmittance.size());
    for (size_t i = 0; i < truth.size(); ++i) truth[i] = 1.0f - image.transmittance[i];
    const std::vector<float> p = capture::EstimateCloudProbability(frame, sky, sr.sun_dir, {}).probability;
    const capture::CloudOpacity o = capture::EstimateCloudOpacity(frame, sky, p, {}, {});
    const double unmixed = RmsAboveHorizon(o.opacity, truth), ramp = RmsAboveHorizon(p, truth);
    std::cout << "[cloud opacity] sun " << elevation << " deg: RMS against the truth, unmixed " << unmixed
              << ", probability " << ramp << "\n";
    // Measured 0.079 / 0.37 at 25 deg and 0.018 / 0.30 at 55 deg (noise seed 3, the sky
    // behind known exactly): a thin cloud lit by the sun and a far hazy one are what the
    // ramp gets wrong.
    EXPECT_LT(unmixed, 0.7 * ramp);
    EXPECT_LT(unmixed, 0.2);
  }
}

TEST(CloudOpacity, TheProbabilityStandsInWhereSkyAndCloudsShareAColour) {
  ImageRGB sky(kW, kH), frame(kW, kH);
  std::vector<float> probability(static_cast<size_t>(kW) * kH, 0.25f);
  for (float& v : sky.pixels) v = 1.0f;   // a white sky
  for (float& v : frame.pixels) v = 2.0f;  // and white clouds
  const capture::CloudOpacity o = capture::EstimateCloudOpacity(frame, sky, probability, {}, {});
  EXPECT_EQ(o.unmixed, 0);
  EXPECT_EQ(o.from_probability, static_cast<long long>(kW) * kH / 2);  // the upper half
  EXPECT_EQ(o.colour_pixels, 0);                                       // none sure: grey
  EXPECT_FLOAT_EQ(o.opacity[0], 0.25f);
  EXPECT_FLOAT_EQ(o.opacity.back(), 0.0f);  // below the horizon
}

TEST(CloudOpacity, SizesAndOptionsRefusedByName) {
  const ImageRGB a(kW, kH), b(kW / 2, kH / 2);
  const std::vector<float> p(static_cast<size_t>(kW) * kH, 0.0f);
  try {
    capture::EstimateCloudOpacity(a, b, p, {}, {});
    FAIL() << "a clear sky of another size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the clear sky is 64x32, the frame 128x64"), std::string::npos) << e.what();
  }
  EXPECT_THROW(capture::EstimateCloudOpacity(a, a, std::vector<float>(3), {}, {}), Error);
  EXPECT_THROW(capture::EstimateCloudOpacity(a, a, p, std::vector<float>(3), {}), Error);
  capture::CloudOpacityOptions o;
  o.min_separation = 1.5;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("CloudOpacityOptions::min_separation = 1.5"), std::string::npos) << why;
}

}  // namespace
}  // namespace skycal
