// The game render controller (controllers/game_render.h): the exposure scales the radiance
// and nothing else, the file entry point writes exactly the image the in-memory one
// returns, and a bad option is refused naming its field and value.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "skycal/capture/latlong_frame.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "test_util.h"

namespace skycal {
namespace {

controllers::GameRenderOptions Small() {
  controllers::GameRenderOptions o;
  o.backend = render::Backend::kCpu;  // the double reference: no device needed
  o.width = 64;
  o.height = 32;
  o.sun_dir = latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0);
  o.verbose = false;
  return o;
}

double Mean(const ImageRGB& image) {
  double sum = 0.0;
  for (float v : image.pixels) sum += v;
  return sum / static_cast<double>(image.pixels.size());
}

TEST(GameRender, ExposureTwoIsExactlyTwiceTheRadiance) {
  controllers::GameRenderOptions o = Small();
  const controllers::GameImage one = controllers::RenderGameImage(o);
  o.exposure = 2.0;
  const controllers::GameImage two = controllers::RenderGameImage(o);
  ASSERT_EQ(one.radiance.width, 64);
  ASSERT_EQ(one.radiance.height, 32);
  ASSERT_EQ(two.radiance.pixels.size(), one.radiance.pixels.size());
  EXPECT_GT(Mean(one.radiance), 100.0);  // a daylight sky, cd/m^2: not an empty image
  long long differ = 0;
  for (size_t i = 0; i < one.radiance.pixels.size(); ++i) differ += two.radiance.pixels[i] != 2.0f * one.radiance.pixels[i];
  EXPECT_EQ(differ, 0);
  EXPECT_FALSE(one.clouds_drawn);
  EXPECT_TRUE(one.cloud_transmittance.empty());
  EXPECT_EQ(one.preset_path, controllers::DefaultPresetPath());
  EXPECT_NEAR(one.summary.at("sun_elevation_deg").get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(one.summary.at("sun_azimuth_deg").get<double>(), 40.0, 1e-9);
  EXPECT_FALSE(one.summary.contains("exposure"));
  EXPECT_EQ(two.summary.at("exposure").get<double>(), 2.0);
}

TEST(GameRender, TheFileHoldsTheInMemoryImage) {
  testing::ScratchDir dir("game-render");
  controllers::GameRenderFileOptions f;
  f.render = Small();
  f.render.exposure = 2.0;
  f.out_exr = dir / "sky.exr";
  f.time_of_day_h = 9.5;
  const nlohmann::json summary = controllers::WriteGameRender(f);
  const controllers::GameImage g = controllers::RenderGameImage(f.render);
  const capture::LatLongFrame frame = capture::ReadLatLongFrame(f.out_exr);
  ASSERT_EQ(frame.radiance.width, 64);
  ASSERT_EQ(frame.radiance.height, 32);
  long long differ = 0;
  for (size_t i = 0; i < g.radiance.pixels.size(); ++i) differ += frame.radiance.pixels[i] != g.radiance.pixels[i];
  EXPECT_EQ(differ, 0);
  ASSERT_TRUE(frame.sun_direction.has_value());
  for (int k = 0; k < 3; ++k) EXPECT_NEAR((*frame.sun_direction)[k], g.sun_dir[k], 1e-7);  // a float attribute
  EXPECT_EQ(frame.extra.floats.at("skycalExposure"), 2.0f);
  EXPECT_EQ(frame.extra.floats.at("skycalTimeOfDay"), 9.5f);
  EXPECT_EQ(frame.extra.strings.at("skycalPreset"), controllers::DefaultPresetPath());
  EXPECT_EQ(summary.at("out").get<std::string>(), f.out_exr);
  EXPECT_TRUE(summary.at("png").is_null());
  EXPECT_NEAR(summary.at("radiance_cd_m2").at("mean").get<double>(), Mean(g.radiance), 1e-9 * Mean(g.radiance));
  EXPECT_EQ(dir.CountEntries(), 1);  // the EXR alone: no temporaries left
}

// time_ms.gpu: each Vulkan pass's device time by timestamps (lavapipe writes them), > 0 and
// within the pass's wall time; null for the CPU backend and for a pass not drawn.
TEST(GameRender, DeviceTimePerPassBesideTheWallTime) {
  controllers::GameRenderOptions o = Small();
  o.width = 256;
  o.height = 128;
  o.backend = render::Backend::kVulkan;
  o.clouds.enabled = true;
  o.clouds.march.steps_zenith = 8;
  o.clouds.march.steps_horizon = 16;
  const nlohmann::json t = controllers::RenderGameImage(o).summary.at("time_ms");
  for (const char* pass : {"sky", "clouds"}) {
    ASSERT_TRUE(t.at("gpu").at(pass).is_number()) << pass << ": " << t.dump();
    EXPECT_GT(t["gpu"][pass].get<double>(), 0.0) << pass;
    EXPECT_LE(t["gpu"][pass].get<double>(), t.at(pass).get<double>()) << pass;
  }
  o.clouds.enabled = false;
  EXPECT_TRUE(controllers::RenderGameImage(o).summary["time_ms"]["gpu"]["clouds"].is_null());
  const nlohmann::json cpu = controllers::RenderGameImage(Small()).summary["time_ms"]["gpu"];
  EXPECT_TRUE(cpu["sky"].is_null());
  EXPECT_TRUE(cpu["clouds"].is_null());
}

TEST(GameRender, ABadOptionNamesItsFieldAndValue) {
  controllers::GameRenderOptions o = Small();
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.exposure = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "GameRenderOptions::exposure = 0 (expected a finite scale > 0)");
  try {
    controllers::RenderGameImage(o);
    ADD_FAILURE() << "an exposure of 0 rendered";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), why);
  }
  o.exposure = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "GameRenderOptions::exposure = inf (expected a finite scale > 0)");
  o = Small();
  o.sun_dir = {0.0, 2.0, 0.0};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "GameRenderOptions::sun_dir = (0, 2, 0) (expected a finite unit vector toward the sun)");
  o = Small();
  o.height = 64;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "GameRenderOptions::width x height = 64x64: expected a 2:1 lat-long (width = 2 x height), as fit and import read");
  o = Small();
  o.clouds.enabled = true;
  o.clouds.march.steps_zenith = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "GameCloudOptions::march.steps_zenith = 0 (expected an integer in [1, 4096])");
  o.clouds.enabled = false;  // clouds off: their options are not read
  EXPECT_TRUE(o.IsValid(&why)) << why;
  controllers::GameRenderFileOptions f;
  f.render = Small();
  f.out_exr = "sky.png";
  EXPECT_FALSE(f.IsValid(&why));
  EXPECT_EQ(why, "GameRenderFileOptions::out_exr: expected an output path ending in .exr");
}

}  // namespace
}  // namespace skycal
