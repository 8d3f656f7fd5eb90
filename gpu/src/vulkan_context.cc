#include "skycal/gpu/vulkan_context.h"

#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/gpu/pipeline_cache.h"

namespace skycal::gpu {

const char* VkResultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    default: return "VkResult(other)";
  }
}

void CheckVk(VkResult result, const char* what) {
  if (result == VK_ERROR_OUT_OF_DEVICE_MEMORY || result == VK_ERROR_OUT_OF_HOST_MEMORY) {
    throw Error(std::string("Vulkan: ") + what + " failed: " + VkResultName(result) +
                " (the image does not fit in the device's memory: try a smaller --size, or --backend cpu)");
  }
  if (result != VK_SUCCESS) throw Error(std::string("Vulkan: ") + what + " failed: " + VkResultName(result));
}

namespace {

bool HasLayer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (const auto& l : layers) {
    if (std::strcmp(l.layerName, name) == 0) return true;
  }
  return false;
}

bool HasInstanceExtension(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceExtensionProperties(nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> ext(n);
  vkEnumerateInstanceExtensionProperties(nullptr, &n, ext.data());
  for (const auto& e : ext) {
    if (std::strcmp(e.extensionName, name) == 0) return true;
  }
  return false;
}

int DeviceRank(VkPhysicalDeviceType t) {  // higher is preferred
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
    default: return 0;
  }
}

constexpr const char* kNoDevice =
    "no Vulkan device available (on a CPU-only Debian machine install mesa-vulkan-drivers for lavapipe; "
    "or render with --backend cpu)";

}  // namespace

VKAPI_ATTR VkBool32 VKAPI_CALL VulkanContext::OnValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                                 VkDebugUtilsMessageTypeFlagsEXT,
                                                                 const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                                 void* user) {
  auto* self = static_cast<VulkanContext*>(user);
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    self->validation_messages_++;
    std::cerr << "[vulkan validation] " << (data && data->pMessage ? data->pMessage : "(no message)") << "\n";
  }
  return VK_FALSE;
}

std::shared_ptr<VulkanContext> VulkanContext::Create(bool validation) {
  const char* env = std::getenv("SKYCAL_VULKAN_VALIDATION");
  if (env && std::string(env) == "1") validation = true;
  std::shared_ptr<VulkanContext> ctx(new VulkanContext());

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "skycal";
  app.apiVersion = VK_API_VERSION_1_1;
  std::vector<const char*> layers, extensions;
  const bool debug_utils = validation && HasInstanceExtension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (validation) {
    if (!HasLayer("VK_LAYER_KHRONOS_validation")) {
      throw Error("Vulkan validation requested but VK_LAYER_KHRONOS_validation is not installed "
                  "(Debian: apt-get install vulkan-validationlayers)");
    }
    layers.push_back("VK_LAYER_KHRONOS_validation");
    if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  const VkResult r = vkCreateInstance(&ici, nullptr, &ctx->instance_);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER) throw Error(kNoDevice);
  CheckVk(r, "vkCreateInstance");

  if (debug_utils) {
    VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                      VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mci.pfnUserCallback = &VulkanContext::OnValidationMessage;
    mci.pUserData = ctx.get();
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(ctx->instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (create) CheckVk(create(ctx->instance_, &mci, nullptr, &ctx->messenger_), "vkCreateDebugUtilsMessengerEXT");
  }

  ctx->ChooseDevice();
  if (ctx->physical_ == VK_NULL_HANDLE) throw Error(kNoDevice);
  vkGetPhysicalDeviceMemoryProperties(ctx->physical_, &ctx->memory_);
  ctx->ReadTimestampSupport();

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = ctx->queue_family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  CheckVk(vkCreateDevice(ctx->physical_, &dci, nullptr, &ctx->device_), "vkCreateDevice");
  vkGetDeviceQueue(ctx->device_, ctx->queue_family_, 0, &ctx->queue_);
  ctx->OpenPipelineCache();
  return ctx;
}

// The most capable device with a compute queue (DeviceRank: discrete, integrated, virtual,
// CPU), its first compute family.
void VulkanContext::ChooseDevice() {
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance_, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  if (count) vkEnumeratePhysicalDevices(instance_, &count, devices.data());
  int best_rank = -1;
  for (VkPhysicalDevice d : devices) {
    uint32_t nq = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, nullptr);
    std::vector<VkQueueFamilyProperties> qf(nq);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &nq, qf.data());
    for (uint32_t i = 0; i < nq; ++i) {
      if (!(qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
      VkPhysicalDeviceProperties props;
      vkGetPhysicalDeviceProperties(d, &props);
      const int rank = DeviceRank(props.deviceType);
      if (rank > best_rank) {
        best_rank = rank;
        physical_ = d;
        queue_family_ = i;
        device_name_ = props.deviceName;
      }
      break;
    }
  }
}

void VulkanContext::ReadTimestampSupport() {
  uint32_t nq = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nq, nullptr);
  std::vector<VkQueueFamilyProperties> qf(nq);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &nq, qf.data());
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical_, &props);
  // timestampValidBits 0: this family writes no timestamps (timestampComputeAndGraphics
  // only promises them on every graphics and compute family; the family's bits decide).
  timestamp_valid_bits_ = queue_family_ < nq ? qf[queue_family_].timestampValidBits : 0;
  timestamp_period_ns_ = props.limits.timestampPeriod;
  if (!(timestamp_period_ns_ > 0.0)) timestamp_valid_bits_ = 0;
  const char* off = std::getenv("SKYCAL_VULKAN_TIMESTAMPS");  // 0: no queries (device times null)
  if (off && std::string(off) == "0") timestamp_valid_bits_ = 0;
}

