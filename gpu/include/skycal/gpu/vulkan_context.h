// Vulkan instance, device and queue, created once and shared by every pipeline of the
// process (the sky's and the clouds'). Plain C API (vulkan.h): vulkan.hpp is slow to
// compile (docs/architecture.md). Include only from renderer sources, never from a public header of
// render/ or clouds/.
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>

namespace skycal::gpu {

class PipelineCache;

// A buffer and its memory: host-visible and persistently mapped, or device-local
// (mapped == nullptr).
struct MappedBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  VkDeviceSize size = 0;
  bool coherent = true;
};

class VulkanContext {
 public:
  // Throws skycal::Error with a message that says what to install or which backend to
  // use instead, when no Vulkan driver or no compute-capable device exists.
  static std::shared_ptr<VulkanContext> Create(bool validation);
  // The process's context for `validation`: created on first use, shared while anyone
  // holds it (the sky and cloud renderers of one render use one device and queue).
  static std::shared_ptr<VulkanContext> Shared(bool validation);
  ~VulkanContext();
  VulkanContext(const VulkanContext&) = delete;
  VulkanContext& operator=(const VulkanContext&) = delete;

  VkPhysicalDevice physical_device() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  const std::string& device_name() const { return device_name_; }
  bool validation_enabled() const { return messenger_ != VK_NULL_HANDLE; }
  // Validation warnings and errors reported so far (0 when validation is off).
  int validation_messages() const { return validation_messages_.load(); }

  // usage: VK_BUFFER_USAGE_*; prefer_cached asks for HOST_CACHED memory (fast readback).
  MappedBuffer CreateMappedBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool prefer_cached);
  // A DEVICE_LOCAL buffer, preferring a type that is not host-visible (a discrete GPU's
  // own memory), not mapped; filled and read by transfer commands.
  MappedBuffer CreateDeviceBuffer(VkDeviceSize size, VkBufferUsageFlags usage);
  // The memory type CreateDeviceBuffer would choose among `type_bits`
  // (VkMemoryRequirements::memoryTypeBits), or -1 when none: images use it too.
  int DeviceLocalMemoryType(uint32_t type_bits) const;
  // True when some memory type is DEVICE_LOCAL and not HOST_VISIBLE (a discrete GPU):
  // resources then go there through staging uploads. False on lavapipe and unified memory,
  // where device-local memory is the host's.
  bool has_device_only_memory() const;

  // Timestamp queries on the queue: the nanoseconds per tick and the valid bits (0: the
  // queue family writes no timestamps; then device times are reported as unknown).
  uint32_t timestamp_valid_bits() const { return timestamp_valid_bits_; }
  double timestamp_period_ns() const { return timestamp_period_ns_; }

  // The pipeline cache every pipeline is created with (VK_NULL_HANDLE when disabled), and
  // its on-disk file (pipeline_cache.h); SavePipelineCache writes it when it changed.
  VkPipelineCache pipeline_cache() const;
  void SavePipelineCache();
  const PipelineCache* pipeline_cache_file() const { return pipeline_cache_.get(); }
  void DestroyBuffer(MappedBuffer& b);
  void InvalidateForRead(const MappedBuffer& b);
  void FlushForDevice(const MappedBuffer& b);

 private:
  VulkanContext() = default;
  void ChooseDevice();
  void ReadTimestampSupport();
  void OpenPipelineCache();
  static VKAPI_ATTR VkBool32 VKAPI_CALL OnValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                           VkDebugUtilsMessageTypeFlagsEXT types,
                                                           const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  std::string device_name_;
  VkPhysicalDeviceMemoryProperties memory_{};
  uint32_t timestamp_valid_bits_ = 0;
  double timestamp_period_ns_ = 0.0;
  std::unique_ptr<PipelineCache> pipeline_cache_;
  std::atomic<int> validation_messages_{0};
};

// Throws skycal::Error("Vulkan: <what> failed: <VkResult name>") unless result is VK_SUCCESS.
void CheckVk(VkResult result, const char* what);
const char* VkResultName(VkResult r);

}  // namespace skycal::gpu
