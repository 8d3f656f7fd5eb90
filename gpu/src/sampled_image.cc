#include "skycal/gpu/sampled_image.h"

#include <string>

#include "skycal/core/error.h"

namespace skycal::gpu {

std::string SampledImage::Unsupported(const VulkanContext& ctx, const ImageExtent& extent) {
  VkFormatProperties fp;
  vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), kFormat, &fp);
  const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT |
                                    VK_FORMAT_FEATURE_TRANSFER_DST_BIT;
  if ((fp.optimalTilingFeatures & need) != need) {
    return "the device cannot sample RGBA32F images with linear filtering (optional in Vulkan)";
  }
  VkImageFormatProperties ip;
  const VkImageType type = extent.depth > 1 ? VK_IMAGE_TYPE_3D : VK_IMAGE_TYPE_2D;
  const VkResult r = vkGetPhysicalDeviceImageFormatProperties(
      ctx.physical_device(), kFormat, type, VK_IMAGE_TILING_OPTIMAL,
      VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, 0, &ip);
  const std::string shape = std::to_string(extent.width) + "x" + std::to_string(extent.height) +
                            (extent.depth > 1 ? "x" + std::to_string(extent.depth) : std::string());
  if (r != VK_SUCCESS) return std::string("the device has no ") + (extent.depth > 1 ? "3D" : "2D") + " RGBA32F sampled images";
  if (extent.width > ip.maxExtent.width || extent.height > ip.maxExtent.height || extent.depth > ip.maxExtent.depth) {
    return "a " + shape + " image exceeds the device's largest (" + std::to_string(ip.maxExtent.width) + "x" +
           std::to_string(ip.maxExtent.height) + "x" + std::to_string(ip.maxExtent.depth) + ")";
  }
  return {};
}

SampledImage::SampledImage(VulkanContext& ctx, const ImageExtent& extent) : ctx_(ctx), extent_(extent) {
  const VkDevice d = ctx_.device();
  try {
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = extent.depth > 1 ? VK_IMAGE_TYPE_3D : VK_IMAGE_TYPE_2D;
    ici.format = kFormat;
    ici.extent = {extent.width, extent.height, extent.depth};
    ici.mipLevels = 1;
    ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    ici.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    CheckVk(vkCreateImage(d, &ici, nullptr, &image_), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(d, image_, &req);
    const int type = ctx_.DeviceLocalMemoryType(req.memoryTypeBits);
    if (type < 0) throw Error("Vulkan: no memory type for a sampled image");
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = static_cast<uint32_t>(type);
    CheckVk(vkAllocateMemory(d, &mai, nullptr, &memory_), "vkAllocateMemory (image)");
    CheckVk(vkBindImageMemory(d, image_, memory_, 0), "vkBindImageMemory");
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image_;
    vci.viewType = extent.depth > 1 ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D;
    vci.format = kFormat;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    CheckVk(vkCreateImageView(d, &vci, nullptr, &view_), "vkCreateImageView");
    staging_ = ctx_.CreateMappedBuffer(bytes(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, /*prefer_cached=*/false);
  } catch (...) {
    Release();
    throw;
  }
}

SampledImage::~SampledImage() { Release(); }

void SampledImage::Release() {
  const VkDevice d = ctx_.device();
  ctx_.DestroyBuffer(staging_);
  if (view_) vkDestroyImageView(d, view_, nullptr);
  if (image_) vkDestroyImage(d, image_, nullptr);
  if (memory_) vkFreeMemory(d, memory_, nullptr);
  view_ = VK_NULL_HANDLE;
  image_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
}

void SampledImage::Flush() {
  ctx_.FlushForDevice(staging_);
  dirty_ = true;
}

namespace {

void Transition(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags src_access,
                VkAccessFlags dst_access, VkPipelineStageFlags src_stage, VkPipelineStageFlags dst_stage) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = src_access;
  b.dstAccessMask = dst_access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

}  // namespace

void SampledImage::RecordUpload(VkCommandBuffer cmd) {
  // The whole image is rewritten: its old contents are discarded (UNDEFINED), after the
  // previous submission's shader reads of it.
  Transition(cmd, image_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
             written_ ? VK_ACCESS_SHADER_READ_BIT : 0, VK_ACCESS_TRANSFER_WRITE_BIT,
             written_ ? VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT : VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
             VK_PIPELINE_STAGE_TRANSFER_BIT);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {extent_.width, extent_.height, extent_.depth};
  vkCmdCopyBufferToImage(cmd, staging_.buffer, image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  Transition(cmd, image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
             VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  dirty_ = false;
  written_ = true;
}

VkSampler CreateLinearRepeatSampler(VkDevice device) {
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = VK_FILTER_LINEAR;
  sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.addressModeV = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.minLod = 0.0f;
  sci.maxLod = 0.0f;
  sci.unnormalizedCoordinates = VK_FALSE;
  VkSampler sampler = VK_NULL_HANDLE;
  CheckVk(vkCreateSampler(device, &sci, nullptr, &sampler), "vkCreateSampler");
  return sampler;
}

}  // namespace skycal::gpu
