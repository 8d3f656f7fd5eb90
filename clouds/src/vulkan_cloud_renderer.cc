// The Vulkan cloud renderer on gpu::ComputePipeline (clouds/shaders/clouds_latlong.comp).
// The textures are uploaded once per change of noise or weather map (by content), the RGB
// ones padded to one vec4 per texel: either the density's packed views of the noise
// (cloud_noise_packing.h: base (R, fbm) pairs, detail fbm quads; the raw base is not
// uploaded) as uniform texel buffers read by texelFetch (lavapipe turns storage-buffer loads
// at per-lane indices into scalar loops, 3x slower overall; the base is 128^3 = 2M texels,
// lavapipe allows 2^27, a device below that fails with ComputePipeline's
// maxTexelBufferElements error), or the raw noise as sampled images (CloudTextures);
// parameters and the direction table per render.
//
// Workgroups of 8 x 8 pixels, not the sky's one image row: the march's cost varies by
// orders of magnitude between pixels (an empty zenith ray exits after a few cheap samples,
// a cloud at the horizon takes 128 full samples with 6 light samples each). Lavapipe runs
// a workgroup's invocations in SIMD lanes and workgroups on its threads: a compact tile
// holds pixels of similar cost (less lane divergence than 128 pixels spread over 90 deg
// of azimuth), and 64-pixel workgroups are small enough to balance the 2 cores.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "resolved_clouds.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/clouds/cloud_noise_packing.h"
#include "skycal/core/error.h"
#include "skycal/gpu/compute_pipeline.h"
#include "skycal/gpu/sampled_image.h"
#include "skycal/gpu/workgroup_order.h"

namespace skycal::spirv {
extern const uint32_t clouds_latlong[];
extern const size_t clouds_latlong_size;
extern const uint32_t clouds_latlong_images[];
extern const size_t clouds_latlong_images_size;
}  // namespace skycal::spirv

