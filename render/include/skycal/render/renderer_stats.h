// A sky renderer's device statistics (core/device_stats.h): the last render's device time
// by timestamp queries, the resource uploads so far, staged or direct memory. A separate
// header from renderer.h so that the many users of renderer.h do not depend on it.
#pragma once
#include "skycal/core/device_stats.h"
#include "skycal/render/renderer.h"

namespace skycal::render {

// Empty (no device time, no uploads) for the CPU backend.
DeviceStats RendererDeviceStats(const SkyRenderer& renderer);

}  // namespace skycal::render
