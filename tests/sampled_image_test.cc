// The cloud march's sampled-image readers (clouds/model/cloud_textures_hw.glsl.h: the noise
// and weather map through the hardware's linear filter with repeat addressing) against the
// shared source's exact filter (cloud_textures.glsl.h, compiled as C++ in double), at the
// same texel coordinates, through tests/shaders/image_probe.comp.
//
// The threshold is the filter's, not a measurement: Vulkan computes each axis's weight with
// subTexelPrecisionBits (b) of fraction, so a weight can be off by up to 2^-b, and a linear
// blend along one axis moves by at most that times the difference of its two ends. Over d
// axes (3 for the noise volumes, 2 for the images) a filtered value is within
//   d 2^-b (max - min of the 2^d texels it reads) + 1e-6
// of the exact one (1e-6: float arithmetic on values of order 1, ~8 ulp). At the base's and
// curl's texel centres every weight is 0 or 1 on both sides: the raw channels must be equal
// bit for bit, and the fbm (formed from filtered channels on the GPU, from each texel's
// channels on the CPU) within 2 ulp. Control: reading the CPU side half a texel off (the convention a reader
// that forgot texel centres would have) breaks the bound on most points.
#include <gtest/gtest.h>
#include <vulkan/vulkan.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <vector>

#include "resolved_clouds.h"
#include "skycal/clouds/cloud_model.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_noise_packing.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/gpu/compute_pipeline.h"
#include "skycal/gpu/sampled_image.h"

namespace skycal::spirv {
extern const uint32_t image_probe[];
extern const size_t image_probe_size;
}  // namespace skycal::spirv

