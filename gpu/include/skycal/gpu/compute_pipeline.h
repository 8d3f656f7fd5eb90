// One compute shader with one descriptor set of buffers: the pipeline setup every skycal
// renderer needs (shader module, set layout, pipeline with specialization constants,
// descriptor pool and set, command buffer, fence), written once. Each binding owns a
// persistently mapped host-visible buffer that grows on demand; a dispatch records, submits
// and waits, and leaves the shader's storage writes readable by the host.
//
// Include only from renderer sources (vulkan.h; see vulkan_context.h).
#pragma once
#include <vulkan/vulkan.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "skycal/gpu/vulkan_context.h"

namespace skycal::gpu {

class ComputePipeline {
 public:
  // The format of every VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER binding's view: vec4 of float.
  static constexpr VkFormat kTexelBufferFormat = VK_FORMAT_R32G32B32A32_SFLOAT;

  // bindings[i]: the descriptor type of binding i (VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
  // VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, or VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER: a
  // samplerBuffer of kTexelBufferFormat texels, read with texelFetch; on lavapipe a
  // texelFetch of a vec4 gathers one 16-byte texel per lane, where a storage-buffer load
  // runs a bounds-checked scalar loop per lane and component); spec[i]: specialization
  // constant i (uint32).
  // Throws skycal::Error on a Vulkan failure or an unsupported descriptor type.
  ComputePipeline(std::shared_ptr<VulkanContext> ctx, const uint32_t* spirv, size_t spirv_bytes,
                  std::vector<VkDescriptorType> bindings, std::vector<uint32_t> spec = {});
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  // The mapped memory of `binding`'s buffer, at least `bytes` long (grown, never shrunk;
  // growing waits for the device and rebinds the set; a texel buffer larger than the
  // device's maxTexelBufferElements throws skycal::Error). `host_readback` asks for
  // HOST_CACHED memory: reading a large output from write-combined memory is slow.
  void* Map(uint32_t binding, size_t bytes, bool host_readback = false);
  // Makes host writes to `binding` visible to the device (a no-op on coherent memory).
  void Flush(uint32_t binding);
  // Records one dispatch of (gx, gy, gz) workgroups, submits it and waits; afterwards
  // every storage buffer's writes are visible through Read().
  void Dispatch(uint32_t gx, uint32_t gy, uint32_t gz);
  // `binding`'s mapped memory (after Dispatch: invalidated for the host).
  const void* Read(uint32_t binding) const;
  size_t Size(uint32_t binding) const;

  VulkanContext& context() { return *ctx_; }

 private:
  void Release();  // destroys every Vulkan object (idempotent)
  void CreateObjects(const uint32_t* spirv, size_t spirv_bytes, const std::vector<uint32_t>& spec);
  void WriteDescriptors();
  void Record(uint32_t gx, uint32_t gy, uint32_t gz);

  std::shared_ptr<VulkanContext> ctx_;
  std::vector<VkDescriptorType> types_;
  std::vector<MappedBuffer> buffers_;
  std::vector<VkBufferView> views_;
  uint32_t max_texel_buffer_elements_ = 0;  // per binding: the texel buffer's view (VK_NULL_HANDLE otherwise)
  bool descriptors_stale_ = true;
  VkShaderModule shader_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout pipeline_layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptor_pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
};

}  // namespace skycal::gpu
