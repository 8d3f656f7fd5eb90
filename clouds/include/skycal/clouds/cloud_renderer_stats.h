// A cloud renderer's device statistics (core/device_stats.h): the last render's device
// time by timestamp queries, the texture uploads so far, staged or direct memory. Apart from
// cloud_renderer.h so that its users do not depend on it.
#pragma once
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/device_stats.h"

namespace skycal::clouds {

// Empty (no device time, no uploads) for the CPU backends.
DeviceStats RendererDeviceStats(const CloudRenderer& renderer);

}  // namespace skycal::clouds