void VulkanContext::OpenPipelineCache() {
  const std::string dir = PipelineCacheDir();
  if (dir.empty()) return;  // SKYCAL_PIPELINE_CACHE=0: pipelines are compiled every time
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical_, &props);
  PipelineCacheKey key;
  key.vendor_id = props.vendorID;
  key.device_id = props.deviceID;
  key.driver_version = props.driverVersion;
  std::memcpy(key.uuid, props.pipelineCacheUUID, VK_UUID_SIZE);
  pipeline_cache_ = std::make_unique<PipelineCache>(device_, key, PipelineCachePath(dir, key));
}

VkPipelineCache VulkanContext::pipeline_cache() const {
  return pipeline_cache_ ? pipeline_cache_->handle() : VK_NULL_HANDLE;
}

void VulkanContext::SavePipelineCache() {
  if (pipeline_cache_) pipeline_cache_->Save();
}

std::shared_ptr<VulkanContext> VulkanContext::Shared(bool validation) {
  // A cache of a device handle, not of options: at most one context per validation mode,
  // released when its last renderer goes.
  static std::mutex mutex;
  static std::weak_ptr<VulkanContext> cached[2];
  std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<VulkanContext> ctx = cached[validation ? 1 : 0].lock();
  if (!ctx) {
    ctx = Create(validation);
    cached[validation ? 1 : 0] = ctx;
  }
  return ctx;
}

