#include "skycal/gpu/compute_pipeline.h"

#include <cstdlib>
#include <string>

#include "skycal/core/error.h"
#include "skycal/core/device_stats.h"

namespace skycal::gpu {

int EnvironmentChoice(const char* variable, std::initializer_list<const char*> values) {
  const char* env = std::getenv(variable);
  const std::string v = env ? env : "";
  if (v.empty()) return 0;
  std::string expected;
  int i = 0;
  for (const char* option : values) {
    if (v == option) return i;
    expected += (i == 0 ? "" : (i + 1 == static_cast<int>(values.size()) ? " or " : ", ")) + std::string(option);
    ++i;
  }
  throw Error(std::string(variable) + " = '" + v + "': expected " + expected);
}

MemoryMode MemoryModeFromEnvironment() {
  return static_cast<MemoryMode>(EnvironmentChoice("SKYCAL_VULKAN_MEMORY", {"auto", "direct", "staged"}));  // enum order
}

namespace {

VkBufferUsageFlags UsageFor(VkDescriptorType type) {
  switch (type) {
    case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER: return VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT;
    case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: return VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    case VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER: return VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
    case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: return 0;  // a SampledImage, no buffer
    default:
      throw Error("ComputePipeline: only uniform, storage and uniform texel buffer bindings and combined image samplers are supported");
  }
}

}  // namespace

ComputePipeline::ComputePipeline(std::shared_ptr<VulkanContext> ctx, const uint32_t* spirv, size_t spirv_bytes,
                                 std::vector<VkDescriptorType> bindings, std::vector<uint32_t> spec, MemoryMode memory)
    : ctx_(std::move(ctx)),
      types_(std::move(bindings)),
      buffers_(types_.size()),
      staging_(types_.size()),
      readback_(types_.size(), false),
      dirty_(types_.size(), false),
      requested_(types_.size(), 0),
      uploads_(types_.size(), 0),
      upload_bytes_(types_.size(), 0),
      images_(types_.size()),
      views_(types_.size(), VK_NULL_HANDLE) {
  for (VkDescriptorType t : types_) UsageFor(t);  // reject other types before creating anything
  if (memory == MemoryMode::kAuto) memory = MemoryModeFromEnvironment();
  staged_ = memory == MemoryMode::kStaged || (memory == MemoryMode::kAuto && ctx_->has_device_only_memory());
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(ctx_->physical_device(), &props);
  max_texel_buffer_elements_ = props.limits.maxTexelBufferElements;
  try {
    CreateObjects(spirv, spirv_bytes, spec);
  } catch (...) {
    Release();  // a throwing constructor runs no destructor: release what exists
    throw;
  }
}

ComputePipeline::~ComputePipeline() { Release(); }

void ComputePipeline::Release() {
  VkDevice d = ctx_->device();
  vkDeviceWaitIdle(d);
  for (VkBufferView& v : views_) {
    if (v) vkDestroyBufferView(d, v, nullptr);
    v = VK_NULL_HANDLE;
  }
  for (MappedBuffer& b : buffers_) ctx_->DestroyBuffer(b);
  for (MappedBuffer& b : staging_) ctx_->DestroyBuffer(b);
  for (auto& image : images_) image.reset();
  if (sampler_) vkDestroySampler(d, sampler_, nullptr);
  sampler_ = VK_NULL_HANDLE;
  if (queries_) vkDestroyQueryPool(d, queries_, nullptr);
  queries_ = VK_NULL_HANDLE;
  if (fence_) vkDestroyFence(d, fence_, nullptr);
  if (pool_) vkDestroyCommandPool(d, pool_, nullptr);
  if (descriptor_pool_) vkDestroyDescriptorPool(d, descriptor_pool_, nullptr);
  if (pipeline_) vkDestroyPipeline(d, pipeline_, nullptr);
  if (pipeline_layout_) vkDestroyPipelineLayout(d, pipeline_layout_, nullptr);
  if (set_layout_) vkDestroyDescriptorSetLayout(d, set_layout_, nullptr);
  if (shader_) vkDestroyShaderModule(d, shader_, nullptr);
  fence_ = VK_NULL_HANDLE;
  pool_ = VK_NULL_HANDLE;
  descriptor_pool_ = VK_NULL_HANDLE;
  pipeline_ = VK_NULL_HANDLE;
  pipeline_layout_ = VK_NULL_HANDLE;
  set_layout_ = VK_NULL_HANDLE;
  shader_ = VK_NULL_HANDLE;
}

void ComputePipeline::CreateObjects(const uint32_t* spirv, size_t spirv_bytes, const std::vector<uint32_t>& spec) {
  VkDevice d = ctx_->device();
  VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smci.codeSize = spirv_bytes;
  smci.pCode = spirv;
  CheckVk(vkCreateShaderModule(d, &smci, nullptr, &shader_), "vkCreateShaderModule");

  const uint32_t n = static_cast<uint32_t>(types_.size());
  for (VkDescriptorType t : types_) {
    if (t == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER && !sampler_) sampler_ = CreateLinearRepeatSampler(d);
  }
  std::vector<VkDescriptorSetLayoutBinding> layout_bindings(n);
  std::vector<VkDescriptorPoolSize> sizes;
  for (uint32_t i = 0; i < n; ++i) {
    layout_bindings[i].binding = i;
    layout_bindings[i].descriptorType = types_[i];
    layout_bindings[i].descriptorCount = 1;
    layout_bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    bool counted = false;
    for (VkDescriptorPoolSize& ps : sizes) {
      if (ps.type == types_[i]) {
        ++ps.descriptorCount;
        counted = true;
      }
    }
    if (!counted) sizes.push_back({types_[i], 1});
  }
  VkDescriptorSetLayoutCreateInfo dslci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dslci.bindingCount = n;
  dslci.pBindings = layout_bindings.data();
  CheckVk(vkCreateDescriptorSetLayout(d, &dslci, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");

  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &set_layout_;
  CheckVk(vkCreatePipelineLayout(d, &plci, nullptr, &pipeline_layout_), "vkCreatePipelineLayout");

  std::vector<VkSpecializationMapEntry> entries(spec.size());
  for (uint32_t i = 0; i < spec.size(); ++i) entries[i] = {i, static_cast<uint32_t>(i * sizeof(uint32_t)), sizeof(uint32_t)};
  VkSpecializationInfo spec_info{static_cast<uint32_t>(entries.size()), entries.data(), spec.size() * sizeof(uint32_t),
                                 spec.data()};
  VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = shader_;
  cpci.stage.pName = "main";
  cpci.stage.pSpecializationInfo = spec.empty() ? nullptr : &spec_info;
  cpci.layout = pipeline_layout_;
  CheckVk(vkCreateComputePipelines(d, ctx_->pipeline_cache(), 1, &cpci, nullptr, &pipeline_), "vkCreateComputePipelines");
  ctx_->SavePipelineCache();  // a new process finds this pipeline compiled

  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = static_cast<uint32_t>(sizes.size());
  dpci.pPoolSizes = sizes.data();
  CheckVk(vkCreateDescriptorPool(d, &dpci, nullptr, &descriptor_pool_), "vkCreateDescriptorPool");
  VkDescriptorSetAllocateInfo dsai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  dsai.descriptorPool = descriptor_pool_;
  dsai.descriptorSetCount = 1;
  dsai.pSetLayouts = &set_layout_;
  CheckVk(vkAllocateDescriptorSets(d, &dsai, &set_), "vkAllocateDescriptorSets");

  VkCommandPoolCreateInfo cpi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  cpi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  cpi.queueFamilyIndex = ctx_->queue_family();
  CheckVk(vkCreateCommandPool(d, &cpi, nullptr, &pool_), "vkCreateCommandPool");
  VkCommandBufferAllocateInfo cbai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cbai.commandPool = pool_;
  cbai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cbai.commandBufferCount = 1;
  CheckVk(vkAllocateCommandBuffers(d, &cbai, &cmd_), "vkAllocateCommandBuffers");
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  CheckVk(vkCreateFence(d, &fci, nullptr, &fence_), "vkCreateFence");
  if (ctx_->timestamp_valid_bits() > 0) {
    VkQueryPoolCreateInfo qpci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qpci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qpci.queryCount = 2;
    CheckVk(vkCreateQueryPool(d, &qpci, nullptr, &queries_), "vkCreateQueryPool");
  }
}

void* ComputePipeline::Map(uint32_t binding, size_t bytes, bool host_readback) {
  if (binding >= buffers_.size()) throw Error("ComputePipeline: binding " + std::to_string(binding) + " does not exist");
  if (types_[binding] == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER) {
    throw Error("ComputePipeline: binding " + std::to_string(binding) + " is an image (MapImage, not Map)");
  }
  MappedBuffer& b = buffers_[binding];
  if (!b.buffer) readback_[binding] = host_readback;
  if (!b.buffer || b.size < bytes) {
    if (types_[binding] == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER && bytes / 16 > max_texel_buffer_elements_) {
      throw Error("ComputePipeline: binding " + std::to_string(binding) + " needs " + std::to_string(bytes / 16) +
                  " texels, more than the device's maxTexelBufferElements (" +
                  std::to_string(max_texel_buffer_elements_) + ")");
    }
    if (b.buffer) {
      vkDeviceWaitIdle(ctx_->device());
      if (views_[binding]) vkDestroyBufferView(ctx_->device(), views_[binding], nullptr);
      views_[binding] = VK_NULL_HANDLE;
      ctx_->DestroyBuffer(b);
      ctx_->DestroyBuffer(staging_[binding]);
    }
    CreateBuffers(binding, bytes, readback_[binding]);
    descriptors_stale_ = true;
  }
  requested_[binding] = bytes;
  return staged_ ? staging_[binding].mapped : b.mapped;
}

void* ComputePipeline::MapImage(uint32_t binding, const ImageExtent& extent) {
  if (binding >= types_.size() || types_[binding] != VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER) {
    throw Error("ComputePipeline: binding " + std::to_string(binding) + " is not an image binding");
  }
  std::unique_ptr<SampledImage>& image = images_[binding];
  if (!image || !(image->extent() == extent)) {
    if (image) vkDeviceWaitIdle(ctx_->device());
    image.reset();
    image = std::make_unique<SampledImage>(*ctx_, extent);
    descriptors_stale_ = true;
  }
  requested_[binding] = image->bytes();
  return image->staging();
}

void ComputePipeline::CreateBuffers(uint32_t binding, size_t bytes, bool host_readback) {
  // Vulkan forbids zero-sized buffers; an empty binding still needs a valid descriptor.
  const VkDeviceSize size = bytes > 0 ? bytes : 16;
  MappedBuffer& b = buffers_[binding];
  const VkBufferUsageFlags usage = UsageFor(types_[binding]);
  if (staged_) {
    b = ctx_->CreateDeviceBuffer(size, usage | (host_readback ? VK_BUFFER_USAGE_TRANSFER_SRC_BIT : VK_BUFFER_USAGE_TRANSFER_DST_BIT));
    staging_[binding] = ctx_->CreateMappedBuffer(
        size, host_readback ? VK_BUFFER_USAGE_TRANSFER_DST_BIT : VK_BUFFER_USAGE_TRANSFER_SRC_BIT, host_readback);
  } else {
    b = ctx_->CreateMappedBuffer(size, usage, host_readback);
  }
  dirty_[binding] = false;
  if (types_[binding] == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER) {
    VkBufferViewCreateInfo vci{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    vci.buffer = b.buffer;
    vci.format = kTexelBufferFormat;
    vci.offset = 0;
    vci.range = VK_WHOLE_SIZE;
    CheckVk(vkCreateBufferView(ctx_->device(), &vci, nullptr, &views_[binding]), "vkCreateBufferView");
  }
}

void ComputePipeline::Flush(uint32_t binding) {
  if (images_.at(binding)) {
    images_[binding]->Flush();
    ++uploads_[binding];
    upload_bytes_[binding] += static_cast<long long>(requested_[binding]);
    return;
  }
  ctx_->FlushForDevice(staged_ ? staging_.at(binding) : buffers_.at(binding));
  if (staged_) dirty_[binding] = true;
  ++uploads_[binding];
  upload_bytes_[binding] += static_cast<long long>(requested_[binding]);
}

const void* ComputePipeline::Read(uint32_t binding) const {
  return staged_ ? staging_.at(binding).mapped : buffers_.at(binding).mapped;
}

size_t ComputePipeline::Size(uint32_t binding) const { return static_cast<size_t>(buffers_.at(binding).size); }

void ComputePipeline::WriteDescriptors() {
  const uint32_t n = static_cast<uint32_t>(types_.size());
  std::vector<VkDescriptorBufferInfo> infos(n);
  std::vector<VkDescriptorImageInfo> image_infos(n);
  std::vector<VkWriteDescriptorSet> writes(n);
  for (uint32_t i = 0; i < n; ++i) {
    writes[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    writes[i].dstSet = set_;
    writes[i].dstBinding = i;
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = types_[i];
    if (types_[i] == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER) {
      if (!images_[i]) throw Error("ComputePipeline: binding " + std::to_string(i) + " has no image (MapImage it before Dispatch)");
      image_infos[i] = {sampler_, images_[i]->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
      writes[i].pImageInfo = &image_infos[i];
      continue;
    }
    if (!buffers_[i].buffer) throw Error("ComputePipeline: binding " + std::to_string(i) + " has no buffer (Map it before Dispatch)");
    infos[i] = {buffers_[i].buffer, 0, VK_WHOLE_SIZE};
    if (types_[i] == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER) {
      writes[i].pTexelBufferView = &views_[i];
    } else {
      writes[i].pBufferInfo = &infos[i];
    }
  }
  vkUpdateDescriptorSets(ctx_->device(), n, writes.data(), 0, nullptr);
  descriptors_stale_ = false;
}

// The Flush()ed images copied from their staging buffers (each with its own layout
// barriers); staged: the Flush()ed buffers' staging copied to their device buffers, then a
// barrier that makes the copies visible to the shader's reads.
void ComputePipeline::RecordUploads() {
  for (auto& image : images_) {
    if (image && image->dirty()) image->RecordUpload(cmd_);
  }
  bool any = false;
  for (uint32_t i = 0; i < buffers_.size() && staged_; ++i) {
    if (!dirty_[i] || requested_[i] == 0 || images_[i]) continue;
    const VkBufferCopy region{0, 0, requested_[i]};
    vkCmdCopyBuffer(cmd_, staging_[i].buffer, buffers_[i].buffer, 1, &region);
    any = true;
  }
  if (!any) return;
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT;
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                       nullptr, 0, nullptr);
}

// After the dispatch: staged readback bindings copied to their host buffers; then the
// writes (the shader's or the copies') made visible to the host once the fence signals.
void ComputePipeline::RecordReadbacks() {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  if (staged_) {
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    for (uint32_t i = 0; i < buffers_.size(); ++i) {
      if (!readback_[i] || requested_[i] == 0) continue;
      const VkBufferCopy region{0, 0, requested_[i]};
      vkCmdCopyBuffer(cmd_, buffers_[i].buffer, staging_[i].buffer, 1, &region);
    }
  }
  barrier.srcAccessMask = staged_ ? VK_ACCESS_TRANSFER_WRITE_BIT : VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd_, staged_ ? VK_PIPELINE_STAGE_TRANSFER_BIT : VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

void ComputePipeline::Record(uint32_t gx, uint32_t gy, uint32_t gz) {
  CheckVk(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  CheckVk(vkBeginCommandBuffer(cmd_, &bi), "vkBeginCommandBuffer");
  if (queries_) {
    vkCmdResetQueryPool(cmd_, queries_, 0, 2);
    vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
  }
  RecordUploads();
  vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
  vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout_, 0, 1, &set_, 0, nullptr);
  vkCmdDispatch(cmd_, gx, gy, gz);
  RecordReadbacks();
  if (queries_) vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, 1);
  CheckVk(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
}

// The two timestamps' difference in ms: ticks masked to the valid bits (a counter that
// wrapped between them still gives the right difference), times timestampPeriod ns.
std::optional<double> ComputePipeline::ReadTimestamps() {
  if (!queries_) return std::nullopt;
  uint64_t ticks[2] = {0, 0};
  const VkResult r = vkGetQueryPoolResults(ctx_->device(), queries_, 0, 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                           VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
  if (r != VK_SUCCESS) return std::nullopt;
  const uint32_t bits = ctx_->timestamp_valid_bits();
  const uint64_t mask = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
  const uint64_t delta = ((ticks[1] & mask) - (ticks[0] & mask)) & mask;
  return static_cast<double>(delta) * ctx_->timestamp_period_ns() * 1e-6;
}

void ComputePipeline::Dispatch(uint32_t gx, uint32_t gy, uint32_t gz) {
  if (descriptors_stale_) WriteDescriptors();
  Record(gx, gy, gz);
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd_;
  CheckVk(vkQueueSubmit(ctx_->queue(), 1, &si, fence_), "vkQueueSubmit");
  CheckVk(vkWaitForFences(ctx_->device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  CheckVk(vkResetFences(ctx_->device(), 1, &fence_), "vkResetFences");
  for (uint32_t i = 0; i < buffers_.size(); ++i) {
    dirty_[i] = false;
    if (staged_ && readback_[i]) ctx_->InvalidateForRead(staging_[i]);
    if (!staged_ && types_[i] == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER) ctx_->InvalidateForRead(buffers_[i]);
  }
  last_gpu_ms_ = ReadTimestamps();
  AddDeviceTime(last_gpu_ms_);
}

}  // namespace skycal::gpu
