// A cloud renderer's device statistics (core/device_stats.h): the last render's device
// time by timestamp queries, the texture uploads so far, staged or direct memory. Apart from
// cloud_renderer.h so that its users do not depend on it.
#pragma once
#include <string>

#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/device_stats.h"

namespace skycal::clouds {

// Empty (no device time, no uploads) for the CPU backends.
DeviceStats RendererDeviceStats(const CloudRenderer& renderer);

// SKYCAL_VULKAN_TEXTURES (unset or empty: kAuto); throws skycal::Error naming the variable
// and its value unless it is auto, buffers or images.
CloudTextures CloudTexturesFromEnvironment();

struct CloudTextureChoice {
  bool images = false;
  std::string note;  // why images were asked for and not used (empty otherwise)
};
// kAuto: images on a device with device-only memory (a discrete GPU, whose texture units
// and caches are built for this read) and texel buffers elsewhere (lavapipe, where the
// shared source's filter measured faster: docs/cloud-model.md). Images requested (or chosen)
// on a device that cannot sample them (`images_unsupported` says why; empty: it can):
// texel buffers, and `note` says so.
CloudTextureChoice ChooseCloudTextures(CloudTextures requested, bool discrete_gpu, const std::string& images_unsupported);

}  // namespace skycal::clouds
