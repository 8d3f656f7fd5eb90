// Rendering a preset to a full-sphere lat-long image (core/latlong.h convention).
// Two backends share one model source: `vulkan` (compute shaders, the path the game
// runs; default) and `cpu` (double-precision reference).
#pragma once
#include <array>
#include <memory>
#include <string>

#include "skycal/core/image.h"
#include "skycal/render/preset.h"

namespace skycal::render {

enum class Backend { kVulkan, kCpu };
const char* ToString(Backend b);
// Throws skycal::Error naming `what` unless `name` is "vulkan" or "cpu".
Backend ParseBackend(const std::string& name, const std::string& what);

enum class GroundMode {
  kLit,   // constant radiance albedo/pi * (E_sun cos(sun zenith) + E_sky), the model's light
  kZero,  // black below the horizon
};

struct RenderRequest {
  std::array<double, 3> sun_dir = {0.0, 1.0, 0.0};  // toward the sun, normalised by Render
  int width = 1024;   // pixels, >= 2
  int height = 512;   // pixels, >= 2
  bool sun_disc = true;
  GroundMode ground = GroundMode::kLit;

  // Returns false and explains in *why unless the request is renderable.
  bool IsValid(std::string* why) const;
};

class SkyRenderer {
 public:
  virtual ~SkyRenderer() = default;
  // Throws skycal::Error on an invalid preset or request, or a backend failure.
  virtual ImageRGB Render(const Preset& preset, const RenderRequest& request) = 0;
  virtual std::string Describe() const = 0;  // backend and device, for logs
  // Validation-layer warnings and errors reported so far (Vulkan with validation on).
  virtual int ValidationMessages() const { return 0; }
};

struct VulkanOptions {
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation (also: SKYCAL_VULKAN_VALIDATION=1)
};

// The Vulkan renderer creates its instance, device and pipeline once; keep it alive to
// render many times. Throws skycal::Error when no Vulkan device is available.
std::unique_ptr<SkyRenderer> CreateRenderer(Backend backend, const VulkanOptions& vk = {});

}  // namespace skycal::render
