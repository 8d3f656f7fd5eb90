// The kind of sky (capture/sky_kind.h): its rules on constructed statistics, its
// statistics on constructed frames, and each bundled real frame classified.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_kind.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "skycal/skysun/find_sun.h"

namespace skycal {
namespace {

const std::string kRoot = SKYCAL_SOURCE_DIR;
// The disc contrast calibrate asks of a sun (a twilight glow or the moon reach tens to a
// hundred times the median sky; a sun disc thousands).
constexpr double kCalibrateDiscContrast = 300.0;

capture::SkyFeatures ClearDay() {
  capture::SkyFeatures f;
  f.sky_share = 0.9;
  f.zenith_sky_share = 1.0;
  f.zenith_blue = 1.2;
  f.cloud_share = 0.05;
  f.texture = 0.002;
  f.point_sources = 0.0;
  f.sun_elevation_deg = 30.0;
  return f;
}

// Each rule at its threshold: one side and the other.
TEST(SkyKind, EachRuleDecidesAtItsThreshold) {
  const capture::SkyKindOptions o;
  auto kind = [&](const capture::SkyFeatures& f) { return capture::ClassifySky(f, o).kind; };
  capture::SkyFeatures f = ClearDay();
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f.sky_share = 0.249;
  EXPECT_EQ(kind(f), capture::SkyKind::kNotSky);
  f = ClearDay();
  f.zenith_sky_share = 0.499;  // enough sky around, but a roof overhead
  EXPECT_EQ(kind(f), capture::SkyKind::kNotSky);
  EXPECT_NE(capture::ClassifySky(f, o).reason.find("min_zenith_sky_share 0.5"), std::string::npos);
  f.zenith_sky_share = 0.5;
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f = ClearDay();
  f.zenith_blue = -0.21;  // redder than any sky overhead: a lamp-lit ceiling
  EXPECT_EQ(kind(f), capture::SkyKind::kNotSky);
  f.zenith_blue = -0.19;
  f.point_sources = 5e-4;  // with stars, no sun known: a night sky
  f.sun_elevation_deg.reset();
  EXPECT_EQ(kind(f), capture::SkyKind::kNight);
  f = ClearDay();
  f.sun_elevation_deg = -18.0;
  EXPECT_EQ(kind(f), capture::SkyKind::kNight);
  f.sun_elevation_deg = -17.9;
  EXPECT_EQ(kind(f), capture::SkyKind::kTwilight);
  f.sun_elevation_deg = 0.0;
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f = ClearDay();
  f.point_sources = 5e-4;  // stars, but a blue zenith: a day sky (noise, not stars)
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f.zenith_blue = 0.2;  // stars under a grey-orange zenith, the sun known up (given): not night
  EXPECT_NE(kind(f), capture::SkyKind::kNight);
  f.sun_from_disc = true;  // ... the "sun" a disc the detector found (a lamp): night
  EXPECT_EQ(kind(f), capture::SkyKind::kNight);
  f = ClearDay();
  f.cloud_share = 0.7;
  EXPECT_EQ(kind(f), capture::SkyKind::kOvercast);
  f.texture = 0.02;  // mostly cloud, but broken: clouds to place, not one deck
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  f = ClearDay();
  f.zenith_blue = 0.3;  // grey and smooth: a deck
  EXPECT_EQ(kind(f), capture::SkyKind::kOvercast);
  f.texture = 0.01;  // grey with cloud edges: broken cloud
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  f = ClearDay();
  f.texture = 0.0099;
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f.texture = 0.01;
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  EXPECT_NE(capture::ClassifySky(f, o).reason.find("cloudy_texture 0.01"), std::string::npos);
  // A noise-free sky (a game's render): the median on the clear sky, cloud edges in the upper
  // quartile. Blue: partly cloudy; grey or mostly cloud: broken cloud, not one deck.
  f = ClearDay();
  f.texture = 0.001;
  f.texture_q75 = 0.0499;
  EXPECT_EQ(kind(f), capture::SkyKind::kClear);
  f.texture_q75 = 0.05;
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  EXPECT_NE(capture::ClassifySky(f, o).reason.find("cloudy_texture_q75 0.05"), std::string::npos);
  f.cloud_share = 0.7;
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  f.cloud_share = 0.05;
  f.zenith_blue = 0.3;
  EXPECT_EQ(kind(f), capture::SkyKind::kPartlyCloudy);
  f.texture_q75 = 0.0499;
  EXPECT_EQ(kind(f), capture::SkyKind::kOvercast);
}

TEST(SkyKind, OptionsNameTheFieldAndValue) {
  capture::SkyKindOptions o;
  o.min_sky_share = 1.5;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "SkyKindOptions::min_sky_share = 1.5 (expected (0, 1))");
  o = {};
  o.night_sun_deg = -2.0;
  o.twilight_sun_deg = -3.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("SkyKindOptions::night_sun_deg = -2"), std::string::npos) << why;
  EXPECT_THROW(capture::ClassifySky(ClearDay(), o), Error);
}

