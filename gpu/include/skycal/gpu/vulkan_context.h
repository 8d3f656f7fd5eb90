// Vulkan instance, device and queue, created once and shared by every pipeline of the
// process (the sky's and the clouds'). Plain C API (vulkan.h): vulkan.hpp is slow to
// compile (docs/architecture.md). Include only from renderer sources, never from a public header of
// render/ or clouds/.
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <memory>
#include <string>

namespace skycal::gpu {

// A host-visible buffer, persistently mapped.
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
  void DestroyBuffer(MappedBuffer& b);
  void InvalidateForRead(const MappedBuffer& b);
  void FlushForDevice(const MappedBuffer& b);

 private:
  VulkanContext() = default;
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
  std::atomic<int> validation_messages_{0};
};

// Throws skycal::Error("Vulkan: <what> failed: <VkResult name>") unless result is VK_SUCCESS.
void CheckVk(VkResult result, const char* what);
const char* VkResultName(VkResult r);

}  // namespace skycal::gpu