namespace skycal::clouds {
namespace {

constexpr int kValues = 9;  // per probe point (image_probe.comp)

// The spread (max - min) of a channel over the texels a linear read at texel coordinates
// (u, v[, w]) of an n-wide wrapped texture reads; value(x, y, z) gives the texel's channel.
template <typename Value>
double Spread(Value value, int n, int dims, double u, double v, double w) {
  auto axis = [n](double c, int k) { return ((static_cast<int>(std::floor(c - 0.5)) + k) % n + n) % n; };
  double lo = 1e30, hi = -1e30;
  for (int k = 0; k < (1 << dims); ++k) {
    const double x = value(axis(u, k & 1), axis(v, (k >> 1) & 1), dims == 3 ? axis(w, (k >> 2) & 1) : 0);
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return hi - lo;
}

// image_probe.comp's bindings: the points, the four textures as images, the values.
std::vector<VkDescriptorType> ProbeBindings() {
  const VkDescriptorType img = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  return {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, img, img, img, img, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
}

struct Probe {
  std::vector<float> points;  // 4 per point
  std::vector<float> gpu;     // kValues per point
};

// Uploads the textures as the renderer's image path does and reads back the probe.
Probe RunProbe(std::shared_ptr<gpu::VulkanContext> ctx, const CloudNoise& noise, const WeatherMap& weather,
               std::vector<float> points) {
  gpu::ComputePipeline p(ctx, spirv::image_probe, spirv::image_probe_size, ProbeBindings());
  constexpr uint32_t b = CloudNoise::kBaseSize, d = CloudNoise::kDetailSize, c = CloudNoise::kCurlSize;
  std::memcpy(p.MapImage(1, {b, b, b}), noise.base.data(), noise.base.size() * sizeof(float));
  p.Flush(1);
  auto padded = [&](uint32_t binding, const std::vector<float>& rgb, gpu::ImageExtent e) {
    float* dst = static_cast<float*>(p.MapImage(binding, e));
    for (size_t i = 0; i < rgb.size() / 3; ++i) {
      for (int k = 0; k < 3; ++k) dst[4 * i + k] = rgb[3 * i + k];
      dst[4 * i + 3] = 0.0f;
    }
    p.Flush(binding);
  };
  padded(2, noise.detail, {d, d, d});
  padded(3, noise.curl, {c, c, 1});
  padded(4, weather.rgb, {static_cast<uint32_t>(weather.width), static_cast<uint32_t>(weather.height), 1});
  const size_t n = points.size() / 4;
  std::memcpy(p.Map(0, points.size() * sizeof(float)), points.data(), points.size() * sizeof(float));
  p.Flush(0);
  p.Map(5, n * kValues * sizeof(float), /*host_readback=*/true);
  p.Dispatch(static_cast<uint32_t>((n + 63) / 64), 1, 1);
  const float* out = static_cast<const float*>(p.Read(5));
  return {std::move(points), std::vector<float>(out, out + n * kValues)};
}

struct Reference {
  double value[kValues];
  double spread[kValues];
};

// The exact reads (CloudModelD) at a point shifted by `shift` texels, and each value's spread.
Reference Exact(CloudModelD& m, const CloudNoise& noise, const WeatherMap& wm, const float* pt, double shift) {
  const double u = pt[0] + shift, v = pt[1] + shift, w = pt[2] + shift;
  Reference r{};
  const auto base = m.sample_base_noise(u, v, w);
  const double detail = m.sample_detail_fbm(u * 0.25, v * 0.25, w * 0.25);
  const auto curl = m.sample_image(CloudModelD::CLOUD_TEX_CURL, CloudNoise::kCurlSize, CloudNoise::kCurlSize, u, w);
  const auto weather = m.sample_image(CloudModelD::CLOUD_TEX_WEATHER, wm.width, wm.height, u * 0.5, w * 0.5);
  const double values[kValues] = {base.r, base.fbm, detail, curl.r, curl.g, curl.b, weather.r, weather.g, weather.b};
  std::copy(values, values + kValues, r.value);
  constexpr int nb = CloudNoise::kBaseSize, nd = CloudNoise::kDetailSize, nc = CloudNoise::kCurlSize;
  for (int k = 0; k < kValues; ++k) {
    if (k == 0) {
      r.spread[k] = Spread([&](int x, int y, int z) { return noise.base[4 * ((z * nb + y) * nb + x)]; }, nb, 3, u, v, w);
    } else if (k == 1) {
      r.spread[k] = Spread([&](int x, int y, int z) { return BaseFbm(&noise.base[4 * ((z * nb + y) * nb + x)]); }, nb, 3, u, v, w);
    } else if (k == 2) {
      r.spread[k] = Spread([&](int x, int y, int z) { return DetailFbm(&noise.detail[3 * ((z * nd + y) * nd + x)]); }, nd, 3,
                           u * 0.25, v * 0.25, w * 0.25);
    } else if (k <= 5) {
      r.spread[k] = Spread([&](int x, int y, int) { return noise.curl[3 * (y * nc + x) + (k - 3)]; }, nc, 2, u, w, 0);
    } else {
      r.spread[k] = Spread([&](int x, int y, int) { return wm.rgb[3 * (y * wm.width + x) + (k - 6)]; }, wm.width, 2,
                           u * 0.5, w * 0.5, 0);
    }
  }
  return r;
}

TEST(SampledImages, HardwareFilterWithinItsWeightPrecisionOfTheSharedSource) {
  std::shared_ptr<gpu::VulkanContext> ctx;
  try {
    ctx = gpu::VulkanContext::Shared(false);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "no Vulkan device: " << e.what();
  }
  const std::string unsupported = gpu::SampledImage::Unsupported(*ctx, {128, 128, 128});
  if (!unsupported.empty()) GTEST_SKIP() << unsupported;
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(ctx->physical_device(), &props);
  const double delta = std::ldexp(1.0, -static_cast<int>(props.limits.subTexelPrecisionBits));
  const CloudNoise noise =
      LoadOrGenerateCloudNoise(1, (std::filesystem::temp_directory_path() / "skycal-clouds-parity-cache").string());
  WeatherNoiseOptions wo;
  const WeatherMap weather = NoiseWeatherMap(5, 64, 60000.0, wo);
  // 512 points at texel centres of the base and curl noise (i + 0.5 texels, i in
  // [-256, 256)), then 3584 anywhere in [-300, 300) texels (negative ones wrap).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> any(-300.0f, 300.0f);
  std::vector<float> points;
  for (int i = 0; i < 4096; ++i) {
    for (int k = 0; k < 3; ++k) points.push_back(i < 512 ? static_cast<float>(static_cast<int>(rng() % 512) - 256) + 0.5f : any(rng));
    points.push_back(0.0f);
  }
  const Probe probe = RunProbe(ctx, noise, weather, points);
  CpuCloudTextures tex(noise, weather);
  CloudModelD m(tex);
  double worst_ratio = 0.0, worst_centre = 0.0;
  int control_breaks = 0, control_points = 0;
  for (int i = 0; i < 4096; ++i) {
    const Reference ref = Exact(m, noise, weather, &probe.points[4 * i], 0.0);
    const Reference off = Exact(m, noise, weather, &probe.points[4 * i], 0.5);
    bool broken = false;
    for (int k = 0; k < kValues; ++k) {
      const int dims = k >= 3 ? 2 : 3;
      const double got = probe.gpu[kValues * i + k], bound = dims * delta * ref.spread[k] + 1e-6;
      const double err = std::abs(got - ref.value[k]);
      worst_ratio = std::max(worst_ratio, err / bound);
      EXPECT_LE(err, bound) << "point " << i << " value " << k;
      // Texel centres (of the base and the curl: the detail and weather reads are scaled).
      const bool at_centre = i < 512 && k != 2 && k < 6;
      if (at_centre) worst_centre = std::max(worst_centre, err);
      if (at_centre && k != 1) EXPECT_EQ(got, static_cast<float>(ref.value[k])) << "texel centre " << i << " value " << k;
      if (at_centre && k == 1) EXPECT_LE(err, 2.0 * std::ldexp(1.0, -23)) << "texel centre " << i << " (fbm)";
      if (std::abs(got - off.value[k]) > dims * delta * off.spread[k] + 1e-6) broken = true;
    }
    if (i >= 512) {
      ++control_points;
      control_breaks += broken ? 1 : 0;
    }
  }
  std::printf("subTexelPrecisionBits %u: worst error / bound %.3f; texel centres worst %.2e; control (half a texel off) breaks the "
              "bound on %d of %d points\n",
              props.limits.subTexelPrecisionBits, worst_ratio, worst_centre, control_breaks, control_points);
  EXPECT_GT(control_breaks, control_points / 2);
}

// Which path the renderer takes: auto follows the device (images on a discrete GPU, texel
// buffers on lavapipe and unified memory); asked-for images on a device that cannot sample
// them fall back to buffers with the device's reason in the note; a bad
// SKYCAL_VULKAN_TEXTURES names the variable and its value.
TEST(SampledImages, TheTexturePathFollowsTheDeviceAndFallsBackWithItsReason) {
  EXPECT_TRUE(ChooseCloudTextures(CloudTextures::kAuto, true, "").images);
  EXPECT_FALSE(ChooseCloudTextures(CloudTextures::kAuto, false, "").images);
  EXPECT_TRUE(ChooseCloudTextures(CloudTextures::kImages, false, "").images);
  EXPECT_FALSE(ChooseCloudTextures(CloudTextures::kBuffers, true, "").images);
  EXPECT_TRUE(ChooseCloudTextures(CloudTextures::kAuto, true, "").note.empty());
  const CloudTextureChoice fallback = ChooseCloudTextures(CloudTextures::kImages, true, "no 3D RGBA32F images");
  EXPECT_FALSE(fallback.images);
  EXPECT_NE(fallback.note.find("no 3D RGBA32F images"), std::string::npos) << fallback.note;
  EXPECT_NE(fallback.note.find("texel buffers"), std::string::npos) << fallback.note;
  EXPECT_FALSE(ChooseCloudTextures(CloudTextures::kAuto, true, "no linear filter").images);
  ::setenv("SKYCAL_VULKAN_TEXTURES", "hardware", 1);
  try {
    CloudTexturesFromEnvironment();
    ADD_FAILURE() << "a bad SKYCAL_VULKAN_TEXTURES was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("SKYCAL_VULKAN_TEXTURES = 'hardware'"), std::string::npos) << e.what();
  }
  ::setenv("SKYCAL_VULKAN_TEXTURES", "images", 1);
  EXPECT_EQ(CloudTexturesFromEnvironment(), CloudTextures::kImages);
  ::unsetenv("SKYCAL_VULKAN_TEXTURES");
  EXPECT_EQ(CloudTexturesFromEnvironment(), CloudTextures::kAuto);
}

// The pipeline keeps images and buffers apart: Map of an image binding and MapImage of a
// buffer binding are refused, naming the binding.
TEST(SampledImages, ImageAndBufferBindingsAreNotConfused) {
  std::shared_ptr<gpu::VulkanContext> ctx;
  try {
    ctx = gpu::VulkanContext::Shared(false);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "no Vulkan device: " << e.what();
  }
  gpu::ComputePipeline p(ctx, spirv::image_probe, spirv::image_probe_size, ProbeBindings());
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message([&] { p.Map(1, 64); }).find("binding 1 is an image"), std::string::npos);
  EXPECT_NE(message([&] { p.MapImage(0, {4, 4, 1}); }).find("binding 0 is not an image"), std::string::npos);
  EXPECT_NE(message([&] { p.Dispatch(1, 1, 1); }).find("has no"), std::string::npos);
}

}  // namespace
}  // namespace skycal::clouds
