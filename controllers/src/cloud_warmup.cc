#include "cloud_warmup.h"

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
      const render::Preset preset = render::LoadPreset(DefaultCloudyPresetPath());
      const clouds::CloudParams params = clouds::ParseCloudSectionText(preset.clouds_json, DefaultCloudyPresetPath());
      const auto noise = clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
      const clouds::WeatherMap weather = clouds::UniformWeatherMap(0.5, 0.0, 0.5, params.weather_extent_m);
      clouds::CloudRenderRequest request = OpacityRequest(8, 4);
      OpacityRenderer(render::Backend::kVulkan)->Render({&preset, &params, noise.get(), &weather}, request);
    } catch (...) {  // NOLINT(bugprone-empty-catch): reported by the fit that needs the device
    }
  });
}

}  // namespace skycal::controllers
