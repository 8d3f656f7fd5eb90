// The cloud march's device made ready on a second thread while calibrate reads and analyses
// the photo (import, segmentation, the sun, the cloud probability: one core's work on a
// machine of two or more): the Vulkan device, the march's pipeline (compiled by the driver on
// lavapipe), the noise (read from its cache, or made) and its upload, which the cloud
// statistics' first render would otherwise wait for. The device is kept by the caller's
// clouds::KeepCloudDevices; Join() before anything else renders.
#pragma once
#include <thread>

#include "skycal/render/renderer.h"

namespace skycal::controllers {

class CloudDeviceWarmup {
 public:
  // Starts nothing unless `backend` is Vulkan. A failure (no device) is silent here: the fit
  // that needs the device meets it and reports it.
  explicit CloudDeviceWarmup(render::Backend backend);
  ~CloudDeviceWarmup() { Join(); }
  CloudDeviceWarmup(const CloudDeviceWarmup&) = delete;
  CloudDeviceWarmup& operator=(const CloudDeviceWarmup&) = delete;
  void Join() {
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::thread thread_;
};

}  // namespace skycal::controllers
