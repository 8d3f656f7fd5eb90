// What a renderer's device work cost and what it moved to the device, without vulkan.h
// (render/renderer_stats.h and clouds/cloud_renderer_stats.h return it; bench's timing
// reads the process-wide totals). Filled by gpu::ComputePipeline.
//
// Device time is measured with timestamp queries around each submitted command buffer
// (vkCmdWriteTimestamp; ticks x VkPhysicalDeviceLimits::timestampPeriod ns, masked to the
// queue family's timestampValidBits). It is the device's time for the pass (uploads,
// dispatch, readback copy), not the host's wait: wall time stays the headline number.
#pragma once
#include <atomic>
#include <optional>

namespace skycal {

struct DeviceStats {
  // The last render's device time, ms; nullopt for a CPU backend, before the first render,
  // or on a device whose queue reports no timestamp support (timestampValidBits 0).
  std::optional<double> gpu_ms;
  // Host writes of resources (textures, LUTs, direction tables; not the per-render
  // parameters) since the renderer was made: one per binding and change of content.
  long long resource_uploads = 0;
  long long resource_upload_bytes = 0;
  // Resources in device-local memory filled through staging buffers (discrete GPUs, or
  // forced by SKYCAL_VULKAN_MEMORY=staged); false: host-visible memory read in place.
  bool staged = false;
  // The cloud textures sampled as images through the hardware's filter (clouds'
  // SKYCAL_VULKAN_TEXTURES); false: texel buffers filtered by the shared source.
  bool sampled_images = false;
};

// Process-wide sums over every timed submission (for benchmarks: the device time of a
// measured call is the difference of two readings).
struct DeviceTimeTotals {
  double gpu_ms = 0.0;             // summed device time of timed submissions
  long long timed_submits = 0;     // submissions with a device time
  long long untimed_submits = 0;   // submissions on a queue without timestamps
};

namespace detail {
inline std::atomic<long long> device_time_ns{0};
inline std::atomic<long long> timed_submits{0};
inline std::atomic<long long> untimed_submits{0};
}  // namespace detail

inline DeviceTimeTotals DeviceTimeSoFar() {
  return {static_cast<double>(detail::device_time_ns.load()) * 1e-6, detail::timed_submits.load(),
          detail::untimed_submits.load()};
}

// Called by gpu::ComputePipeline after each submission (nullopt: untimed).
inline void AddDeviceTime(std::optional<double> ms) {
  if (ms) {
    detail::device_time_ns += static_cast<long long>(*ms * 1e6);
    ++detail::timed_submits;
  } else {
    ++detail::untimed_submits;
  }
}

}  // namespace skycal
