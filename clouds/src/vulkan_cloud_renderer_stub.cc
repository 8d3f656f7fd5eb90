// Placeholder until the gpu module (gpu::ComputePipeline) lands: the Vulkan cloud renderer
// is built on it (vulkan_cloud_renderer.cc).
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/error.h"

namespace skycal::clouds {
std::unique_ptr<CloudRenderer> CreateVulkanCloudRenderer(bool) {
  throw Error("clouds: the Vulkan cloud renderer is not built yet (use --backend cpu)");
}
}  // namespace skycal::clouds