VulkanContext::~VulkanContext() {
  pipeline_cache_.reset();  // before its device
  if (device_) vkDestroyDevice(device_, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

namespace {

// An exclusive buffer of `size` bytes and its memory requirements (no memory bound yet).
VkBuffer NewBuffer(VkDevice device, VkDeviceSize size, VkBufferUsageFlags usage, VkMemoryRequirements* req) {
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer = VK_NULL_HANDLE;
  CheckVk(vkCreateBuffer(device, &bci, nullptr, &buffer), "vkCreateBuffer");
  vkGetBufferMemoryRequirements(device, buffer, req);
  return buffer;
}

// Memory of type `type` allocated for `buffer` and bound to it; the buffer is destroyed when
// the allocation fails.
VkDeviceMemory AllocateBound(VkDevice device, VkBuffer buffer, const VkMemoryRequirements& req, uint32_t type) {
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = type;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  const VkResult r = vkAllocateMemory(device, &mai, nullptr, &memory);
  if (r != VK_SUCCESS) {
    vkDestroyBuffer(device, buffer, nullptr);
    CheckVk(r, "vkAllocateMemory");
  }
  CheckVk(vkBindBufferMemory(device, buffer, memory, 0), "vkBindBufferMemory");
  return memory;
}

}  // namespace

MappedBuffer VulkanContext::CreateMappedBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool prefer_cached) {
  MappedBuffer b;
  b.size = size;
  VkMemoryRequirements req;
  b.buffer = NewBuffer(device_, size, usage, &req);
  // Prefer HOST_VISIBLE|HOST_COHERENT (+HOST_CACHED for readback); accept any HOST_VISIBLE.
  const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT |
                                     (prefer_cached ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT : 0);
  int chosen = -1;
  for (int pass = 0; pass < 3 && chosen < 0; ++pass) {
    const VkMemoryPropertyFlags need = pass == 0 ? want
                                       : pass == 1 ? (VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
                                                   : VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
    for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
      if ((req.memoryTypeBits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & need) == need) {
        chosen = static_cast<int>(i);
        break;
      }
    }
  }
  if (chosen < 0) {
    vkDestroyBuffer(device_, b.buffer, nullptr);
    throw Error("Vulkan: no host-visible memory type for a buffer");
  }
  b.coherent = memory_.memoryTypes[chosen].propertyFlags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  b.memory = AllocateBound(device_, b.buffer, req, static_cast<uint32_t>(chosen));
  CheckVk(vkMapMemory(device_, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
  return b;
}

bool VulkanContext::has_device_only_memory() const {
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
    if ((f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) && !(f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) return true;
  }
  return false;
}

int VulkanContext::DeviceLocalMemoryType(uint32_t type_bits) const {
  // DEVICE_LOCAL without HOST_VISIBLE first (a discrete GPU's VRAM, not its small BAR
  // window), then any DEVICE_LOCAL, then anything (unified memory).
  for (int pass = 0; pass < 3; ++pass) {
    for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
      const VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
      const bool ok = pass == 0   ? (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) && !(f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)
                      : pass == 1 ? (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0
                                  : true;
      if ((type_bits & (1u << i)) && ok) return static_cast<int>(i);
    }
  }
  return -1;
}

MappedBuffer VulkanContext::CreateDeviceBuffer(VkDeviceSize size, VkBufferUsageFlags usage) {
  MappedBuffer b;
  b.size = size;
  VkMemoryRequirements req;
  b.buffer = NewBuffer(device_, size, usage, &req);
  const int chosen = DeviceLocalMemoryType(req.memoryTypeBits);
  if (chosen < 0) {
    vkDestroyBuffer(device_, b.buffer, nullptr);
    throw Error("Vulkan: no memory type for a device buffer");
  }
  b.memory = AllocateBound(device_, b.buffer, req, static_cast<uint32_t>(chosen));
  return b;
}

void VulkanContext::DestroyBuffer(MappedBuffer& b) {
  if (b.memory) {
    if (b.mapped) vkUnmapMemory(device_, b.memory);
    vkFreeMemory(device_, b.memory, nullptr);
  }
  if (b.buffer) vkDestroyBuffer(device_, b.buffer, nullptr);
  b = MappedBuffer{};
}

void VulkanContext::InvalidateForRead(const MappedBuffer& b) {
  if (b.coherent) return;
  VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
  range.memory = b.memory;
  range.size = VK_WHOLE_SIZE;
  CheckVk(vkInvalidateMappedMemoryRanges(device_, 1, &range), "vkInvalidateMappedMemoryRanges");
}

void VulkanContext::FlushForDevice(const MappedBuffer& b) {
  if (b.coherent) return;
  VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
  range.memory = b.memory;
  range.size = VK_WHOLE_SIZE;
  CheckVk(vkFlushMappedMemoryRanges(device_, 1, &range), "vkFlushMappedMemoryRanges");
}

}  // namespace skycal::gpu
