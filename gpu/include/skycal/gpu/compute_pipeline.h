// One compute shader with one descriptor set of buffers and sampled images: the pipeline
// setup every skycal renderer needs (shader module, set layout, pipeline with
// specialization constants from the context's pipeline cache, descriptor pool and set,
// command buffer, fence), written once. Each buffer binding owns a buffer that grows on
// demand, each image binding a SampledImage; a dispatch records, submits and waits, and
// leaves the shader's storage writes readable by the host.
//
// Memory, chosen per pipeline (MemoryMode): `direct`, every buffer host-visible and read by
// the shader in place (lavapipe and unified memory, where device-local memory is the
// host's); `staged`, every buffer device-local, the host writing a persistently mapped
// staging buffer that the next Dispatch copies over (only bindings Flush()ed since: a
// texture is uploaded once per change of content), and host-readback bindings copied into
// a HOST_CACHED buffer after the dispatch. Auto picks staged where the device has memory
// that is device-local and not host-visible (a discrete GPU); SKYCAL_VULKAN_MEMORY=
// direct|staged|auto overrides it. Both give the same bits: only where the bytes live differs.
//
// Include only from renderer sources (vulkan.h; see vulkan_context.h).
#pragma once
#include <vulkan/vulkan.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <vector>

#include "skycal/gpu/sampled_image.h"
#include "skycal/gpu/vulkan_context.h"

namespace skycal::gpu {

// Which of `values` the environment variable names: its index, 0 when it is unset or
// empty. Throws skycal::Error "<variable> = '<value>': expected a, b or c" otherwise. The
// one parser of skycal's SKYCAL_VULKAN_* choices.
int EnvironmentChoice(const char* variable, std::initializer_list<const char*> values);

enum class MemoryMode { kAuto, kDirect, kStaged };
// SKYCAL_VULKAN_MEMORY (unset or empty: kAuto); throws skycal::Error naming the variable and
// its value unless it is auto, direct or staged.
MemoryMode MemoryModeFromEnvironment();

class ComputePipeline {
 public:
  // The format of every VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER binding's view: vec4 of float.
  static constexpr VkFormat kTexelBufferFormat = VK_FORMAT_R32G32B32A32_SFLOAT;

  // bindings[i]: the descriptor type of binding i (VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
  // VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, or VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER: a
  // samplerBuffer of kTexelBufferFormat texels, read with texelFetch; on lavapipe a
  // texelFetch of a vec4 gathers one 16-byte texel per lane, where a storage-buffer load
  // runs a bounds-checked scalar loop per lane and component); spec[i]: specialization
  // constant i (uint32); or VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: a SampledImage
  // (sampled_image.h) read through the hardware's linear filter with repeat addressing,
  // filled through MapImage in either memory mode.
  // Throws skycal::Error on a Vulkan failure or an unsupported descriptor type.
  // `memory`: kAuto resolves SKYCAL_VULKAN_MEMORY, then the device (see above).
  ComputePipeline(std::shared_ptr<VulkanContext> ctx, const uint32_t* spirv, size_t spirv_bytes,
                  std::vector<VkDescriptorType> bindings, std::vector<uint32_t> spec = {},
                  MemoryMode memory = MemoryMode::kAuto);
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  // The mapped memory of `binding`'s buffer, at least `bytes` long (grown, never shrunk;
  // growing waits for the device and rebinds the set; a texel buffer larger than the
  // device's maxTexelBufferElements throws skycal::Error). `host_readback` asks for
  // HOST_CACHED memory: reading a large output from write-combined memory is slow.
  void* Map(uint32_t binding, size_t bytes, bool host_readback = false);
  // The staging memory of image binding `binding`, `extent` texels of 4 floats (x fastest);
  // the image is (re)made when the extent changes (waiting for the device). Flush() then
  // uploads it with the next Dispatch. Throws skycal::Error for a binding that is not an
  // image, or when the device cannot make the image.
  void* MapImage(uint32_t binding, const ImageExtent& extent);
  // Makes host writes to `binding` (the first `bytes` Map asked for) visible to the device:
  // flushes non-coherent memory, and when staged schedules the copy to the device buffer
  // for the next Dispatch. Counted as one upload of the binding.
  void Flush(uint32_t binding);
  // Records one dispatch of (gx, gy, gz) workgroups, submits it and waits; afterwards
  // every storage buffer's writes are visible through Read().
  void Dispatch(uint32_t gx, uint32_t gy, uint32_t gz);
  // `binding`'s mapped memory (after Dispatch: invalidated for the host).
  const void* Read(uint32_t binding) const;
  size_t Size(uint32_t binding) const;

  bool staged() const { return staged_; }
  // The last Dispatch's device time (timestamps around its command buffer: uploads,
  // dispatch, readback copy), ms; nullopt before the first or without timestamp support.
  std::optional<double> last_gpu_ms() const { return last_gpu_ms_; }
  // Flush()es of `binding` so far, and the bytes they covered.
  long long uploads(uint32_t binding) const { return uploads_.at(binding); }
  long long upload_bytes(uint32_t binding) const { return upload_bytes_.at(binding); }

  VulkanContext& context() { return *ctx_; }

 private:
  void Release();  // destroys every Vulkan object (idempotent)
  void CreateObjects(const uint32_t* spirv, size_t spirv_bytes, const std::vector<uint32_t>& spec);
  void CreateBuffers(uint32_t binding, size_t bytes, bool host_readback);
  void WriteDescriptors();
  void Record(uint32_t gx, uint32_t gy, uint32_t gz);
  void RecordUploads();
  void RecordReadbacks();
  std::optional<double> ReadTimestamps();

  std::shared_ptr<VulkanContext> ctx_;
  std::vector<VkDescriptorType> types_;
  bool staged_ = false;
  std::vector<MappedBuffer> buffers_;   // what the shader reads and writes
  std::vector<MappedBuffer> staging_;   // staged: the host's side (upload or readback buffer)
  std::vector<bool> readback_;          // the binding is read back by the host
  std::vector<bool> dirty_;             // staged: Flush()ed since the last upload
  std::vector<size_t> requested_;       // bytes the last Map asked for
  std::vector<long long> uploads_, upload_bytes_;
  VkQueryPool queries_ = VK_NULL_HANDLE;  // two timestamps per Dispatch (none without support)
  std::optional<double> last_gpu_ms_;
  std::vector<std::unique_ptr<SampledImage>> images_;  // image bindings (nullptr otherwise)
  VkSampler sampler_ = VK_NULL_HANDLE;                  // made when any binding is an image
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
