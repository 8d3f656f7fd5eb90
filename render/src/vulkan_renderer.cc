// The Vulkan compute renderer: one pipeline (render/shaders/sky_latlong.comp), buffers
// reused between renders and grown on demand, one submit and fence wait per render.
#include <cmath>
#include <cstring>
#include <vector>

#include "cpu_renderer.h"
#include "resolved_sky.h"
#include "sky_uniforms.h"
#include "skycal/core/error.h"
#include "vulkan_context.h"

namespace skycal::spirv {
extern const uint32_t sky_latlong[];
extern const size_t sky_latlong_size;
}  // namespace skycal::spirv

namespace skycal::render {
namespace {

// Workgroup size (specialization constants 0, 1). The shader maps one image row to one
// workgroup (y = gl_WorkGroupID.y), so the second dimension must stay 1.
constexpr uint32_t kLocalX = 128, kLocalY = 1;
// Bindings of sky_latlong.comp: 0 uniforms, 1 LUTs, 2 output, 3 direction trig table.
constexpr uint32_t kBindings = 4;
constexpr VkDescriptorType kBindingTypes[kBindings] = {
    VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

class VulkanSkyRenderer final : public SkyRenderer {
 public:
  explicit VulkanSkyRenderer(std::shared_ptr<VulkanContext> ctx) : ctx_(std::move(ctx)) { CreatePipeline(); }
  ~VulkanSkyRenderer() override {
    VkDevice d = ctx_->device();
    vkDeviceWaitIdle(d);
    ctx_->DestroyBuffer(uniforms_);
    ctx_->DestroyBuffer(luts_);
    ctx_->DestroyBuffer(output_);
    ctx_->DestroyBuffer(trig_);
    if (fence_) vkDestroyFence(d, fence_, nullptr);
    if (pool_) vkDestroyCommandPool(d, pool_, nullptr);
    if (descriptor_pool_) vkDestroyDescriptorPool(d, descriptor_pool_, nullptr);
    if (pipeline_) vkDestroyPipeline(d, pipeline_, nullptr);
    if (pipeline_layout_) vkDestroyPipelineLayout(d, pipeline_layout_, nullptr);
    if (set_layout_) vkDestroyDescriptorSetLayout(d, set_layout_, nullptr);
    if (shader_) vkDestroyShaderModule(d, shader_, nullptr);
  }

  ImageRGB Render(const Preset& preset, const RenderRequest& request) override {
    const SkyParamsD params = ResolveSkyParams(preset, request);
    const SkyUniforms u = PackSkyUniforms(params, request.width, request.height);

    const int columns = preset.luts.grid.n_gamma;
    const VkDeviceSize lut_bytes = 3 * static_cast<VkDeviceSize>(kMaxLutColumns) * 4 * sizeof(float);
    if (columns > kMaxLutColumns) throw Error("Vulkan renderer: LUT has " + std::to_string(columns) + " columns, at most " + std::to_string(kMaxLutColumns) + " supported");
    const VkDeviceSize out_bytes = static_cast<VkDeviceSize>(request.width) * request.height * 3 * sizeof(float);
    bool rebind = false;
    rebind |= Ensure(uniforms_, sizeof(SkyUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, false);
    rebind |= Ensure(luts_, lut_bytes, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, false);
    rebind |= Ensure(output_, out_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    const VkDeviceSize trig_bytes = static_cast<VkDeviceSize>(request.width + request.height) * 2 * sizeof(float);
    rebind |= Ensure(trig_, trig_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false);
    if (rebind) WriteDescriptors();
    if (trig_width_ != request.width || trig_height_ != request.height) FillTrigTable(preset, request.width, request.height);

    std::memcpy(uniforms_.mapped, &u, sizeof(u));
    FillLutSlice(preset, params, static_cast<float*>(luts_.mapped));
    ctx_->FlushForDevice(uniforms_);
    ctx_->FlushForDevice(luts_);

    Record(request.width, request.height);
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd_;
    CheckVk(vkQueueSubmit(ctx_->queue(), 1, &si, fence_), "vkQueueSubmit");
    CheckVk(vkWaitForFences(ctx_->device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    CheckVk(vkResetFences(ctx_->device(), 1, &fence_), "vkResetFences");
    ctx_->InvalidateForRead(output_);

    // One pass over the mapped memory (no zero-fill of a fresh vector first).
    ImageRGB image;
    image.width = request.width;
    image.height = request.height;
    const float* mapped = static_cast<const float*>(output_.mapped);
    image.pixels.assign(mapped, mapped + out_bytes / sizeof(float));
    return image;
  }

  int ValidationMessages() const override { return ctx_->validation_messages(); }
  std::string Describe() const override {
    return std::string("vulkan (") + ctx_->device_name() + (ctx_->validation_enabled() ? ", validation on" : "") + ")";
  }

 private:
  // The LUTs interpolated (in double, by the shared model's own hook) to this frame's sun
  // row position: one vec4 per table and column. Tables the variant does not use stay 0.
  void FillLutSlice(const Preset& preset, const SkyParamsD& params, float* dst) {
    const CpuLutSource source{&preset.luts};
    CpuSkyModel m(source);
    const auto lr = m.lut_row(params.sun_dir.y, params);
    const int columns = preset.luts.grid.n_gamma;
    const int tables = preset.variant == ModelVariant::kFfxvIso ? 3 : 2;
    for (int t = 0; t < 3; ++t) {
      for (int c = 0; c < columns; ++c) {
        float* v = dst + 4 * (t * columns + c);
        const auto texel = t < tables ? m.lut_column_texel(t, lr.row0, lr.frow, c) : glsl::Vec3<double>(0.0);
        v[0] = static_cast<float>(texel.x);
        v[1] = static_cast<float>(texel.y);
        v[2] = static_cast<float>(texel.z);
        v[3] = 0.0f;
      }
    }
  }

  // Per-row (sin, cos) of latitude then per-column (sin, cos) of longitude, in double
  // through the shared model's angle functions, rounded once to float.
  void FillTrigTable(const Preset& preset, int width, int height) {
    const CpuLutSource source{&preset.luts};
    CpuSkyModel m(source);
    float* t = static_cast<float*>(trig_.mapped);
    for (int y = 0; y < height; ++y) {
      const double lat = m.latlong_latitude(y, height);
      t[2 * y] = static_cast<float>(std::sin(lat));
      t[2 * y + 1] = static_cast<float>(std::cos(lat));
    }
    for (int x = 0; x < width; ++x) {
      const double lon = m.latlong_longitude(x, width);
      t[2 * (height + x)] = static_cast<float>(std::sin(lon));
      t[2 * (height + x) + 1] = static_cast<float>(std::cos(lon));
    }
    ctx_->FlushForDevice(trig_);
    trig_width_ = width;
    trig_height_ = height;
  }

  // (Re)creates `b` when it is smaller than `size`; returns true if it changed.
  bool Ensure(MappedBuffer& b, VkDeviceSize size, VkBufferUsageFlags usage, bool cached) {
    if (b.buffer && b.size >= size) return false;
    if (b.buffer) {
      vkDeviceWaitIdle(ctx_->device());
      ctx_->DestroyBuffer(b);
    }
    b = ctx_->CreateMappedBuffer(size, usage, cached);
    return true;
  }

  void CreatePipeline() {
    VkDevice d = ctx_->device();
    VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = spirv::sky_latlong_size;
    smci.pCode = spirv::sky_latlong;
    CheckVk(vkCreateShaderModule(d, &smci, nullptr, &shader_), "vkCreateShaderModule");

    VkDescriptorSetLayoutBinding bindings[kBindings] = {};
    for (uint32_t i = 0; i < kBindings; ++i) {
      bindings[i].binding = i;
      bindings[i].descriptorType = kBindingTypes[i];
      bindings[i].descriptorCount = 1;
      bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo dslci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dslci.bindingCount = kBindings;
    dslci.pBindings = bindings;
    CheckVk(vkCreateDescriptorSetLayout(d, &dslci, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");

    VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    plci.setLayoutCount = 1;
    plci.pSetLayouts = &set_layout_;
    CheckVk(vkCreatePipelineLayout(d, &plci, nullptr, &pipeline_layout_), "vkCreatePipelineLayout");

    VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = shader_;
    cpci.stage.pName = "main";
    const uint32_t local_size[2] = {kLocalX, kLocalY};
    const VkSpecializationMapEntry entries[2] = {{0, 0, sizeof(uint32_t)}, {1, sizeof(uint32_t), sizeof(uint32_t)}};
    VkSpecializationInfo spec{2, entries, sizeof(local_size), local_size};
    cpci.stage.pSpecializationInfo = &spec;
    cpci.layout = pipeline_layout_;
    CheckVk(vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipeline_), "vkCreateComputePipelines");

    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kBindings - 2}};
    VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dpci.maxSets = 1;
    dpci.poolSizeCount = 2;
    dpci.pPoolSizes = sizes;
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
  }

  void WriteDescriptors() {
    VkDescriptorBufferInfo infos[kBindings] = {{uniforms_.buffer, 0, VK_WHOLE_SIZE},
                                               {luts_.buffer, 0, VK_WHOLE_SIZE},
                                               {output_.buffer, 0, VK_WHOLE_SIZE},
                                               {trig_.buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet writes[kBindings] = {};
    for (uint32_t i = 0; i < kBindings; ++i) {
      writes[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
      writes[i].dstSet = set_;
      writes[i].dstBinding = i;
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = kBindingTypes[i];
      writes[i].pBufferInfo = &infos[i];
    }
    vkUpdateDescriptorSets(ctx_->device(), kBindings, writes, 0, nullptr);
  }

  void Record(int width, int height) {
    CheckVk(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    CheckVk(vkBeginCommandBuffer(cmd_, &bi), "vkBeginCommandBuffer");
    vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout_, 0, 1, &set_, 0, nullptr);
    static_assert(kLocalY == 1, "sky_latlong.comp renders one row per workgroup");
    vkCmdDispatch(cmd_, (width + kLocalX - 1) / kLocalX, height, 1);
    // Make the shader's writes visible to the host once the fence signals.
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    CheckVk(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
  }

  std::shared_ptr<VulkanContext> ctx_;
  VkShaderModule shader_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout pipeline_layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptor_pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  MappedBuffer uniforms_, luts_, output_, trig_;
  int trig_width_ = 0, trig_height_ = 0;  // size the trig table was filled for
};

}  // namespace

std::unique_ptr<SkyRenderer> CreateRenderer(Backend backend, const VulkanOptions& vk) {
  if (backend == Backend::kCpu) return CreateCpuRenderer();
  return std::make_unique<VulkanSkyRenderer>(VulkanContext::Create(vk.validation));
}

}  // namespace skycal::render