// The statistics on frames whose answer is known: the model's clear sky is blue and smooth,
// a uniform grey frame is a deck, scattered bright points are stars, and a mask with little
// sky is not a sky.
TEST(SkyKind, StatisticsOfConstructedFrames) {
  const render::Preset clear = render::LoadPreset(kRoot + "/datasets/presets/default_clear.json");
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(30.0, 20.0);
  req.width = 256;
  req.height = 128;
  req.sun_disc = false;
  const ImageRGB sky = render::CreateRenderer(render::Backend::kCpu)->Render(clear, req);
  const std::vector<float> all(static_cast<size_t>(256) * 128, 1.0f);
  const auto f = capture::MeasureSkyFeatures(sky, all, {}, 30.0);
  EXPECT_NEAR(f.sky_share, 1.0, 1e-12);
  EXPECT_NEAR(f.zenith_sky_share, 1.0, 1e-12);
  EXPECT_GT(f.zenith_blue, 0.5);
  EXPECT_LT(f.texture, 0.005);
  EXPECT_EQ(f.point_sources, 0.0);
  EXPECT_TRUE(std::isnan(f.cloud_share));
  EXPECT_EQ(capture::ClassifySky(f, {}).kind, capture::SkyKind::kClear);

  // The texture is measured at one angular scale: the same clear sky as a thumbnail (a
  // smooth gradient is 4x steeper per pixel at a quarter of the width) is still clear.
  req.width = 64;
  req.height = 32;
  const ImageRGB thumb = render::CreateRenderer(render::Backend::kCpu)->Render(clear, req);
  const auto t = capture::MeasureSkyFeatures(thumb, std::vector<float>(64 * 32, 1.0f), {}, 30.0);
  EXPECT_LT(t.texture, 0.005);
  EXPECT_EQ(capture::ClassifySky(t, {}).kind, capture::SkyKind::kClear);

  // Without noise (a game's render): the same clear sky with textured clouds over a third of
  // the upper hemisphere's rows leaves the median texture at the clear sky's, its upper
  // quartile on the clouds: partly cloudy. The clear sky alone (the control) is not.
  EXPECT_LT(f.texture_q75, 0.05);
  ImageRGB cloudy = sky;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 256; ++x)
      if ((x / 32) % 3 == 0 && y > 8)
        for (int c = 0; c < 3; ++c) cloudy.at(x, y, c) = 5e3f * (1.0f + 0.6f * std::sin(1.3f * x) * std::sin(1.1f * y));
  const auto k = capture::MeasureSkyFeatures(cloudy, all, {}, 30.0);
  EXPECT_LT(k.texture, 0.01);
  EXPECT_GE(k.texture_q75, 0.05);
  EXPECT_EQ(capture::ClassifySky(k, {}).kind, capture::SkyKind::kPartlyCloudy);

  ImageRGB grey(256, 128);
  for (float& v : grey.pixels) v = 2.0f;
  const auto g = capture::MeasureSkyFeatures(grey, all, {}, std::nullopt);
  EXPECT_NEAR(g.zenith_blue, 0.0, 1e-6);
  EXPECT_NEAR(g.texture, 0.0, 1e-6);
  EXPECT_NEAR(g.sky_luminance, 2.0, 1e-5);
  EXPECT_EQ(capture::ClassifySky(g, {}).kind, capture::SkyKind::kOvercast);
  for (int y = 4; y < 40; y += 6)
    for (int x = 3; x < 256; x += 9)
      for (int c = 0; c < 3; ++c) grey.at(x, y, c) = 20.0f;
  const auto n = capture::MeasureSkyFeatures(grey, all, {}, std::nullopt);
  EXPECT_GT(n.point_sources, 4e-4);
  EXPECT_EQ(capture::ClassifySky(n, {}).kind, capture::SkyKind::kNight);

  std::vector<float> little(all.size(), 0.0f);
  for (size_t i = 0; i < little.size() / 20; ++i) little[i] = 1.0f;  // the top rows only
  EXPECT_LT(capture::MeasureSkyFeatures(sky, little, {}, 30.0).sky_share, 0.25);
  // A roof over the zenith, open sky below 45 degrees (rows 32-63 of 128 are 0.7-45 deg up):
  // about 0.7 of the upper hemisphere's solid angle is sky (sin 45 deg), none of the cap.
  std::vector<float> roofed(all.size(), 0.0f);
  for (int y = 32; y < 64; ++y)
    for (int x = 0; x < 256; ++x) roofed[static_cast<size_t>(y) * 256 + x] = 1.0f;
  const auto r = capture::MeasureSkyFeatures(sky, roofed, {}, 30.0);
  EXPECT_NEAR(r.zenith_sky_share, 0.0, 1e-12);
  EXPECT_GT(r.sky_share, 0.25);
  EXPECT_EQ(capture::ClassifySky(r, {}).kind, capture::SkyKind::kNotSky);
  EXPECT_THROW(capture::MeasureSkyFeatures(sky, std::vector<float>(10, 1.0f), {}, 30.0), Error);
}