namespace skycal::clouds {
namespace {

constexpr uint32_t kLocalX = 8, kLocalY = 8;
// kBase: the base noise's packed (R, fbm) pairs (texel buffers) or its RGBA image; kDetail:
// the detail fbm's quads or its RGB image.
enum Binding : uint32_t { kParams = 0, kBase = 1, kDetail = 2, kCurl = 3, kWeather = 4, kTrig = 5, kOutput = 6 };

// The upload key of noise made by hand (no checksum): FNV-1a's step over 8-byte words, not
// bytes (34 MB of noise: ~3 ms a render instead of ~35). Each step is a bijection of the
// running value for a given word and of the word for a given value, so content that
// differs in one word always gives another key.
uint64_t Fnv(const std::vector<float>& v, uint64_t h = 1469598103934665603ull) {
  const size_t words = v.size() / 2;
  const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
  for (size_t i = 0; i < words; ++i) {
    uint64_t w;
    std::memcpy(&w, bytes + 8 * i, 8);
    h = (h ^ w) * 1099511628211ull;
  }
  if (v.size() % 2) {
    uint32_t w;
    std::memcpy(&w, bytes + 8 * words, 4);
    h = (h ^ w) * 1099511628211ull;
  }
  return h;
}

std::vector<VkDescriptorType> BindingTypes(bool images) {
  const VkDescriptorType tex = images ? VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER : VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
  return {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, tex, tex, tex, tex, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
          VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
}

// The device side of the renderer: the pipeline and what has been uploaded to it. One per
// (validation, memory mode, texture path) while a renderer or a KeepCloudDevices holds it: a calibration
// makes a renderer per stage (statistics, inversion, refit, the game's image), and each new
// pipeline would upload the noise (32 MB of base pairs or base image) again. Render holds the
// mutex: renderers on several threads take turns on the one pipeline.
class CloudDevice {
 public:
  CloudDevice(std::shared_ptr<gpu::VulkanContext> ctx, bool images)
      : ctx_(std::move(ctx)),
        images_(images),
        pipeline_(ctx_, images ? spirv::clouds_latlong_images : spirv::clouds_latlong,
                  images ? spirv::clouds_latlong_images_size : spirv::clouds_latlong_size, BindingTypes(images),
                  {kLocalX, kLocalY}) {}

  // One dispatch of params.size() layers (gl_WorkGroupID.z): layer k reads parameter block
  // k (the shade, then width, height and the workgroup row stride) and writes image k.
  std::vector<CloudImage> Render(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                 const CloudRenderRequest& request) {
    const int w = request.width, h = request.height;
    const uint32_t tile_rows = (h + kLocalY - 1) / kLocalY;
    std::vector<float> blocks;
    for (const CloudShadeD& shade : ResolveCloudShades(scene, params, request)) {
      std::vector<float> block = PackCloudShade(shade);
      block.push_back(static_cast<float>(w));
      block.push_back(static_cast<float>(h));
      block.push_back(static_cast<float>(gpu::WorkgroupRowStride(tile_rows)));  // exact: < 2^24
      blocks.insert(blocks.end(), block.begin(), block.end());
    }
    const size_t pixels = static_cast<size_t>(w) * h;
    std::lock_guard<std::mutex> lock(mutex_);
    Upload(kParams, blocks);
    UploadTextures(*scene.noise, *scene.weather);
    UploadTrig(w, h);
    pipeline_.Map(kOutput, params.size() * pixels * 4 * sizeof(float), /*host_readback=*/true);
    pipeline_.Dispatch((w + kLocalX - 1) / kLocalX, tile_rows, static_cast<uint32_t>(params.size()));
    std::vector<CloudImage> images(params.size());
    for (size_t k = 0; k < params.size(); ++k) {
      const float* out = static_cast<const float*>(pipeline_.Read(kOutput)) + k * pixels * 4;
      CloudImage& image = images[k];
      image.radiance = ImageRGB(w, h);
      image.transmittance.resize(pixels);
      for (size_t i = 0; i < pixels; ++i) {
        image.radiance.pixels[3 * i] = out[4 * i];
        image.radiance.pixels[3 * i + 1] = out[4 * i + 1];
        image.radiance.pixels[3 * i + 2] = out[4 * i + 2];
        image.transmittance[i] = out[4 * i + 3];
      }
    }
    return images;
  }

  std::string DeviceName() const { return ctx_->device_name(); }
  bool images() const { return images_; }
  DeviceStats Stats() {
    std::lock_guard<std::mutex> lock(mutex_);
    DeviceStats s;
    s.gpu_ms = pipeline_.last_gpu_ms();
    for (uint32_t b : {kBase, kDetail, kCurl, kWeather, kTrig}) {
      s.resource_uploads += pipeline_.uploads(b);
      s.resource_upload_bytes += pipeline_.upload_bytes(b);
    }
    s.staged = pipeline_.staged();
    s.sampled_images = images_;
    return s;
  }

 private:
  void Upload(uint32_t binding, const std::vector<float>& v) {
    std::memcpy(pipeline_.Map(binding, v.size() * sizeof(float)), v.data(), v.size() * sizeof(float));
    pipeline_.Flush(binding);
  }
  // A packed view of the noise (cloud_noise_packing.h) for an n^3 volume, written texel by
  // texel straight into the mapped (or staging) memory: a new process touches 33 MB of
  // memory once for the base pairs, not twice (PackBasePairs' vector, then the copy).
  template <typename PackTexel>
  void UploadPacked(uint32_t binding, int n, PackTexel pack) {
    const int texels = n * n * n;
    float* dst = static_cast<float*>(pipeline_.Map(binding, static_cast<size_t>(texels) * 4 * sizeof(float)));
    for (int i = 0; i < texels; ++i) pack(i, dst + 4 * static_cast<size_t>(i));
    pipeline_.Flush(binding);
  }
  // An RGB texture as one vec4 per texel (alpha 0): the shader loads 16 bytes per texel.
  // `extent`: its shape as an image (image path), ignored for a texel buffer.
  void UploadPadded(uint32_t binding, const std::vector<float>& rgb, const gpu::ImageExtent& extent) {
    const size_t texels = rgb.size() / 3;
    float* dst = static_cast<float*>(images_ ? pipeline_.MapImage(binding, extent)
                                             : pipeline_.Map(binding, texels * 4 * sizeof(float)));
    for (size_t i = 0; i < texels; ++i) {
      dst[4 * i] = rgb[3 * i];
      dst[4 * i + 1] = rgb[3 * i + 1];
      dst[4 * i + 2] = rgb[3 * i + 2];
      dst[4 * i + 3] = 0.0f;
    }
    pipeline_.Flush(binding);
  }
  void UploadTextures(const CloudNoise& noise, const WeatherMap& weather) {
    const uint64_t noise_key = noise.sha256.empty() ? Fnv(noise.curl, Fnv(noise.detail, Fnv(noise.base)))
                                                    : Fnv(std::vector<float>{}, std::hash<std::string>{}(noise.sha256));
    if (noise_key != noise_key_ || !noise_uploaded_) {
      constexpr uint32_t b = CloudNoise::kBaseSize, d = CloudNoise::kDetailSize, c = CloudNoise::kCurlSize;
      if (images_) {
        // The raw noise: the hardware filters each channel and the shader forms the fbm.
        std::memcpy(pipeline_.MapImage(kBase, {b, b, b}), noise.base.data(), noise.base.size() * sizeof(float));
        pipeline_.Flush(kBase);
        UploadPadded(kDetail, noise.detail, {d, d, d});
      } else {
        UploadPacked(kBase, b, [&](int i, float* t) { BasePairTexel(noise.base.data(), i, t); });
        UploadPacked(kDetail, d, [&](int i, float* t) { DetailQuadTexel(noise.detail.data(), i, t); });
      }
      UploadPadded(kCurl, noise.curl, {c, c, 1});
      noise_key_ = noise_key;
      noise_uploaded_ = true;
    }
    // The weather map compared with the copy last uploaded, not hashed: a 512^2 map is 3 MB,
    // which a byte-wise hash reads in several ms per render and a comparison in a fraction.
    if (!weather_uploaded_ || weather.width != weather_width_ || weather.height != weather_height_ ||
        weather.rgb != weather_rgb_) {
      UploadPadded(kWeather, weather.rgb,
                   {static_cast<uint32_t>(weather.width), static_cast<uint32_t>(weather.height), 1});
      weather_rgb_ = weather.rgb;
      weather_width_ = weather.width;
      weather_height_ = weather.height;
      weather_uploaded_ = true;
    }
  }
  // The direction table (sin, cos of each row's latitude and each column's longitude).
  void UploadTrig(int w, int h) {
    const size_t trig_bytes = static_cast<size_t>(w + h) * 2 * sizeof(float);
    float* trig = static_cast<float*>(pipeline_.Map(kTrig, trig_bytes));
    if (trig_width_ == w && trig_height_ == h && trig == trig_filled_) return;
    const LatLongTrig t = MakeLatLongTrig(w, h);
    for (int y = 0; y < h; ++y) {
      trig[2 * y] = static_cast<float>(t.sin_lat[y]);
      trig[2 * y + 1] = static_cast<float>(t.cos_lat[y]);
    }
    for (int x = 0; x < w; ++x) {
      trig[2 * (h + x)] = static_cast<float>(t.sin_lon[x]);
      trig[2 * (h + x) + 1] = static_cast<float>(t.cos_lon[x]);
    }
    pipeline_.Flush(kTrig);
    trig_width_ = w;
    trig_height_ = h;
    trig_filled_ = trig;
  }

  std::mutex mutex_;
  std::shared_ptr<gpu::VulkanContext> ctx_;
  bool images_;  // the textures as sampled images (the raw noise), else texel buffers (its packed views)
  gpu::ComputePipeline pipeline_;
  uint64_t noise_key_ = 0;
  std::vector<float> weather_rgb_;  // the weather map last uploaded
  int weather_width_ = 0, weather_height_ = 0;
  bool noise_uploaded_ = false, weather_uploaded_ = false;
  int trig_width_ = 0, trig_height_ = 0;
  const float* trig_filled_ = nullptr;
};

// The process's devices, by (validation, memory mode), and those a KeepCloudDevices holds.
struct DeviceRegistry {
  std::mutex mutex;
  std::map<std::tuple<bool, int, int>, std::weak_ptr<CloudDevice>> devices;  // validation, memory, textures
  int keepers = 0;
  std::vector<std::shared_ptr<CloudDevice>> kept;
};
DeviceRegistry& Registry() {
  static DeviceRegistry* registry = new DeviceRegistry;  // never destroyed: no order at exit to get wrong
  return *registry;
}

// Why the device cannot read the cloud textures as sampled images (empty: it can): the
// two 3D noise volumes and a 2D image (curl; the weather map is checked when uploaded).
std::string ImagesUnsupported(const gpu::VulkanContext& ctx) {
  constexpr uint32_t b = CloudNoise::kBaseSize, d = CloudNoise::kDetailSize, c = CloudNoise::kCurlSize;
  for (const gpu::ImageExtent& e : {gpu::ImageExtent{b, b, b}, gpu::ImageExtent{d, d, d}, gpu::ImageExtent{c, c, 1}}) {
    const std::string why = gpu::SampledImage::Unsupported(ctx, e);
    if (!why.empty()) return why;
  }
  return {};
}

std::shared_ptr<CloudDevice> SharedCloudDevice(bool validation, CloudTextures textures) {
  DeviceRegistry& r = Registry();
  if (textures == CloudTextures::kAuto) textures = CloudTexturesFromEnvironment();
  const std::tuple<bool, int, int> key{validation, static_cast<int>(gpu::MemoryModeFromEnvironment()),
                                       static_cast<int>(textures)};
  std::lock_guard<std::mutex> lock(r.mutex);
  std::shared_ptr<CloudDevice> device = r.devices[key].lock();
  if (!device) {
    std::shared_ptr<gpu::VulkanContext> ctx = gpu::VulkanContext::Shared(validation);
    const CloudTextureChoice choice =
        ChooseCloudTextures(textures, ctx->has_device_only_memory(), ImagesUnsupported(*ctx));
    if (!choice.note.empty()) std::cerr << "skycal: " << choice.note << "\n";
    device = std::make_shared<CloudDevice>(std::move(ctx), choice.images);
    r.devices[key] = device;
  }
  if (r.keepers > 0 && std::find(r.kept.begin(), r.kept.end(), device) == r.kept.end()) r.kept.push_back(device);
  return device;
}

class VulkanCloudRenderer final : public CloudRenderer {
 public:
  VulkanCloudRenderer(bool validation, CloudTextures textures) : device_(SharedCloudDevice(validation, textures)) {}
  CloudImage Render(const CloudScene& scene, const CloudRenderRequest& request) override {
    return std::move(device_->Render(scene, {scene.params}, request).front());
  }
  std::vector<CloudImage> RenderEach(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                     const CloudRenderRequest& request) override {
    if (params.empty()) return {};
    return device_->Render(scene, params, request);
  }
  std::string Describe() const override {
    return "vulkan clouds (" + device_->DeviceName() + (device_->images() ? ", sampled images" : "") + ")";
  }
  DeviceStats Stats() const { return device_->Stats(); }

 private:
  std::shared_ptr<CloudDevice> device_;
};

}  // namespace

CloudTextures CloudTexturesFromEnvironment() {
  // The values in the enum's order.
  return static_cast<CloudTextures>(gpu::EnvironmentChoice("SKYCAL_VULKAN_TEXTURES", {"auto", "buffers", "images"}));
}

CloudTextureChoice ChooseCloudTextures(CloudTextures requested, bool discrete_gpu, const std::string& images_unsupported) {
  CloudTextureChoice c;
  const bool want = requested == CloudTextures::kImages || (requested == CloudTextures::kAuto && discrete_gpu);
  c.images = want && images_unsupported.empty();
  if (want && !c.images) {
    c.note = "sampled images unavailable (" + images_unsupported + "): the clouds read their textures from texel buffers";
  }
  return c;
}

DeviceStats RendererDeviceStats(const CloudRenderer& renderer) {
  const auto* vulkan = dynamic_cast<const VulkanCloudRenderer*>(&renderer);
  return vulkan ? vulkan->Stats() : DeviceStats{};
}

KeepCloudDevices::KeepCloudDevices() {
  DeviceRegistry& r = Registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  ++r.keepers;
}

KeepCloudDevices::~KeepCloudDevices() {
  std::vector<std::shared_ptr<CloudDevice>> released;  // destroyed after the lock is let go
  DeviceRegistry& r = Registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  if (--r.keepers == 0) released.swap(r.kept);
}

std::unique_ptr<CloudRenderer> CreateVulkanCloudRenderer(bool validation, CloudTextures textures) {
  return std::make_unique<VulkanCloudRenderer>(validation, textures);
}

}  // namespace skycal::clouds
