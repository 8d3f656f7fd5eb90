// A texture as a game's shader samples it: an optimally tiled 2D or 3D image in device-local
// memory, RGBA 32-bit float texels, read through a sampler with the hardware's linear
// filter and repeat addressing (the way Horizon Zero Dawn samples its 128^3 and 32^3 cloud
// noise). Filled from a persistently mapped staging buffer by a copy recorded into the
// next submission; ComputePipeline owns one per VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
// binding.
//
// The hardware filter is not the shared source's exact one: Vulkan computes the filter
// weights with VkPhysicalDeviceLimits::subTexelPrecisionBits of fraction (at least 4; 8 on
// current desktop GPUs), so a filtered value can differ from the exact blend by up to
// 2^-bits of the texels' spread per axis (docs/cloud-model.md, "Sampled images").
//
// Include only from renderer sources (vulkan.h; see vulkan_context.h).
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>

#include "skycal/gpu/vulkan_context.h"

namespace skycal::gpu {

struct ImageExtent {
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t depth = 1;  // 1: a 2D image
  bool operator==(const ImageExtent& o) const { return width == o.width && height == o.height && depth == o.depth; }
  size_t texels() const { return static_cast<size_t>(width) * height * depth; }
};

class SampledImage {
 public:
  static constexpr VkFormat kFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
  static constexpr size_t kTexelBytes = 16;

  // Empty when `ctx`'s device can sample a kFormat image of `extent` with linear filtering
  // (optimal tiling); otherwise why not, in words (the caller falls back and says so).
  static std::string Unsupported(const VulkanContext& ctx, const ImageExtent& extent);

  // Throws skycal::Error (naming what failed) when the image or its memory cannot be made.
  SampledImage(VulkanContext& ctx, const ImageExtent& extent);
  ~SampledImage();
  SampledImage(const SampledImage&) = delete;
  SampledImage& operator=(const SampledImage&) = delete;

  // The staging memory: extent.texels() texels of 4 floats, x fastest, then y, then z.
  void* staging() const { return staging_.mapped; }
  // Makes the host's writes to the staging memory visible and schedules the copy.
  void Flush();
  bool dirty() const { return dirty_; }
  // Records the copy of the staging buffer into the image between the layout transitions
  // it needs; the image is then SHADER_READ_ONLY_OPTIMAL for compute reads.
  void RecordUpload(VkCommandBuffer cmd);

  const ImageExtent& extent() const { return extent_; }
  VkImageView view() const { return view_; }
  size_t bytes() const { return extent_.texels() * kTexelBytes; }

 private:
  void Release();
  VulkanContext& ctx_;
  ImageExtent extent_;
  VkImage image_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  MappedBuffer staging_;
  bool dirty_ = false;
  bool written_ = false;  // the image has been filled once (its layout is SHADER_READ_ONLY)
};

// The sampler every image binding uses: linear min/mag filter, one mip level, repeat
// addressing on every axis, normalized coordinates. The caller destroys it.
VkSampler CreateLinearRepeatSampler(VkDevice device);

}  // namespace skycal::gpu
