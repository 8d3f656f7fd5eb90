#include "cloud_warmup.h"

#include <future>
#include <memory>

#include "calibrate_weather.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/game_clouds.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {

CloudDeviceWarmup::CloudDeviceWarmup(render::Backend backend) {
  if (backend != render::Backend::kVulkan) return;
  thread_ = std::thread([] {
    try {  // a tiny march of the bundled cloudy preset with the noise every render uses
      // The noise (a 34 MB file read and hashed) on a thread of its own while the device is
      // made and the march compiled: the two meet only at the render. (A failure to make the
      // device waits for the read: the future's destructor joins it.)
      auto noise = std::async(std::launch::async,
                              [] { return clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir()); });
      const std::unique_ptr<clouds::CloudRenderer> renderer = OpacityRenderer(render::Backend::kVulkan);
      const render::Preset preset = render::LoadPreset(DefaultCloudyPresetPath());
      const clouds::CloudParams params = clouds::ParseCloudSectionText(preset.clouds_json, DefaultCloudyPresetPath());
      const clouds::WeatherMap weather = clouds::UniformWeatherMap(0.5, 0.0, 0.5, params.weather_extent_m);
      clouds::CloudRenderRequest request = OpacityRequest(8, 4);
      renderer->Render({&preset, &params, noise.get().get(), &weather}, request);
    } catch (...) {  // NOLINT(bugprone-empty-catch): reported by the fit that needs the device
    }
  });
}

}  // namespace skycal::controllers
