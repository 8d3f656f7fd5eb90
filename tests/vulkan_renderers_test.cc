// The Vulkan sky and cloud renderers as a game runs them: device time by timestamps,
// staged (device-local) and direct memory giving the same bits, textures uploaded once per
// change of content.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "cloud_test_scenes.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "skycal/render/renderer_stats.h"

namespace skycal {
namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

DeviceStats Stats(const render::SkyRenderer& r) { return render::RendererDeviceStats(r); }
DeviceStats Stats(const clouds::CloudRenderer& r) { return clouds::RendererDeviceStats(r); }

render::Preset DefaultPreset() {
  return render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
}

// Sets SKYCAL_VULKAN_MEMORY for one scope (read when a renderer's pipeline is made).
class MemoryModeEnv {
 public:
  explicit MemoryModeEnv(const char* mode) { setenv("SKYCAL_VULKAN_MEMORY", mode, 1); }
  ~MemoryModeEnv() { unsetenv("SKYCAL_VULKAN_MEMORY"); }
};

std::unique_ptr<render::SkyRenderer> VulkanSkyOrSkip(const char* mode) {
  MemoryModeEnv env(mode);
  return render::CreateRenderer(render::Backend::kVulkan);
}

const clouds::CloudNoise& TestNoise() {
  static const clouds::CloudNoise noise = testing::SinusoidCloudNoise();
  return noise;
}

struct CloudFixture {
  render::Preset preset = DefaultPreset();
  clouds::CloudParams params;
  clouds::WeatherMap weather = testing::PatchyWeather(0.55f, 0.5f);
  clouds::CloudScene Scene() const { return {&preset, &params, &TestNoise(), &weather}; }
};

clouds::CloudRenderRequest SmallCloudRequest(int width, double sun_y) {
  clouds::CloudRenderRequest r;
  r.width = width;
  r.height = width / 2;
  r.sun_dir = {0.6, sun_y, 0.5};
  return r;
}

// Device time present, positive, and within the render's wall time (lavapipe writes
// timestamps: 64 valid bits on its one queue family).
TEST(VulkanRenderers, DeviceTimeWithinWallTime) {
  auto sky = VulkanSkyOrSkip("auto");
  EXPECT_FALSE(Stats(*sky).gpu_ms.has_value());
  render::RenderRequest req;
  req.width = 512;
  req.height = 256;
  sky->Render(DefaultPreset(), req);
  const auto t0 = Clock::now();
  sky->Render(DefaultPreset(), req);
  const double wall = MsSince(t0);
  const DeviceStats s = Stats(*sky);
  ASSERT_TRUE(s.gpu_ms.has_value());
  EXPECT_GT(*s.gpu_ms, 0.0);
  EXPECT_LE(*s.gpu_ms, wall);

  CloudFixture f;
  auto cloud = clouds::CreateVulkanCloudRenderer();
  const auto t1 = Clock::now();
  cloud->Render(f.Scene(), SmallCloudRequest(128, 0.4));
  const double cloud_wall = MsSince(t1);
  ASSERT_TRUE(Stats(*cloud).gpu_ms.has_value());
  EXPECT_GT(*Stats(*cloud).gpu_ms, 0.0);
  EXPECT_LE(*Stats(*cloud).gpu_ms, cloud_wall);
  // The CPU backends report none.
  EXPECT_FALSE(Stats(*render::CreateRenderer(render::Backend::kCpu)).gpu_ms.has_value());
}

// Staged (device-local buffers filled by copies) and direct (host-visible buffers read in
// place) give bit-identical images: the same shader reads the same bytes.
TEST(VulkanRenderers, StagedAndDirectAreBitIdentical) {
  auto direct = VulkanSkyOrSkip("direct");
  auto staged = VulkanSkyOrSkip("staged");
  EXPECT_FALSE(Stats(*direct).staged);
  EXPECT_TRUE(Stats(*staged).staged);
  const render::Preset preset = DefaultPreset();
  for (double y : {0.9, 0.1, -0.05}) {
    render::RenderRequest req;
    req.width = 256;
    req.height = 128;
    req.sun_dir = {0.3, y, 0.5};
    const ImageRGB a = direct->Render(preset, req), b = staged->Render(preset, req);
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    EXPECT_EQ(0, std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float))) << "sun y " << y;
  }
  CloudFixture f;
  std::unique_ptr<clouds::CloudRenderer> cd, cs;
  {
    MemoryModeEnv env("direct");
    cd = clouds::CreateVulkanCloudRenderer();
  }
  {
    MemoryModeEnv env("staged");
    cs = clouds::CreateVulkanCloudRenderer();
  }
  EXPECT_TRUE(Stats(*cs).staged);
  for (double y : {0.4, 0.05}) {
    const clouds::CloudImage a = cd->Render(f.Scene(), SmallCloudRequest(128, y));
    const clouds::CloudImage b = cs->Render(f.Scene(), SmallCloudRequest(128, y));
    EXPECT_EQ(0, std::memcmp(a.radiance.pixels.data(), b.radiance.pixels.data(), a.radiance.pixels.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(a.transmittance.data(), b.transmittance.data(), a.transmittance.size() * sizeof(float)));
  }
}

// Textures go to the device once per change of content: a second render of the same scene
// uploads nothing; a new weather map uploads the weather map alone; a new size the
// direction table alone.
TEST(VulkanRenderers, UnchangedContentIsNotUploadedAgain) {
  for (const char* mode : {"direct", "staged"}) {
    MemoryModeEnv env(mode);
    CloudFixture f;
    auto cloud = clouds::CreateVulkanCloudRenderer();
    cloud->Render(f.Scene(), SmallCloudRequest(64, 0.4));
    const DeviceStats first = Stats(*cloud);
    // Noise (4 bindings), weather map, direction table.
    EXPECT_EQ(first.resource_uploads, 6) << mode;
    EXPECT_GT(first.resource_upload_bytes, 30'000'000) << mode;  // the noise's texel buffers
    cloud->Render(f.Scene(), SmallCloudRequest(64, 0.7));       // another sun: same textures
    EXPECT_EQ(Stats(*cloud).resource_uploads, 6) << mode;
    f.weather = testing::PatchyWeather(0.3f, 0.5f);
    cloud->Render(f.Scene(), SmallCloudRequest(64, 0.7));
    EXPECT_EQ(Stats(*cloud).resource_uploads, 7) << mode;
    cloud->Render(f.Scene(), SmallCloudRequest(128, 0.7));
    EXPECT_EQ(Stats(*cloud).resource_uploads, 8) << mode;

    auto sky = render::CreateRenderer(render::Backend::kVulkan);
    render::RenderRequest req;
    req.width = 64;
    req.height = 32;
    sky->Render(f.preset, req);
    EXPECT_EQ(Stats(*sky).resource_uploads, 2) << mode;  // LUT slice, direction table
    sky->Render(f.preset, req);
    EXPECT_EQ(Stats(*sky).resource_uploads, 2) << mode;
    req.sun_dir = {0.0, 0.2, 0.98};  // another sun: another LUT slice
    sky->Render(f.preset, req);
    EXPECT_EQ(Stats(*sky).resource_uploads, 3) << mode;
  }
}

}  // namespace
}  // namespace skycal