struct RealCase {
  const char* frame;
  capture::SkyKind expected;
};

TEST(SkyKind, EachBundledRealFrame) {
  const RealCase cases[] = {{"sunrise", capture::SkyKind::kClear},      {"sunset", capture::SkyKind::kClear},
                            {"sky", capture::SkyKind::kPartlyCloudy},  {"dawn", capture::SkyKind::kTwilight},
                            {"city", capture::SkyKind::kOvercast},     {"forest", capture::SkyKind::kNotSky},
                            {"night", capture::SkyKind::kNight}};
  const render::Preset clear = render::LoadPreset(kRoot + "/datasets/presets/default_clear.json");
  for (const auto& c : cases) {
    const std::string path = kRoot + "/datasets/real/" + c.frame + ".exr";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent: run datasets/fetch_real_skies.sh";
    const auto frame = capture::ReadLatLongFrame(path);
    std::string why;
    const auto sun = skysun::FindSun(frame.radiance, kCalibrateDiscContrast, {}, &why);
    std::optional<std::array<double, 3>> sun_dir;
    if (sun) sun_dir = sun->direction;
    const capture::SkyMask m = capture::EstimateSkyMask(frame.radiance, sun_dir, {});
    std::vector<float> prob;
    if (sun_dir) {
      render::RenderRequest req;
      req.sun_dir = *sun_dir;
      req.width = frame.radiance.width;
      req.height = frame.radiance.height;
      req.sun_disc = false;
      const ImageRGB clear_sky = render::CreateRenderer(render::Backend::kCpu)->Render(clear, req);
      prob = capture::EstimateCloudProbability(frame.radiance, clear_sky, sun_dir, {}).probability;
    }
    std::optional<double> el;
    if (sun_dir) el = latlong::ElevationDeg(*sun_dir);
    auto f = capture::MeasureSkyFeatures(frame.radiance, m.sky, prob, el);
    f.sun_from_disc = sun && sun->source == "disc";
    const auto d = capture::ClassifySky(f, {});
    std::cout << "[sky kind] " << c.frame << ": sky share " << f.sky_share << ", zenith ln(B/R) " << f.zenith_blue
              << ", cloud share " << f.cloud_share << ", texture " << f.texture << ", point sources " << f.point_sources
              << ", sun " << (sun ? std::to_string(*el) + " deg (" + sun->source + ")" : "not found") << " -> "
              << capture::ToString(d.kind) << " (" << d.reason << ")\n";
    EXPECT_EQ(capture::ToString(d.kind), std::string(capture::ToString(c.expected))) << c.frame << ": " << d.reason;
  }
}

}  // namespace
}  // namespace skycal
