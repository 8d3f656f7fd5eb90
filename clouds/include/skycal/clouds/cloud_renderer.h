// Rendering the cloudscape to a full-sphere lat-long (core/latlong.h convention): per pixel
// the clouds' in-scattered radiance (cd/m^2, scene-linear Rec.709) and their transmittance.
// Composite over the clear sky with composite.h. Backends share one model source
// (clouds/model/*.glsl.h): the double reference, a float CPU path taking the shader's
// decisions (the parity test's twin of the shader), and Vulkan (clouds_latlong.comp).
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/core/image.h"
#include "skycal/render/preset.h"

namespace skycal::clouds {

struct CloudRenderRequest {
  std::array<double, 3> sun_dir = {0.0, 1.0, 0.0};  // toward the sun, normalised by Render
  int width = 1024;    // pixels, >= 2
  int height = 512;    // pixels, >= 2
  double time_s = 0.0;  // the wind moves the clouds by wind_speed x time
  MarchOptions march;
  bool IsValid(std::string* why) const;
};

struct CloudImage {
  ImageRGB radiance;                // in-scattered radiance L_cloud, cd/m^2 per channel
  std::vector<float> transmittance; // T per pixel (width x height, row-major), 1
  long long full_samples = 0;       // full-density primary samples taken (all pixels)
};

// Everything a cloud render needs. The preset supplies the light: its sun (illuminance x
// tint x the LUT's transmittance, render::SunIlluminanceAtGround), the SH-9 of its clear
// sky (ambient and the atmosphere's colour) and its lit ground.
struct CloudScene {
  const render::Preset* preset = nullptr;
  const CloudParams* params = nullptr;
  const CloudNoise* noise = nullptr;
  const WeatherMap* weather = nullptr;
};

enum class CloudPrecision { kDouble, kFloat };

class CloudRenderer {
 public:
  virtual ~CloudRenderer() = default;
  // Throws skycal::Error on invalid parameters, textures or request, or a backend failure.
  virtual CloudImage Render(const CloudScene& scene, const CloudRenderRequest& request) = 0;
  // One image per parameter set over the scene's preset, textures and request, in order
  // (scene.params is not read): what a fit renders at one point of its other parameters.
  // The Vulkan backend draws them in one submission (one dispatch, a layer per set: the
  // device's per-submission cost and the readback once, not per image); others, and this
  // default, render them one by one. The images are Render's, bit for bit. Throws as Render.
  virtual std::vector<CloudImage> RenderEach(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                             const CloudRenderRequest& request);
  virtual std::string Describe() const = 0;
};

// CPU: `threads` workers over rows (0: the hardware's count).
std::unique_ptr<CloudRenderer> CreateCpuCloudRenderer(CloudPrecision precision, int threads = 0);
// How the Vulkan renderer reads the noise and the weather map: texel buffers filtered
// exactly by the shared source (clouds/model/cloud_textures.glsl.h), or sampled images
// (3D for the noise) through the hardware's linear filter with repeat addressing, as a
// game samples them. kAuto: SKYCAL_VULKAN_TEXTURES (auto, buffers or images), then the
// device (cloud_renderer_stats.h, ChooseCloudTextures).
enum class CloudTextures { kAuto, kBuffers, kImages };
// Vulkan (lavapipe or a GPU); keeps its pipeline and uploaded textures between renders.
// Renderers alive at the same time (same validation, SKYCAL_VULKAN_MEMORY and textures)
// share one pipeline and its textures. Throws skycal::Error when no Vulkan device is
// available or SKYCAL_VULKAN_TEXTURES is not one of its values.
std::unique_ptr<CloudRenderer> CreateVulkanCloudRenderer(bool validation = false,
                                                         CloudTextures textures = CloudTextures::kAuto);

// While one lives, the Vulkan cloud pipelines made in the process outlive their renderers:
// a controller whose stages each make a renderer (statistics, inversion, refit, the game's
// image) holds one so the noise goes to the device once, not once per stage. The last one
// to go releases them.
class KeepCloudDevices {
 public:
  KeepCloudDevices();
  ~KeepCloudDevices();
  KeepCloudDevices(const KeepCloudDevices&) = delete;
  KeepCloudDevices& operator=(const KeepCloudDevices&) = delete;
};

// Throws skycal::Error naming `origin` unless the textures match the layout contract
// (sizes, finite values, the weather map's channels in [0, 1]). Noise carrying its sha256
// was validated where it was made (ValidateCloudNoise): only its sizes are checked here.
void ValidateCloudTextures(const CloudNoise& noise, const WeatherMap& weather, const std::string& origin);
// Throws naming `origin` unless every noise value is finite and in range (base and detail
// in [0, 1], curl in [-1, 1]) and the sizes match cloud_textures.h (8.7 M values: once,
// where the noise is made or loaded).
void ValidateCloudNoise(const CloudNoise& noise, const std::string& origin);

}  // namespace skycal::clouds
